"""What the simulator needs to know about the robot, read from its URDF (the single source of truth).

The URDF names the frames and gives the wheel geometry; nothing here restates a dimension.
"""
import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

LEFT_WHEEL_JOINT = 'wheel_left_joint'
RIGHT_WHEEL_JOINT = 'wheel_right_joint'
BASE_FRAME = 'base_footprint'
SCAN_FRAME = 'base_scan'
CAMERA_FRAME = 'camera_link'
CAMERA_OPTICAL_FRAME = 'camera_optical_frame'


class RobotModelError(ValueError):
    """The URDF lacks something the simulator relies on; the message names the file and element."""


@dataclass(frozen=True)
class RobotModel:
    urdf_path: str
    wheel_radius_m: float
    wheel_separation_m: float   # distance between the wheel contact points, along y
    scan_to_front_m: float      # along x, from the LIDAR axis to the front face of base_link's body box


def default_urdf_path():
    """The package's robot description, ``urdf/robot.urdf``."""
    here = os.path.dirname(os.path.abspath(__file__))
    return os.path.normpath(os.path.join(here, '..', '..', 'urdf', 'robot.urdf'))


def load_robot_model(urdf_path):
    """Read wheel radius and separation from the URDF's wheel joints and their links' cylinders."""
    try:
        root = ET.parse(urdf_path).getroot()
    except (OSError, ET.ParseError) as error:
        raise RobotModelError('%s: cannot read the robot description: %s' % (urdf_path, error))
    joints = {j.get('name'): j for j in root.findall('joint')}
    links = {k.get('name'): k for k in root.findall('link')}
    frames = set(links)
    for name in (BASE_FRAME, SCAN_FRAME, CAMERA_FRAME, CAMERA_OPTICAL_FRAME):
        if name not in frames:
            raise RobotModelError('%s: link %r is missing' % (urdf_path, name))
    ys = []
    radii = []
    for name in (LEFT_WHEEL_JOINT, RIGHT_WHEEL_JOINT):
        joint = joints.get(name)
        if joint is None:
            raise RobotModelError('%s: joint %r is missing' % (urdf_path, name))
        origin = joint.find('origin')
        xyz = [float(v) for v in origin.get('xyz', '0 0 0').split()] if origin is not None else [0, 0, 0]
        ys.append(xyz[1])
        child = links.get(joint.find('child').get('link'))
        cylinder = child.find('collision/geometry/cylinder') if child is not None else None
        if cylinder is None:
            raise RobotModelError('%s: joint %r: its child link needs a cylinder collision' % (urdf_path, name))
        radii.append(float(cylinder.get('radius')))
    if abs(radii[0] - radii[1]) > 1e-9:
        raise RobotModelError('%s: the wheels have different radii %s' % (urdf_path, radii))
    separation = abs(ys[0] - ys[1])
    if separation <= 0:
        raise RobotModelError('%s: the wheels are not apart along y' % urdf_path)
    return RobotModel(urdf_path=urdf_path, wheel_radius_m=radii[0], wheel_separation_m=separation,
                      scan_to_front_m=_body_front_x(urdf_path, links) - _joint_x(urdf_path, joints, 'scan_joint'))


def _joint_x(urdf_path, joints, name):
    joint = joints.get(name)
    if joint is None:
        raise RobotModelError('%s: joint %r is missing' % (urdf_path, name))
    origin = joint.find('origin')
    return float(origin.get('xyz', '0 0 0').split()[0]) if origin is not None else 0.0


def _body_front_x(urdf_path, links):
    """x of the front face of base_link's box collision (base_link's x equals base_footprint's)."""
    for collision in links['base_link'].findall('collision'):
        box = collision.find('geometry/box')
        if box is not None:
            origin = collision.find('origin')
            x = float(origin.get('xyz', '0 0 0').split()[0]) if origin is not None else 0.0
            return x + 0.5 * float(box.get('size').split()[0])
    raise RobotModelError('%s: base_link needs a box collision (the body)' % urdf_path)


# --- planar geometry from the URDF text (robot_description) --------------------------------------------

@dataclass(frozen=True)
class Footprint:
    """The robot seen from above: the rectangle (m, in base_footprint) around every collision shape."""
    x_min: float
    x_max: float
    y_min: float
    y_max: float

    @property
    def length_m(self):
        return self.x_max - self.x_min

    @property
    def width_m(self):
        return self.y_max - self.y_min


@dataclass(frozen=True)
class Pose2DInBase:
    """A frame's planar pose in base_footprint: x, y (m) and yaw (rad)."""
    x: float
    y: float
    yaw: float


def _origin_matrix(element):
    """The 4x4 transform of a URDF ``<origin xyz rpy>`` (identity when absent)."""
    origin = element.find('origin') if element is not None else None
    xyz = [float(v) for v in origin.get('xyz', '0 0 0').split()] if origin is not None else [0.0] * 3
    rpy = [float(v) for v in origin.get('rpy', '0 0 0').split()] if origin is not None else [0.0] * 3
    cr, sr, cp, sp, cy, sy = (math.cos(rpy[0]), math.sin(rpy[0]), math.cos(rpy[1]), math.sin(rpy[1]),
                              math.cos(rpy[2]), math.sin(rpy[2]))
    m = np.eye(4)
    # URDF rpy: fixed-axis roll, then pitch, then yaw: R = Rz(yaw) Ry(pitch) Rx(roll).
    m[:3, :3] = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                 [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                 [-sp, cp * sr, cp * cr]]
    m[:3, 3] = xyz
    return m


def _parse_urdf_text(urdf_text, source):
    try:
        return ET.fromstring(urdf_text)
    except ET.ParseError as error:
        raise RobotModelError('%s: cannot parse the robot description: %s' % (source, error)) from None


def link_transforms(urdf_text, root=BASE_FRAME, source='robot_description'):
    """Every link's 4x4 pose in ``root`` with all joints at zero, from the URDF's joint origins."""
    robot = _parse_urdf_text(urdf_text, source)
    children = {}
    for joint in robot.findall('joint'):
        parent, child = joint.find('parent'), joint.find('child')
        if parent is None or child is None:
            raise RobotModelError('%s: joint %r lacks a parent or child' % (source, joint.get('name')))
        children.setdefault(parent.get('link'), []).append((child.get('link'), _origin_matrix(joint)))
    if root not in {k.get('name') for k in robot.findall('link')}:
        raise RobotModelError('%s: link %r is missing' % (source, root))
    poses = {root: np.eye(4)}
    todo = [root]
    while todo:
        parent = todo.pop()
        for child, origin in children.get(parent, []):
            poses[child] = poses[parent] @ origin
            todo.append(child)
    return robot, poses


def _shape_corners(geometry):
    """Points (in the shape's own frame) whose xy hull bounds the shape seen from above, or None."""
    box, cylinder, sphere = geometry.find('box'), geometry.find('cylinder'), geometry.find('sphere')
    if box is not None:
        hx, hy, hz = (0.5 * float(v) for v in box.get('size').split())
        return np.array([[sx * hx, sy * hy, sz * hz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    if cylinder is not None:
        r, h = float(cylinder.get('radius')), 0.5 * float(cylinder.get('length'))
        return np.array([[sx * r, sy * r, sz * h] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    if sphere is not None:
        r = float(sphere.get('radius'))
        return np.array([[sx * r, sy * r, sz * r] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    return None


def footprint(urdf_text, source='robot_description'):
    """The :class:`Footprint` around every ``<collision>`` box, cylinder and sphere of the robot.

    Meshes have no size here and are refused; a robot with no collision shape is refused too.
    """
    robot, poses = link_transforms(urdf_text, source=source)
    points = []
    for link in robot.findall('link'):
        pose = poses.get(link.get('name'))
        if pose is None:
            continue
        for collision in link.findall('collision'):
            geometry = collision.find('geometry')
            corners = _shape_corners(geometry) if geometry is not None else None
            if corners is None:
                raise RobotModelError('%s: link %r: a collision needs a box, cylinder or sphere'
                                      % (source, link.get('name')))
            m = pose @ _origin_matrix(collision)
            points.append(corners @ m[:3, :3].T + m[:3, 3])
    if not points:
        raise RobotModelError('%s: no collision shapes under %r' % (source, BASE_FRAME))
    xy = np.vstack(points)[:, :2]
    return Footprint(float(xy[:, 0].min()), float(xy[:, 0].max()), float(xy[:, 1].min()), float(xy[:, 1].max()))


def frame_pose_2d(urdf_text, frame, source='robot_description'):
    """The planar pose (x, y, yaw) of ``frame`` in base_footprint."""
    _robot, poses = link_transforms(urdf_text, source=source)
    if frame not in poses:
        raise RobotModelError('%s: link %r is missing or not below %r' % (source, frame, BASE_FRAME))
    m = poses[frame]
    return Pose2DInBase(float(m[0, 3]), float(m[1, 3]), math.atan2(m[1, 0], m[0, 0]))
