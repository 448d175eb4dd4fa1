"""Planar poses and rotations as quaternions, in one place (REP 103: yaw counter-clockwise about +z, radians).

Quaternions are (x, y, z, w) tuples, the order of geometry_msgs/Quaternion and of pybullet.
"""
import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Pose2D:
    """A pose on the ground plane in some frame (the world's, or base_footprint's for a sensor on the robot):
    x, y in m, yaw in rad (counter-clockwise from +x)."""
    x: float
    y: float
    yaw: float


def yaw_quaternion(yaw_rad):
    """The quaternion (x, y, z, w) of a rotation by ``yaw_rad`` about +z."""
    return (0.0, 0.0, math.sin(0.5 * yaw_rad), math.cos(0.5 * yaw_rad))


def quaternion_yaw(quaternion):
    """The yaw (rad, in (-pi, pi]) of a quaternion (x, y, z, w): its rotation about +z."""
    x, y, z, w = quaternion
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
