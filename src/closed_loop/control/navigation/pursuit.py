"""Following the way round where the window would stand or turn in place (``window.plan``'s ``follow``):
heading first, then an arc through the way's aim, each move checked by ``closed_loop.control.safety``'s rule.
Free of ROS.
"""
import math

import numpy

from closed_loop.control.navigation.situation import predict, required_margin
from closed_loop.control.safety import keeps_room

#: Following the way where the window would stand: turn in place toward the aim while it lies more than
#: PURSUIT_TURN_RAD to a side (at the first of PURSUIT_TURN_RADPS that keeps the margin), else drive an arc
#: through it at the first of PURSUIT_SPEEDS (x max_speed) that does.
PURSUIT_TURN_RAD = 0.3
PURSUIT_KEEP_RAD = 1.5
PURSUIT_TURN_RADPS = (0.8, 0.4)
PURSUIT_SPEEDS = (0.5, 0.25, 0.125)


def pursue(aim_xy, near, footprint, v0, w0, s, steps, turning=0.0):
    """Toward ``aim_xy`` (the robot's frame) along the way, heading first: a turn in place while it lies more
    than PURSUIT_TURN_RAD to a side, else an arc through it at the fastest of PURSUIT_SPEEDS (x
    ``max_speed``) whose path keeps the margin (``safety.keeps_room``); (v, w, predicted poses, their clearance, why),
    or None when none keeps it. ``turning``: the side (+1 left, -1 right) of a turn in place at the last
    decision, which goes on while the aim lies more than PURSUIT_KEEP_RAD to the other side (an aim that
    swings between ahead and behind from one scan to the next would turn the robot back and forth)."""
    distance, bearing = math.hypot(*aim_xy), math.atan2(aim_xy[1], aim_xy[0])
    if abs(bearing) > PURSUIT_TURN_RAD:
        side = turning if turning and abs(bearing) > PURSUIT_KEEP_RAD else math.copysign(1.0, bearing)
        options = [(0.0, side * min(s.max_yaw_rate, rate)) for rate in PURSUIT_TURN_RADPS]
        why = 'turning in place toward the way round (%.2f rad off)' % bearing
    else:
        curvature = 2.0 * aim_xy[1] / max(distance ** 2, 1e-9)
        options = [(f * s.max_speed, max(-s.max_yaw_rate, min(s.max_yaw_rate, f * s.max_speed * curvature)))
                   for f in PURSUIT_SPEEDS]
        why = 'following the way round %.2f m to its aim' % distance
    for v, w in options:
        poses = predict(v0, w0, numpy.array([v]), numpy.array([w]), s, s.horizon, steps)[0]
        safe, clearance = keeps_room(near, footprint, poses, required_margin(s, max(v, abs(v0))))
        if safe:
            return v, w, poses, clearance, why
    return None
