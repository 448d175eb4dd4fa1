"""What one decision of the navigator knows (:class:`Situation`), and the small rules every stage shares: the
prediction of a move at the settings' accelerations (:func:`predict`), the margin a path keeps at a speed
(:func:`required_margin`), one period's step of a command (:func:`step_toward`), and the check of what it is
given (:func:`check_finite`, :class:`NavigatorError`). Free of ROS.
"""
import dataclasses
import math

import numpy

from closed_loop.control import safety
from closed_loop.control.navigation.memory import blind_points
from closed_loop.control.scan import scan_points

#: Step between predicted poses (s): between two poses an obstacle point cannot slip through more than the
#: margin allows.
PREDICTION_STEP_S = 0.1


class NavigatorError(ValueError):
    """Unusable input to the planner (a bad pose, goal or speed)."""


@dataclasses.dataclass(frozen=True)
class Situation:
    """What one decision knows, in the robot's frame: the newest ``scan`` (a
    :class:`closed_loop.control.scan.Scan`, REP 117) from the laser at ``laser_pose`` (its pose in the base
    frame, :class:`closed_loop.geometry.Pose2D`), the robot's ``footprint`` rectangle, its speeds now (``v0``
    m/s, ``w0`` rad/s), the goal ``goal_xy`` (m); and, where the navigator has them: ``remembered``, (M, 2)
    points of earlier scans (``memory``), used to choose the way around, and for safety only where the
    scanner cannot see now; ``scanned``, the scan's points if already computed; ``previous``, the command sent
    last (m/s, rad/s), which the step is taken from; ``turning``, +1 or -1 while the last decision was a turn
    in place that way (it goes on that way rather than swing back and forth between two ways round), else 0;
    ``corridor``, where the way round may go (``wavefront.aim``'s), None for anywhere; ``closed``, points (M, 2)
    the way keeps off as it does the scan's (places closed to it), never for safety; ``kept_way``, (N, 2) the
    way followed until now (``wavefront.way``'s ``kept``); ``follow``, where the window would stand or turn in
    place, follow the way instead, heading first (the navigator asks it once it has made no progress for a
    while)."""
    scan: object
    laser_pose: object
    footprint: object
    v0: float
    w0: float
    goal_xy: tuple
    remembered: object = None
    scanned: object = None
    previous: tuple = None
    turning: float = 0.0
    corridor: tuple = None
    closed: object = None
    kept_way: object = None
    follow: bool = False

    def points(self):
        """(the scan's points, those remembered where the scanner cannot see, both of them): what every
        command's path keeps the margin from. Where the scanner cannot see (behind a LIDAR of less than a full
        turn), what was seen there before is the best knowledge there is, so a turn does not swing the robot's
        back into something it saw a moment ago."""
        scanned = scan_points(self.scan, self.laser_pose) if self.scanned is None else self.scanned
        remembered = self.remembered
        blind = blind_points(remembered, self.scan, self.laser_pose) if remembered is not None and len(remembered) \
            else scanned[:0]
        return scanned, blind, numpy.concatenate((scanned, blind)) if len(blind) else scanned


def required_margin(settings, speed):
    """The clearance (m) a path driven at ``speed`` (m/s, the faster of the command's and the robot's) must
    keep: ``safety_margin`` at rest, ``margin_per_speed`` more per m/s (a base at speed strays farther
    from the predicted arc: a skid-steer one turns less than its wheels say)."""
    return settings.safety_margin + settings.margin_per_speed * abs(speed)


def check_finite(name, *values):
    for value in values:
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            raise NavigatorError('%s: expected finite numbers, got %r' % (name, values))


def step_toward(target, previous, measured, rate, period_s, limit):
    """One period's step of a speed toward ``target``, at most ``rate`` x ``period_s``, from the command
    sent last (``previous``; None: the ``measured`` speed), and never more than that step above the
    measured speed in magnitude, nor beyond +-``limit``.

    From the measured speed alone, a base that overshoots its command (a skid-steer one, in a turn) would
    be sent ever more of it; the magnitude bound keeps a base held back (stopped by a watchdog) from
    being sent a jump the plan did not predict."""
    step = rate * period_s
    base = measured if previous is None else previous
    value = min(max(target, base - step), base + step)
    reach = min(abs(measured) + step, limit)
    return float(min(max(value, -reach), reach))


def predict(v0, w0, v, w, settings, horizon_s, steps, step_s=PREDICTION_STEP_S):
    """Poses (C, K, 3) float32 for candidates ``v``, ``w`` (C,) from (v0, w0): ``safety.predict`` at the
    settings' accelerations (``accel``, ``yaw_accel``)."""
    return safety.predict(v0, w0, v, w, settings.accel, settings.yaw_accel, horizon_s, steps, step_s)
