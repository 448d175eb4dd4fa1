"""Is this move safe? One rule and one motion predictor, for every part that asks: the navigator's window
(``closed_loop.control.navigation.window``: its exact checks; its fast one reads the same rule off a distance
grid), its final approach, its recovery and escape (``navigation.move_check``), the check of the command being
followed (``move_check.in_danger``), and the guard any controller can sit behind (``closed_loop.control.guard``).

The predictor (:func:`predict`): from the speeds now, each speed ramps toward the move's at the given
accelerations for a horizon (how long the move is followed: a control period, the scan's age, the command's
delivery), then brakes to zero at the same rates; the footprint's poses along it.

The rule (:func:`keeps_room`), point by point, for the points the robot must keep off (a scan's, and what it
remembers where the scan cannot see, each less its doubt): along the predicted poses no point comes within the
margin of the footprint, except one that is already within it, which must come no closer. Judged on the least
clearance alone, a move would pass that creeps toward one obstacle while the nearest is another beside it.

Free of ROS: points, poses and speeds are plain numbers and arrays (REP 103 units, the robot's frame).
"""
import importlib
import math

import numpy

#: Of a point already within the margin, a clearance change smaller than this (m) counts as "not closer" (the
#: rounding of the exact clearance).
CLEARANCE_EPS_M = 1e-3


def predict(v0, w0, v, w, accel, yaw_accel, horizon_s, steps, step_s):
    """Poses (C, K, 3) float32 (x, y, yaw from the robot) of moves ``v``, ``w`` ((C,) m/s, rad/s) from the speeds
    now (``v0``, ``w0``): each speed toward the move's at ``accel`` (m/s^2) and ``yaw_accel`` (rad/s^2) for
    ``horizon_s``, then to zero at the same rates; K = ``steps`` poses ``step_s`` apart (each step at the speeds
    reached at its end: the pose runs slightly ahead). Compiled: ``closed_loop.control.arc_kernel``."""
    return importlib.import_module('closed_loop.control.arc_kernel').predict(
        float(v0), float(w0), numpy.ascontiguousarray(v, float), numpy.ascontiguousarray(w, float),
        float(accel), float(yaw_accel), float(horizon_s), int(steps), float(step_s))


def steps_to_rest(v0, w0, v, w, accel, yaw_accel, horizon_s, step_s):
    """How many steps of ``step_s`` :func:`predict` needs for the move (``v``, ``w``) from (``v0``, ``w0``) to
    come to rest: the horizon, the ramps to the move and from it to zero, and two steps to spare."""
    return int(math.ceil((horizon_s + (abs(v - v0) + abs(v)) / accel + (abs(w - w0) + abs(w)) / yaw_accel)
                         / step_s)) + 2


def footprint_clearances(points, footprint, poses):
    """Least distance (m) from the footprint at each of ``poses`` ((P, 3): x, y, yaw) to ``points`` (N, 2)."""
    if len(points) == 0:
        return numpy.full(len(poses), math.inf)
    return numpy.min(_point_clearances(points, footprint, poses), axis=1)


def point_clearances(points, footprint, poses):
    """(N,): the least distance (m) from the footprint over ``poses`` ((P, 3)) to each of ``points`` (N, 2)."""
    if len(points) == 0:
        return numpy.zeros(0)
    return numpy.min(_point_clearances(points, footprint, poses), axis=0)


def _point_clearances(points, footprint, poses):
    """(P, N): the distance (m) from the footprint at each of ``poses`` to each of ``points`` (N >= 1)."""
    poses = numpy.asarray(poses, dtype=float).reshape(-1, 3)
    c, s = numpy.cos(poses[:, 2:3]), numpy.sin(poses[:, 2:3])
    dx, dy = points[None, :, 0] - poses[:, 0:1], points[None, :, 1] - poses[:, 1:2]
    px, py = c * dx + s * dy, -s * dx + c * dy
    ox = numpy.maximum(numpy.maximum(footprint.x_min - px, px - footprint.x_max), 0.0)
    oy = numpy.maximum(numpy.maximum(footprint.y_min - py, py - footprint.y_max), 0.0)
    return numpy.hypot(ox, oy)


def footprint_clearance(points, footprint, x, y, yaw):
    """Least distance (m) from the footprint rectangle, placed at pose (x, y, yaw), to ``points``.

    0 for a point inside; ``inf`` when there are no points.
    """
    return float(footprint_clearances(points, footprint, [(x, y, yaw)])[0])


def _near(points, footprint, poses, margin):
    """The points the footprint swept over ``poses`` can come within ``margin`` of (and their indices)."""
    poses = numpy.asarray(poses, dtype=float).reshape(-1, 3)
    reach = float(numpy.hypot(poses[:, 0], poses[:, 1]).max(initial=0.0)) + footprint.radius_m + margin
    return numpy.nonzero(numpy.hypot(points[:, 0], points[:, 1]) <= reach)[0]


def path_clearance(points, footprint, poses):
    """Least footprint clearance (m) to ``points`` over ``poses`` (inf: none near)."""
    if len(points) == 0:
        return math.inf
    near = _near(points, footprint, poses, 1.0)
    return float(numpy.min(footprint_clearances(points[near], footprint, poses))) if len(near) else math.inf


def keeps_room(points, footprint, poses, margin, doubt=None):
    """(safe, least clearance m over ``poses``): the rule of the module's docstring. ``points`` (N, 2) in the
    robot's frame at the origin's pose; ``poses`` (P, 3) the footprint's along the move; ``margin`` (m);
    ``doubt``: (N,) m taken off each point's clearance, now and along (how far a remembered point may be off),
    or None."""
    if len(points) == 0:
        return True, math.inf
    near = _near(points, footprint, poses, margin + (float(numpy.max(doubt)) if doubt is not None else 0.0))
    if len(near) == 0:
        return True, math.inf
    now = _point_clearances(points[near], footprint, [(0.0, 0.0, 0.0)])[0]
    along = _point_clearances(points[near], footprint, poses).min(axis=0)
    if doubt is not None:
        now, along = now - doubt[near], along - doubt[near]
    return bool(numpy.all(along >= numpy.where(now < margin, now - CLEARANCE_EPS_M, margin))), float(along.min())
