"""A safety filter any controller can sit behind: veto or slow commands that would hit what the LIDAR sees.

Given the latest scan (as points in base_footprint), the robot's footprint rectangle (from the URDF),
its current velocity and a commanded velocity, :func:`filter_command` predicts the path the base would
take if it followed the command for ``reaction_time`` and then braked at ``braking_decel`` (linear)
and ``angular_decel`` (yaw), and measures the footprint's clearance to every scan point along that path:
the package's one predictor and one rule (``closed_loop.control.safety``), the navigator's too. The command
passes if the clearance stays at least ``safety_margin``; when the robot is already closer than that to some
points, if none of those comes closer and none of the others comes within the margin (point by point).
Otherwise the command is scaled down, keeping its curvature,
to the largest safe fraction; where none is safe the answer is zero (brake). This is the scheme of the
ecosystem's safety limiters: predict, then limit; it knows nothing of the controller in front of it.

Free of ROS: scans are :class:`closed_loop.control.scan.Scan`, poses and speeds plain numbers (REP 103 units).
"""
import dataclasses
import enum

import numpy

from closed_loop import robot_model
from closed_loop.control import safety
from closed_loop.control.decisions import input_problem
from closed_loop.control.scan import nearest
from closed_loop.settings import MIN_RATE_HZ, SettingsError, param

#: Fractions of a command tried, largest first, when the whole command is not safe.
SCALES = (1.0, 0.8, 0.6, 0.45, 0.3, 0.2, 0.12, 0.06, 0.0)
#: Prediction time step (s). At 1.5 m/s the robot moves 3 cm per step; the clearance between steps is
#: covered by ``safety_margin``, which must exceed half of that.
PREDICTION_STEP_S = 0.02


class GuardVerdict(enum.IntEnum):
    """What the guard did to a command; a larger value is more restrictive."""
    PASS = 0
    SLOWED = 1
    VETOED = 2


@dataclasses.dataclass
class GuardSettings:
    """cmd_vel_guard's ``~parameters``."""
    safety_margin: float = param(0.10, 'm', 'least clearance kept between the footprint and any scan point '
                                 'along the predicted path', minimum=0.04, maximum=2.0, live=True)
    reaction_time: float = param(0.25, 's', 'how long a command is assumed followed before braking starts '
                                 '(scan age, delivery and the next command)', minimum=0.0, maximum=2.0, live=True)
    braking_decel: float = param(2.0, 'm/s^2', "deceleration the base is counted on to brake at (at most "
                                 "the base's own limit)", minimum=0.1, maximum=20.0, live=True)
    angular_decel: float = param(6.0, 'rad/s^2', 'yaw deceleration the base is counted on', minimum=0.1,
                                 maximum=60.0, live=True)
    rate_hz: float = param(20.0, 'Hz', 'watchdog rate: how often stale input is checked (wall clock)',
                           minimum=MIN_RATE_HZ)
    scan_timeout: float = param(0.5, 's', 'a scan older than this (or none) vetoes every motion',
                                minimum=0.0, maximum=5.0, exclusive_minimum=True)
    cmd_timeout: float = param(0.5, 's', 'an input command older than this is replaced by zero',
                               minimum=0.0, maximum=5.0, exclusive_minimum=True)
    scan_frame: str = param(robot_model.SCAN_FRAME, '', "the laser's frame_id; scans in another frame "
                            'are refused (zero)')

    def check_together(self):
        if not self.safety_margin > 0.5 * 1.5 * PREDICTION_STEP_S:
            raise SettingsError('~safety_margin: expected more than the path between two prediction steps')


@dataclasses.dataclass(frozen=True)
class GuardResult:
    """The command to send (m/s, rad/s), what was done to it, and why."""
    linear_x: float
    angular_z: float
    verdict: GuardVerdict
    reason: str
    clearance_m: float  # least clearance along the chosen command's predicted path (inf: nothing seen)


def scan_problem(scan, age_s, scan_timeout_s):
    """Why the scan cannot be trusted for guarding (missing, stale, or no valid ray), or None."""
    return input_problem(None if scan is None else nearest(scan), age_s, scan_timeout_s)


def predicted_poses(v0, w0, v_cmd, w_cmd, settings):
    """Poses (x, y, yaw) from the origin, the origin first: follow (v_cmd, w_cmd) for reaction_time, then brake
    to rest (``safety.predict``, at the braking rates; the same rates are assumed for speeding up)."""
    steps = safety.steps_to_rest(v0, w0, v_cmd, w_cmd, settings.braking_decel, settings.angular_decel,
                                 settings.reaction_time, PREDICTION_STEP_S)
    poses = safety.predict(v0, w0, [v_cmd], [w_cmd], settings.braking_decel, settings.angular_decel,
                           settings.reaction_time, steps, PREDICTION_STEP_S)[0]
    return numpy.concatenate((numpy.zeros((1, 3)), poses))


def filter_command(points, footprint, v0, w0, v_cmd, w_cmd, settings):
    """The largest safe fraction of the command (:class:`GuardResult`).

    ``points``: scan points in base_footprint (:func:`scan_points`); ``v0``, ``w0``: the robot's current
    speeds (m/s, rad/s); ``v_cmd``, ``w_cmd``: the command.
    """
    now = safety.footprint_clearance(points, footprint, 0.0, 0.0, 0.0)
    if v_cmd == 0.0 and w_cmd == 0.0:
        return GuardResult(0.0, 0.0, GuardVerdict.PASS, 'zero command', now)
    full = None
    for scale in SCALES[:-1]:
        v, w = scale * v_cmd, scale * w_cmd
        safe, clearance = safety.keeps_room(points, footprint, predicted_poses(v0, w0, v, w, settings),
                                            settings.safety_margin)
        full = clearance if full is None else full
        if safe:
            if scale == 1.0:
                return GuardResult(v, w, GuardVerdict.PASS, 'clear: %.2f m or more on the predicted path'
                                   % min(clearance, 99.0), clearance)
            return GuardResult(v, w, GuardVerdict.SLOWED, 'slowed to %d%%: the full command (%.2f m/s, %.2f rad/s) '
                               'would come within %.2f m of an obstacle (safety_margin %.2f m)'
                               % (round(100 * scale), v_cmd, w_cmd, full, settings.safety_margin), clearance)
    braking = safety.path_clearance(points, footprint, predicted_poses(v0, w0, 0.0, 0.0, settings))
    return GuardResult(0.0, 0.0, GuardVerdict.VETOED, 'vetoed (%.2f m/s, %.2f rad/s): even %d%% of it would come '
                       'within %.2f m of an obstacle (safety_margin %.2f m)'
                       % (v_cmd, w_cmd, round(100 * SCALES[-2]), full, settings.safety_margin), braking)
