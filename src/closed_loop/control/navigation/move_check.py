"""Whether the command being followed is still safe (:func:`in_danger`), and the exact check of a move off the
dynamic window (the navigator's final approach, recovery and escape, ``closed_loop.control.navigation.navigator``,
``closed_loop.control.navigation.escape``): ``closed_loop.control.safety``'s rule against the current scan, and against
what the robot remembers where the scan cannot see. Free of ROS.
"""
import numpy

from closed_loop.control.navigation.situation import PREDICTION_STEP_S, predict, required_margin
from closed_loop.control.safety import keeps_room, steps_to_rest
from closed_loop.control.navigation.memory import BLIND_EXTRA_M, blind_mask

#: A move keeps BLIND_EXTRA_M (``memory``'s), and BLIND_DRIFT_MPS for each second since it was seen,
#: beyond the margin from a point remembered where the scan cannot see: odometry drifts while a skid-steer
#: base turns in pockets (docs/benchmarks.md has the drift measured among posts).
BLIND_DRIFT_MPS = 0.005


class MoveCheck:
    """Is a move (v, w) from the speeds now safe? ``closed_loop.control.safety``'s rule, for the scan's points
    (``scanned``, the robot's frame) and for what is remembered where the scan cannot see (``remembered``, the
    robot's frame, and ``seen_s`` when each was seen), each of those less its doubt: BLIND_EXTRA_M, and
    BLIND_DRIFT_MPS for each second since it was seen.

    Point by point, a doubt that grows while the robot stays in a pocket never comes to forbid a move straight
    away from the point (docs/benchmarks.md, "Moves that bring nothing closer")."""

    def __init__(self, settings, footprint, v0, w0, scan, laser_pose, scanned, remembered, seen_s, now_s):
        self.settings, self.footprint, self.v0, self.w0 = settings, footprint, v0, w0
        blind = blind_mask(remembered, scan, laser_pose)
        # Where the scan cannot see, what is remembered is only as right as odometry since it was seen.
        self.blind = remembered[blind]
        self.doubt = BLIND_EXTRA_M + BLIND_DRIFT_MPS * (now_s - seen_s[blind])
        self.points = numpy.concatenate((scanned, self.blind)) if len(self.blind) else scanned
        self._doubts = numpy.concatenate((numpy.zeros(len(scanned)), self.doubt))

    def safe(self, v, w, seconds, speed=None):
        """True if (v, w) followed for ``seconds`` and then braked keeps the margin for ``speed`` (default
        ``v``; ``situation.required_margin``) by the rule."""
        s = self.settings
        steps = steps_to_rest(self.v0, self.w0, v, w, s.accel, s.yaw_accel, seconds, PREDICTION_STEP_S)
        poses = predict(self.v0, self.w0, numpy.array([v]), numpy.array([w]), s, seconds, steps)[0]
        return keeps_room(self.points, self.footprint, poses, required_margin(s, v if speed is None else speed),
                          self._doubts)[0]


def in_danger(sent, scan_points_xy, settings, footprint):
    """True if the command being followed (``sent``, m/s and rad/s) is no longer safe by the rule
    (``closed_loop.control.safety``) against the scan's points (robot frame): its predicted path comes within
    the margin of one, or closer to one already within it. The node acts at once on such a scan rather than at
    its next tick."""
    v, w = sent
    if v == 0.0 and w == 0.0 or not len(scan_points_xy):
        return False
    s = settings
    poses = predict(v, w, [v], [w], s, s.horizon, steps_to_rest(v, w, v, w, s.accel, s.yaw_accel, s.horizon,
                                                                PREDICTION_STEP_S))[0]
    return not keeps_room(scan_points_xy, footprint, poses, required_margin(s, v))[0]
