"""Whether the command being followed is still safe (:func:`in_danger`), and the exact check of a slow move off
the dynamic window (the navigator's recovery and escape,
``closed_loop.control.navigator``, ``closed_loop.control.escape``): against the current scan, and against what
the robot remembers where the scan cannot see. Free of ROS.
"""
import math

import numpy

from closed_loop.control.guard import footprint_clearance, footprint_clearances, path_clearance, point_clearances
from closed_loop.control.local_planner import PREDICTION_STEP_S, predict, required_margin
from closed_loop.control.scan_memory import BLIND_EXTRA_M, blind_mask

#: A move keeps BLIND_EXTRA_M (``scan_memory``'s), and BLIND_DRIFT_MPS for each second since it was seen,
#: beyond the margin from a point remembered where the scan cannot see: among posts a Jackal's odometry drifted
#: about 5 mm a second (0.37 m in 80 s of a BARN run, turning in pockets).
BLIND_DRIFT_MPS = 0.005
#: Within the margin of what the scan shows, a move is allowed if it brings no point closer than this
#: (m, the rounding of the exact clearance).
NOT_CLOSER_M = 1e-3


class MoveCheck:
    """Is a move (v, w) from the speeds now safe? It keeps the margin from what the scan shows, and the margin
    and each point's doubt from what is remembered where the scan cannot see; where the robot already stands
    closer than that to either, a move that brings nothing closer (of the scan's points; of the remembered ones,
    counting the doubt). ``scanned``: the scan's points (the robot's frame); ``remembered``: the memory's (the
    robot's frame) and ``seen_s`` when each was seen.

    The rule is the same for both: a doubt grows while the robot stays in a pocket, and would otherwise come to
    forbid every move, even one straight away from the point (docs/benchmarks.md, "Moves that bring nothing
    closer")."""

    def __init__(self, settings, footprint, v0, w0, scan, laser_pose, scanned, remembered, seen_s, now_s):
        self.settings, self.footprint, self.v0, self.w0 = settings, footprint, v0, w0
        self.scanned = scanned
        blind = blind_mask(remembered, scan, laser_pose)
        # Where the scan cannot see, what is remembered is only as right as odometry since it was seen.
        self.blind = remembered[blind]
        self.doubt = BLIND_EXTRA_M + BLIND_DRIFT_MPS * (now_s - seen_s[blind])
        self.now_clear = footprint_clearance(scanned, footprint, 0.0, 0.0, 0.0)
        self.now_blind = self._blind_clearance(numpy.zeros((1, 3)))

    def _blind_clearance(self, poses):
        """The least clearance (m) over ``poses`` from what is remembered where the scan cannot see, less each
        point's doubt; +inf where nothing is."""
        if not len(self.blind):
            return math.inf
        return float((point_clearances(self.blind, self.footprint, poses) - self.doubt).min())

    def safe(self, v, w, seconds, speed=None):
        """True if (v, w) followed for ``seconds`` and then braked keeps the margin for ``speed`` (default
        ``v``) as above."""
        s = self.settings
        poses = predict(self.v0, self.w0, numpy.array([v]), numpy.array([w]), s, seconds,
                        int(math.ceil((seconds + 1.0) / PREDICTION_STEP_S)))[0]
        margin = required_margin(s, v if speed is None else speed)
        clearance = path_clearance(self.scanned, self.footprint, poses)
        if not (clearance >= margin or clearance >= self.now_clear - NOT_CLOSER_M):
            return False
        blind = self._blind_clearance(poses)
        return blind >= margin or blind >= self.now_blind - NOT_CLOSER_M


def in_danger(sent, scan_points_xy, settings, footprint):
    """True if the command being followed (``sent``, m/s and rad/s) is no longer safe: its predicted path
    comes within ``safety_margin`` of the scan's points (robot frame). The node acts at once on such a
    scan rather than at its next tick."""
    v, w = sent
    if v == 0.0 and w == 0.0 or not len(scan_points_xy):
        return False
    s = settings
    steps = int(math.ceil((s.horizon + abs(v) / s.accel + abs(w) / s.yaw_accel) / PREDICTION_STEP_S)) + 1
    poses = predict(v, w, [v], [w], s, s.horizon, steps)[0]
    # Only a point within the margin of the swept footprint counts: none farther from the robot than the
    # farthest pose, the footprint's corner and the margin.
    margin = required_margin(s, v)
    reach = float(numpy.hypot(poses[:, 0], poses[:, 1]).max()) + footprint.radius_m + margin
    near = scan_points_xy[numpy.hypot(scan_points_xy[:, 0], scan_points_xy[:, 1]) <= reach]
    return bool(len(near)) and float(footprint_clearances(near, footprint, poses).min()) < margin
