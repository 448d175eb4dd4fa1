"""What the navigator remembers of recent scans: their points in ``odom``, for choosing a way around, and
for safety only where the scanner cannot see now (the blind sector of a LIDAR of less than a full turn).

A LIDAR that sweeps less than a full turn does not see behind the robot, and an obstacle hides what is
behind it; a way chosen from the newest scan alone changes as the robot turns, and a robot can circle in a
pocket whose exit it saw a moment ago. So the points of recent scans are kept, one per ``CELL_M`` cell
(the newest), and dropped when older than ``memory_s`` or when a newer ray passes through them (something
that moved away). Free of ROS.
"""
import math

import numpy

CELL_M = 0.1
#: A remembered point this much (m) short of the newest range along its ray is seen through: gone.
SEE_THROUGH_M = 0.15
#: A move turning in place (the window's, the recovery's, the escape's) keeps this much more than the margin
#: from a point remembered where the scan cannot see: what was seen of an obstacle is the side that faced the
#: laser, and a back corner swinging round meets a side never seen (a post's far side can lie centimetres
#: nearer the corner than any point remembered of it); and a skid-steer base turning in place slides a few
#: centimetres its odometry does not see.
BLIND_EXTRA_M = 0.05


def to_frame(points, pose):
    """``points`` ((N, 2), odom) in the frame of a robot at ``pose`` (x, y, yaw in odom)."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = points[:, 0] - x, points[:, 1] - y
    return numpy.column_stack((c * dx + s * dy, -s * dx + c * dy))


def from_frame(points, pose):
    """``points`` ((N, 2), the frame of a robot at ``pose``) in odom."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)
    return numpy.column_stack((x + c * points[:, 0] - s * points[:, 1], y + s * points[:, 0] + c * points[:, 1]))


def blind_points(points, scan, laser_pose):
    """Those of ``points`` ((N, 2), the robot's frame) outside the scan's sweep, as seen from the laser."""
    return points[blind_mask(points, scan, laser_pose)]


def blind_mask(points, scan, laser_pose):
    """(N,) bool: which of ``points`` ((N, 2), the robot's frame) lie outside the scan's sweep."""
    if scan.angle_max - scan.angle_min + scan.angle_increment >= 2 * math.pi - 1e-6 or not len(points):
        return numpy.zeros(len(points), bool)
    bearing = numpy.arctan2(points[:, 1] - laser_pose.y, points[:, 0] - laser_pose.x) - laser_pose.yaw
    middle, half = 0.5 * (scan.angle_min + scan.angle_max), 0.5 * (scan.angle_max - scan.angle_min)
    off = numpy.abs(numpy.arctan2(numpy.sin(bearing - middle), numpy.cos(bearing - middle)))
    return off > half + scan.angle_increment


class ScanMemory:
    """Remembered scan points in odom, with the time each was last seen."""

    def __init__(self, memory_s):
        self.memory_s = memory_s
        self.xy = numpy.zeros((0, 2))
        self.t = numpy.zeros(0)

    def clear(self):
        self.xy, self.t = numpy.zeros((0, 2)), numpy.zeros(0)

    def add(self, now_s, pose, points, scan, laser_pose, footprint=None):
        """Remember ``points`` ((N, 2), robot frame) of ``scan`` taken at ``pose`` (x, y, yaw in odom);
        forget what is too old, what the scan's rays pass through, and what lies within ``footprint`` (the
        robot's rectangle, if given) at ``pose``: the robot stands there, so a point there is one odometry
        misplaced."""
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        keep = self.t >= now_s - self.memory_s
        old, old_t = (self.xy, self.t) if keep.all() else (self.xy[keep], self.t[keep])
        if len(old) and scan.angle_increment > 0:
            # The remembered points in the laser's frame: along which ray, how far.
            dx, dy = old[:, 0] - x, old[:, 1] - y
            bx = c * dx + s * dy - laser_pose.x
            by = -s * dx + c * dy - laser_pose.y
            bearing = numpy.arctan2(by, bx) - laser_pose.yaw
            count = len(scan.ranges)
            index = numpy.round(numpy.mod(bearing - scan.angle_min, 2 * math.pi)
                                / scan.angle_increment).astype(numpy.intp)
            if count * scan.angle_increment >= 2 * math.pi - 1e-6:
                index %= count       # a full turn: the last ray's neighbour is the first
            inside = index < count
            ranges = numpy.where(inside, scan.ranges[numpy.minimum(index, count - 1)], numpy.nan)
            ranges[ranges == numpy.inf] = scan.range_max
            with numpy.errstate(invalid='ignore'):
                kept = ~(numpy.hypot(bx, by) < ranges - SEE_THROUGH_M)      # not seen through
            if footprint is not None:
                rx, ry = bx + laser_pose.x, by + laser_pose.y               # the robot's frame
                kept &= ((rx < footprint.x_min) | (rx > footprint.x_max) | (ry < footprint.y_min)
                         | (ry > footprint.y_max))
            old, old_t = old[kept], old_t[kept]
        new = numpy.column_stack((x + c * points[:, 0] - s * points[:, 1], y + s * points[:, 0] + c * points[:, 1]))
        xy = numpy.concatenate((new, old))
        t = numpy.concatenate((numpy.full(len(new), now_s), old_t))
        # One point per cell, the newest: the new points come first, and a stable sort of the cells keeps the
        # first of each (as numpy.unique's first indices would, without its wrapping).
        cells = numpy.floor(xy / CELL_M).astype(numpy.int64)
        key = cells[:, 0] * 1000003 + cells[:, 1]
        order = numpy.argsort(key, kind='stable')
        sorted_key = key[order]
        first = numpy.empty(len(order), bool)
        first[:1] = True
        numpy.not_equal(sorted_key[1:], sorted_key[:-1], out=first[1:])
        chosen = order[first]
        self.xy, self.t = xy[chosen], t[chosen]

    def points(self, pose):
        """The remembered points in the robot's frame at ``pose`` (x, y, yaw in odom), (M, 2)."""
        return to_frame(self.xy, pose)

    def occupancy(self):
        """What is remembered as a grid in odom: (origin (x, y) m of cell (0, 0)'s corner, (rows, columns) bool,
        True where a point is, row i at y = origin y + i CELL_M); a single empty cell when nothing is."""
        if not len(self.xy):
            return (0.0, 0.0), numpy.zeros((1, 1), bool)
        cells = numpy.floor(self.xy / CELL_M).astype(numpy.int64)
        low = cells.min(axis=0)
        size = cells.max(axis=0) - low + 1
        grid = numpy.zeros((size[1], size[0]), bool)
        grid[cells[:, 1] - low[1], cells[:, 0] - low[0]] = True
        return (float(low[0] * CELL_M), float(low[1] * CELL_M)), grid
