"""What the simulator needs to know about the robot, read from its URDF (the single source of truth).

The URDF names the frames and gives the wheel geometry; nothing here restates a dimension.
"""
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass

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
