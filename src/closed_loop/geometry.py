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


def matrix_quaternion(rotation):
    """The quaternion (x, y, z, w) of a 3x3 rotation matrix (rows of numbers)."""
    m = rotation
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        return ((m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s)
    i = max(range(3), key=lambda k: m[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(max(1.0 + m[i][i] - m[j][j] - m[k][k], 1e-12))
    q = [0.0, 0.0, 0.0, (m[k][j] - m[j][k]) / s]
    q[i], q[j], q[k] = 0.25 * s, (m[j][i] + m[i][j]) / s, (m[k][i] + m[i][k]) / s
    return tuple(q)
