"""Backing up: whether the scan sees behind the robot, the way it came (its trail in odom), and the command
that backs it out along that way. Free of ROS.

A LIDAR of less than a full turn cannot see behind the robot, but the robot has been there: the ground its
footprint swept on the way in was clear, so backing out along the trail stays on known ground (the navigator
still checks every such move against the scan and the points it remembers).
"""
import math

import numpy

from closed_loop.control.scan import sample_angles

#: Backing up straight needs the scan to see behind: rays within this of straight back (rad).
REAR_HALF_ANGLE_RAD = math.radians(30.0)

#: A trail point is kept every TRAIL_STEP_M travelled; the trail keeps the last TRAIL_LENGTH_M of them.
TRAIL_STEP_M = 0.1
TRAIL_LENGTH_M = 5.0
#: Backing out steers the robot's rear toward the trail point TRAIL_LOOKBACK_M farther back than itself, at
#: BACK_TURN_GAIN x the rear's heading error (rad/s per rad); it backs at full speed while that error is
#: within BACK_STRAIGHT_RAD, turns in place beyond BACK_TURN_ONLY_RAD, and slows linearly in between.
TRAIL_LOOKBACK_M = 0.3
BACK_TURN_GAIN = 1.5
BACK_STRAIGHT_RAD = math.radians(15.0)
BACK_TURN_ONLY_RAD = math.radians(45.0)


class Trail:
    """The odom positions a robot passed, a point every ``TRAIL_STEP_M``, newest last."""

    def __init__(self):
        self._points = []

    def __len__(self):
        return len(self._points)

    def add(self, x, y):
        """The robot is at (x, y) (odom, m): a new point once it is TRAIL_STEP_M from the newest."""
        if not self._points or math.hypot(x - self._points[-1][0], y - self._points[-1][1]) >= TRAIL_STEP_M - 1e-9:
            self._points.append((float(x), float(y)))
            del self._points[:-int(round(TRAIL_LENGTH_M / TRAIL_STEP_M))]

    def back(self, distance_m):
        """The point ``distance_m`` back along the trail from its newest point (odom; its oldest if the
        trail is shorter; None if it is empty)."""
        if not self._points:
            return None
        left = distance_m
        for newer, older in zip(self._points[::-1], self._points[-2::-1]):
            step = math.hypot(newer[0] - older[0], newer[1] - older[1])
            if step >= left:
                t = left / step if step else 0.0
                return (newer[0] + t * (older[0] - newer[0]), newer[1] + t * (older[1] - newer[1]))
            left -= step
        return self._points[0]

    def drop_behind(self, x, y):
        """Forget the points newer than the one nearest (x, y) (backing out has gone back over them)."""
        if self._points:
            points = numpy.asarray(self._points)
            nearest = int(numpy.argmin(numpy.hypot(points[:, 0] - x, points[:, 1] - y)))
            del self._points[nearest + 1:]


def back_toward(pose, target, speed_mps, max_yaw_rate):
    """(m/s, rad/s): backing at up to ``speed_mps`` with the robot's rear turned toward ``target`` (odom)."""
    x, y, yaw = pose
    bearing = math.atan2(target[1] - y, target[0] - x)
    error = math.atan2(math.sin(bearing - yaw - math.pi), math.cos(bearing - yaw - math.pi))
    w = max(-max_yaw_rate, min(max_yaw_rate, BACK_TURN_GAIN * error))
    share = (BACK_TURN_ONLY_RAD - abs(error)) / (BACK_TURN_ONLY_RAD - BACK_STRAIGHT_RAD)
    return -speed_mps * max(0.0, min(1.0, share)), w


def rear_seen(scan, laser_pose):
    """True if the scan has rays toward the whole rear sector (a 270-degree LIDAR facing forward has
    none: then what is behind is unknown, and backing up is not safe)."""
    angles = numpy.asarray(sample_angles(scan)) + laser_pose.yaw
    off_back = numpy.abs(numpy.arctan2(numpy.sin(angles - math.pi), numpy.cos(angles - math.pi)))
    covered = off_back <= REAR_HALF_ANGLE_RAD
    if not covered.any():
        return False
    spacing = abs(scan.angle_increment)
    return covered.sum() * spacing >= 2 * REAR_HALF_ANGLE_RAD - 2 * spacing
