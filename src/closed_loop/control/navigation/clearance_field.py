"""The clearance of a footprint rectangle to scan points, fast and never overstated, for the local planner
(``closed_loop.control.navigation.window``): a distance transform of the points on a local grid (OpenCV), read at
samples along the footprint's outline, with a measured bound on how far a reading can fall below the
truth, and the exact check for the candidates that bound leaves in doubt. Free of ROS.
"""
import functools
import importlib
import math

import cv2
import numpy

from closed_loop.control.safety import footprint_clearances

#: Grid cell of the distance transform (m); clearances are read this much on the safe side.
GRID_CELL_M = 0.04
#: The most OpenCV's 5x5 chamfer distance differs from the Euclidean one, as a fraction of it (about 1.4%).
CHAMFER_ERROR = 0.02
#: Largest gap between samples of the footprint's outline (m) on the checked paths. A reading between
#: samples is bounded exactly (see :func:`edge_clearance`).
OUTLINE_STEP_M = 0.1
#: How much the grid's clearance can read below the truth (m): a cell's diagonal (the point's and the
#: query's places in their cells) and half the outline's sample gap.
FIELD_ERROR_M = GRID_CELL_M * math.sqrt(2.0) + 0.5 * OUTLINE_STEP_M


@functools.lru_cache(maxsize=16)
def outline32(footprint, step_m):
    points = outline(footprint, step_m).astype(numpy.float32)
    points.flags.writeable = False
    return points


def outline(footprint, step_m=OUTLINE_STEP_M):
    """Points (M, 2) along the footprint rectangle's edges, at most ``step_m`` apart, corners included."""
    x0, x1, y0, y1 = footprint.x_min, footprint.x_max, footprint.y_min, footprint.y_max
    nx = max(1, int(math.ceil((x1 - x0) / step_m)))
    ny = max(1, int(math.ceil((y1 - y0) / step_m)))
    xs, ys = numpy.linspace(x0, x1, nx + 1), numpy.linspace(y0, y1, ny + 1)
    return numpy.unique(numpy.concatenate([
        numpy.column_stack((xs, numpy.full_like(xs, y0))), numpy.column_stack((xs, numpy.full_like(xs, y1))),
        numpy.column_stack((numpy.full_like(ys, x0), ys)), numpy.column_stack((numpy.full_like(ys, x1), ys))]),
        axis=0)


class DistanceField:
    """Distance (m) from any point of a square around the robot to the nearest scan point, for the planner.

    Cells beyond the square read as ``reach_m`` (the square is sized so no predicted pose leaves it). A
    reading is lowered by one cell's diagonal, so the field never overstates a clearance.
    """

    def __init__(self, points, reach_m):
        self.cell = GRID_CELL_M
        self.half = int(math.ceil(reach_m / self.cell))
        self.size = size = 2 * self.half + 1
        self.reach_m = reach_m
        free = numpy.full((size, size), 255, numpy.uint8)
        if len(points):
            ij = numpy.round(points / self.cell).astype(numpy.int64) + self.half
            inside = (ij[:, 0] >= 0) & (ij[:, 0] < size) & (ij[:, 1] >= 0) & (ij[:, 1] < size)
            free[ij[inside, 1], ij[inside, 0]] = 0
        if free.all():
            self.flat = None
        else:
            # OpenCV's 5x5 chamfer mask is within CHAMFER_ERROR of the Euclidean distance either way, at
            # about half the cost of the exact transform: its reading is lowered by that much too.
            field = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_5) * (self.cell * (1.0 - CHAMFER_ERROR)) \
                - self.cell * math.sqrt(2.0)
            # The border reads as reach_m: a lookup beyond the square is clipped onto it.
            field[0, :] = field[-1, :] = field[:, 0] = field[:, -1] = reach_m
            self.flat = field.ravel()

    def at_xy(self, x, y):
        """Clearance (m) at points (``x``, ``y``: arrays of one shape) in the robot's frame. The square is
        sized so that nothing the planner asks about lies beyond it; a point that did would read the
        border's value."""
        if self.flat is None:
            return numpy.full(numpy.shape(x), math.inf)
        return self.flat.take(self.index(x, y), mode='clip')

    def index(self, x, y):
        offset = self.half + 0.5
        ix = (x * (1.0 / self.cell) + offset).astype(numpy.intp)
        iy = (y * (1.0 / self.cell) + offset).astype(numpy.intp)
        return iy * self.size + ix

    def at(self, xy):
        """Clearance (m) at points ``xy`` (..., 2) in the robot's frame."""
        return self.at_xy(xy[..., 0], xy[..., 1])


def edge_clearance(sampled, step_m):
    """The least clearance (m) of the whole outline, given the least one over its samples (``sampled``, m)
    taken at most ``step_m`` apart with the corners among them.

    An obstacle point P nearest to an edge's inner point E (the foot of P's perpendicular) lies within
    ``step_m / 2`` of E's nearest sample S along the edge, so ``|PS|^2 = |PE|^2 + |ES|^2``: the edge is at
    least ``sqrt(sampled^2 - (step_m / 2)^2)`` from P. P nearest to a corner is ``sampled`` away or more.
    """
    half = 0.5 * step_m
    sampled = numpy.asarray(sampled)
    return numpy.where(sampled > half, numpy.sqrt(numpy.maximum(sampled * sampled - half * half, 0.0)),
                       sampled - half)


def clearances(field, shape, poses, step_m):
    """Clearance (m) of the footprint outline ``shape`` (M, 2, samples at most ``step_m`` apart) at each of
    ``poses`` (C, K, 3): (C, K)."""
    if field.flat is None:
        return numpy.full(poses.shape[:2], math.inf)
    # In grid cells from the square's corner, float32 (the square has far fewer cells than that resolves), the
    # least over the outline's points at each pose taken in one compiled call (``arc_kernel``); the yaws'
    # cosines and sines from numpy.
    k = numpy.float32(1.0 / field.cell)
    yaw = poses[..., 2]
    least = importlib.import_module('closed_loop.control.arc_kernel').least_on_outline(
        field.flat, field.size, poses, numpy.cos(yaw), numpy.sin(yaw), shape[:, 0] * k, shape[:, 1] * k, k,
        numpy.float32(field.half + 0.5))
    return edge_clearance(least, step_m)


def keeps_margin(points, footprint, poses, margin):
    """True if the footprint at every one of ``poses`` ((K, 3)) is at least ``margin`` from ``points``:
    the exact check, over the points the swept rectangle could come that near to."""
    if not len(points):
        return True
    radius = footprint.radius_m
    reach = float(numpy.hypot(poses[:, 0], poses[:, 1]).max()) + radius + margin
    near = points[numpy.hypot(points[:, 0], points[:, 1]) <= reach]
    return not len(near) or float(footprint_clearances(near, footprint, poses).min()) >= margin
