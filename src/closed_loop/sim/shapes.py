"""Obstacle shapes in one place: how each is seen from above and how pybullet builds it.

An obstacle is a vertical prism: a box (walls are boxes) or a cylinder. :data:`SHAPES` maps the
obstacle's ``shape`` to a class that gives, for one obstacle at its time-0 position, the signed distance
from a point to its footprint, its outline (for pictures), whether a robot's rectangle overlaps it, and its
pybullet collision and visual shapes (alone, or as one of a compound's). World checks, the demo's clearance report and the simulator all go through this table, so
a new shape is one class here, and for the LIDAR's planar ray caster (``closed_loop.sim.planar_rays``) its
ray test there, by its ``RAY_KIND``, with the numbers ``ray_params`` gives of each obstacle.
"""
import math

import numpy


def _corners(cx, cy, yaw, x_min, x_max, y_min, y_max):
    c, s = math.cos(yaw), math.sin(yaw)
    return [(cx + c * x - s * y, cy + s * x + c * y) for x, y in
            ((x_min, y_min), (x_max, y_min), (x_max, y_max), (x_min, y_max))]


def separated(a, b):
    """True if convex polygons ``a`` and ``b`` (corner lists) have a separating axis (an edge normal)."""
    for poly in (a, b):
        for i in range(len(poly)):
            (x1, y1), (x2, y2) = poly[i], poly[(i + 1) % len(poly)]
            nx, ny = y2 - y1, x1 - x2
            pa = [nx * x + ny * y for x, y in a]
            pb = [nx * x + ny * y for x, y in b]
            if max(pa) <= min(pb) or max(pb) <= min(pa):
                return True
    return False


def robot_corners(pose, rect):
    """The corners of a robot's rectangle ``rect`` = (x_min, x_max, y_min, y_max), in its frame, at ``pose``."""
    return _corners(pose.x, pose.y, pose.yaw, *rect)


class Box:
    """A box, rotated by ``yaw`` about its centre: ``size`` is (x, y, z) full extents."""

    @staticmethod
    def distance(obstacle, x_m, y_m):
        c, s = math.cos(obstacle.yaw), math.sin(obstacle.yaw)
        dx, dy = x_m - obstacle.position[0], y_m - obstacle.position[1]
        qx = abs(c * dx + s * dy) - 0.5 * obstacle.size[0]
        qy = abs(-s * dx + c * dy) - 0.5 * obstacle.size[1]
        return math.hypot(max(qx, 0.0), max(qy, 0.0)) + min(max(qx, qy), 0.0)

    @staticmethod
    def outline(obstacle, x_m, y_m):
        """Its footprint's corners, centred at (``x_m``, ``y_m``)."""
        hx, hy = 0.5 * obstacle.size[0], 0.5 * obstacle.size[1]
        return _corners(x_m, y_m, obstacle.yaw, -hx, hx, -hy, hy)

    @staticmethod
    def overlaps_robot(obstacle, pose, rect):
        hx, hy = 0.5 * obstacle.size[0], 0.5 * obstacle.size[1]
        box = _corners(obstacle.position[0], obstacle.position[1], obstacle.yaw, -hx, hx, -hy, hy)
        return not separated(robot_corners(pose, rect), box)

    #: The planar caster's code for a box (``closed_loop.sim.planar_rays._hit``).
    RAY_KIND = 0

    @staticmethod
    def ray_params(obstacles):
        """What the planar caster needs of each box, (M, 4): cos and sin of its yaw, and its half-sizes."""
        return numpy.array([(math.cos(o.yaw), math.sin(o.yaw), 0.5 * o.size[0], 0.5 * o.size[1])
                            for o in obstacles]).reshape(-1, 4)

    @staticmethod
    def pybullet_kind(obstacle, pybullet):
        """(geometry type, radius, half extents, length): the box as one shape of a pybullet shape array."""
        return pybullet.GEOM_BOX, 0.0, [0.5 * s for s in obstacle.size], 0.0

    @staticmethod
    def pybullet_shapes(obstacle, call, pybullet):
        half = [0.5 * s for s in obstacle.size]
        return (call(pybullet.createCollisionShape, pybullet.GEOM_BOX, halfExtents=half),
                call(pybullet.createVisualShape, pybullet.GEOM_BOX, halfExtents=half,
                     rgbaColor=list(obstacle.color)))


class Cylinder:
    """An upright cylinder of ``radius``; ``size`` is (2 r, 2 r, height)."""

    @staticmethod
    def distance(obstacle, x_m, y_m):
        return math.hypot(x_m - obstacle.position[0], y_m - obstacle.position[1]) - obstacle.radius

    @staticmethod
    def outline(obstacle, x_m, y_m, sides=40):
        """Its footprint as a polygon of ``sides`` corners, centred at (``x_m``, ``y_m``)."""
        r = obstacle.radius
        return [(x_m + r * math.cos(2.0 * math.pi * i / sides), y_m + r * math.sin(2.0 * math.pi * i / sides))
                for i in range(sides)]

    @staticmethod
    def overlaps_robot(obstacle, pose, rect):
        x_min, x_max, y_min, y_max = rect
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        dx, dy = obstacle.position[0] - pose.x, obstacle.position[1] - pose.y
        lx, ly = c * dx + s * dy, -s * dx + c * dy
        gap = math.hypot(max(x_min - lx, 0.0, lx - x_max), max(y_min - ly, 0.0, ly - y_max))
        return gap < obstacle.radius

    #: The planar caster's code for a cylinder.
    RAY_KIND = 1

    @staticmethod
    def ray_params(obstacles):
        """(M, 1): each cylinder's radius."""
        return numpy.array([(o.radius,) for o in obstacles]).reshape(-1, 1)

    @staticmethod
    def pybullet_kind(obstacle, pybullet):
        """As :meth:`Box.pybullet_kind`, for a cylinder."""
        return pybullet.GEOM_CYLINDER, obstacle.radius, [0.0, 0.0, 0.0], obstacle.size[2]

    @staticmethod
    def pybullet_shapes(obstacle, call, pybullet):
        return (call(pybullet.createCollisionShape, pybullet.GEOM_CYLINDER, radius=obstacle.radius,
                     height=obstacle.size[2]),
                call(pybullet.createVisualShape, pybullet.GEOM_CYLINDER, radius=obstacle.radius,
                     length=obstacle.size[2], rgbaColor=list(obstacle.color)))


#: obstacle.shape -> its class.
SHAPES = {'box': Box, 'cylinder': Cylinder}


def bounding_radius(obstacle):
    """The radius (m) of a circle round the obstacle's footprint, about its centre."""
    return obstacle.radius if obstacle.shape == 'cylinder' else 0.5 * math.hypot(obstacle.size[0], obstacle.size[1])


def distance(obstacle, x_m, y_m):
    """Signed distance (m) from the point to the obstacle's footprint: negative inside."""
    return SHAPES[obstacle.shape].distance(obstacle, x_m, y_m)


def outline(obstacle, x_m=None, y_m=None):
    """The obstacle's footprint as polygon corners [(x, y), ...] (m), at its time-0 position or centred at
    (``x_m``, ``y_m``) (a moving obstacle's place at some time)."""
    x_m = obstacle.position[0] if x_m is None else x_m
    y_m = obstacle.position[1] if y_m is None else y_m
    return SHAPES[obstacle.shape].outline(obstacle, x_m, y_m)
