"""The one motion predictor's loop, compiled (numba), for ``closed_loop.control.safety.predict``: each candidate's
speeds ramped toward it at the accelerations for the horizon, then to zero at the same rates, and the poses
they reach, integrated step by step: one call for every candidate, with the arithmetic of the array form in
the same order (sums taken one step after another, as numpy's cumulative sum takes them), so the poses are
the same to the bit.

Compiled by numba (``closed_loop.compiled``). Free of ROS.
"""
import math

import numpy

from closed_loop.compiled import jit


@jit
def _speed(start, change, rate, t, horizon_s, within):
    """The speed at time ``t`` of a ramp from ``start`` toward ``start + change`` at ``rate``: within the
    horizon, toward it; after, from where it was at the horizon toward zero."""
    if within:
        return start + min(max(change, -rate * t), rate * t)
    at_end = start + min(max(change, -rate * horizon_s), rate * horizon_s)
    sign = 1.0 if at_end > 0.0 else (-1.0 if at_end < 0.0 else 0.0)
    return sign * max(abs(at_end) - rate * (t - horizon_s), 0.0)


@jit
def predict(v0, w0, v, w, accel, yaw_accel, horizon_s, steps, step_s):
    """Poses (C, K, 3) float32, (x, y, yaw) from the robot, for candidates ``v``, ``w`` (C,) from speeds (v0,
    w0); K = ``steps`` poses ``step_s`` apart, each step at the speeds reached at its end."""
    count = len(v)
    out = numpy.empty((count, steps, 3), numpy.float32)
    for c in range(count):
        dv, dw = v[c] - v0, w[c] - w0
        x = y = yaw = 0.0
        for k in range(steps):
            t = (k + 1) * step_s
            within = t <= horizon_s + 1e-9
            speed = _speed(v0, dv, accel, t, horizon_s, within)
            turn = _speed(w0, dw, yaw_accel, t, horizon_s, within)
            turned = turn * step_s
            yaw = turned if k == 0 else yaw + turned
            mid = yaw - 0.5 * turn * step_s
            ahead_x, ahead_y = speed * math.cos(mid) * step_s, speed * math.sin(mid) * step_s
            x = ahead_x if k == 0 else x + ahead_x
            y = ahead_y if k == 0 else y + ahead_y
            out[c, k, 0], out[c, k, 1], out[c, k, 2] = x, y, yaw
    return out


@jit
def least_on_outline(field, size, poses, cos_yaw, sin_yaw, outline_x, outline_y, scale, offset):
    """(C, K) float32: the least of ``field`` (a distance field's cells, flat, ``size`` a row) over the
    outline's points (``outline_x``, ``outline_y``, in cells) at each of ``poses`` (C, K, 3) float32, its
    yaw's cosine and sine given (C, K); each point's cell from its place (m) times ``scale`` plus ``offset``,
    in float32, cut to whole cells; an index beyond the field clipped to its ends (numpy's ``take`` with
    ``mode='clip'``)."""
    rows, steps = cos_yaw.shape
    out = numpy.empty((rows, steps), numpy.float32)
    last = len(field) - 1
    width = numpy.int32(size)
    for c in range(rows):
        for k in range(steps):
            base_x = poses[c, k, 0] * scale + offset
            base_y = poses[c, k, 1] * scale + offset
            cs, sn = cos_yaw[c, k], sin_yaw[c, k]
            least = numpy.float32(numpy.inf)
            for m in range(len(outline_x)):
                ix = base_x + cs * outline_x[m] - sn * outline_y[m]
                iy = base_y + sn * outline_x[m] + cs * outline_y[m]
                index = numpy.int32(iy) * width + numpy.int32(ix)
                value = field[min(max(index, 0), last)]
                if value < least:
                    least = value
            out[c, k] = least
    return out
