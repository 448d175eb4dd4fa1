"""What the simulator, the guard and the tools need to know about the robot, read from its URDF.

The URDF (on ``robot_description``) is the single source of the robot's geometry: wheel radius and
separation, the footprint rectangle, where the LIDAR and camera sit. A robot profile names which of its
frames and joints play which part (:class:`RobotNames`); nothing here restates a dimension.
"""
import functools
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass

import numpy as np

from closed_loop import description
from closed_loop.geometry import Pose2D, matrix_quaternion

#: The default robot's names (urdf/closed_loop.urdf). A robot profile (config/robots/<name>.yaml) names its own
#: frames and joints through the simulator's parameters; these are only the defaults of those parameters.
LEFT_WHEEL_JOINT = 'wheel_left_joint'
RIGHT_WHEEL_JOINT = 'wheel_right_joint'
BASE_FRAME = 'base_footprint'
BODY_LINK = 'base_link'
SCAN_FRAME = 'base_scan'
CAMERA_FRAME = 'camera_link'
CAMERA_OPTICAL_FRAME = 'camera_optical_frame'
#: The joints a wheel turns on.
WHEEL_JOINT_TYPES = ('continuous', 'revolute')


#: The URDF lacks something the simulator relies on (or a mesh of it is unusable); the message names the source
#: and element.
RobotModelError = description.DescriptionError


@dataclass(frozen=True)
class RobotNames:
    """Which URDF frames and joints play which part; a robot profile sets them (simulator parameters).

    ``camera_frame`` empty: the robot has no camera. Each side may have several wheel joints (a skid-steer
    base like the Jackal); they turn together.
    """
    base_frame: str = BASE_FRAME
    body_link: str = BODY_LINK
    scan_frame: str = SCAN_FRAME
    camera_frame: str = CAMERA_FRAME
    camera_optical_frame: str = CAMERA_OPTICAL_FRAME
    left_wheel_joints: tuple = (LEFT_WHEEL_JOINT,)
    right_wheel_joints: tuple = (RIGHT_WHEEL_JOINT,)


@dataclass(frozen=True)
class RobotModel:
    urdf_text: str
    source: str
    names: RobotNames
    wheel_radius_m: float
    wheel_separation_m: float   # distance between the left and right wheel contact lines, along y
    footprint: 'Footprint'      # the rectangle around the collision shapes, in the base frame
    scan_pose: Pose2D     # the LIDAR frame in the base frame

    @property
    def scan_to_front_m(self):
        """Along x, from the LIDAR axis to the front of the footprint."""
        return self.footprint.x_max - self.scan_pose.x

    @property
    def has_camera(self):
        return bool(self.names.camera_frame)


def default_urdf_path():
    """The package's default robot description, ``urdf/closed_loop.urdf``."""
    from closed_loop.paths import data_path
    return data_path('urdf', 'closed_loop.urdf')


def read_urdf(path):
    """The text of the URDF file at ``path``."""
    try:
        with open(path) as stream:
            return stream.read()
    except OSError as error:
        raise RobotModelError('%s: cannot read the robot description: %s' % (path, error.strerror or error))


def load_robot_model(urdf, names=RobotNames(), source=None):
    """Read the drive geometry, footprint and LIDAR pose from a URDF (its text, or a file path).

    Wheel radius from the wheel links' collision cylinders (all equal); wheel separation from the joint
    origins (the mean y of the left wheels minus that of the right ones). Frames named in ``names`` must
    exist (the camera's only if ``names.camera_frame`` is not empty). The same text and names give the same
    (frozen) model, read once per process.
    """
    if not urdf.lstrip().startswith('<'):
        source = source or urdf
        urdf = read_urdf(urdf)
    return _robot_model(urdf, names, source)


@functools.lru_cache(maxsize=16)
def _robot_model(urdf, names, source):
    source = source or 'robot_description'
    if '<mesh' in urdf:                     # every mesh there and usable before anything runs
        description.meshes(urdf, source)
    root, poses = link_transforms(urdf, names.base_frame, source)
    joints = {j.get('name'): j for j in root.findall('joint')}
    links = {k.get('name'): k for k in root.findall('link')}
    wanted = [names.base_frame, names.body_link, names.scan_frame]
    if names.camera_frame:
        wanted += [names.camera_frame, names.camera_optical_frame]
    for name in wanted:
        if name not in links:
            raise RobotModelError('%s: link %r is missing' % (source, name))
    ys = {'left': [], 'right': []}
    radii = []
    for side, joint_names in (('left', names.left_wheel_joints), ('right', names.right_wheel_joints)):
        if not joint_names:
            raise RobotModelError('%s: no %s wheel joint named' % (source, side))
        for name in joint_names:
            joint = joints.get(name)
            if joint is None or joint.get('type') not in WHEEL_JOINT_TYPES:
                raise RobotModelError('%s: joint %r %s; %s' % (
                    source, name, 'is missing' if joint is None else 'is not a wheel: it is %s' % joint.get('type'),
                    _wheel_hint(joints)))
            child_name = joint.find('child').get('link')
            ys[side].append(float(poses[child_name][1, 3]))
            cylinder = links[child_name].find('collision/geometry/cylinder')
            if cylinder is None:
                raise RobotModelError('%s: joint %r: its child link needs a cylinder collision' % (source, name))
            radii.append(float(cylinder.get('radius')))
    if max(radii) - min(radii) > 1e-9:
        raise RobotModelError('%s: the wheels have different radii %s' % (source, radii))
    separation = sum(ys['left']) / len(ys['left']) - sum(ys['right']) / len(ys['right'])
    if separation <= 0:
        raise RobotModelError('%s: the left wheels are not to the left (+y) of the right ones' % source)
    return RobotModel(urdf_text=urdf, source=source, names=names, wheel_radius_m=radii[0],
                      wheel_separation_m=separation, footprint=footprint(urdf, source, names.base_frame),
                      scan_pose=frame_pose_2d(urdf, names.scan_frame, source, names.base_frame))


def _wheel_hint(joints):
    """What the description offers as wheels, for an error about one that is not there."""
    wheels = sorted(name for name, joint in joints.items() if joint.get('type') in WHEEL_JOINT_TYPES)
    if not wheels:
        return 'the description has no continuous joints: without wheels it cannot drive'
    return ('its continuous joints are %s: the profile names the wheels (sim: left_wheel_joints, '
            'right_wheel_joints)' % ', '.join(wheels))


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

    @property
    def radius_m(self):
        """How far the rectangle reaches from base_footprint's origin (m): its farthest corner."""
        return math.hypot(max(abs(self.x_min), abs(self.x_max)), max(abs(self.y_min), abs(self.y_max)))


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


def parse_urdf(urdf_text, source):
    try:
        return ET.fromstring(urdf_text)
    except ET.ParseError as error:
        raise RobotModelError('%s: cannot parse the robot description: %s' % (source, error)) from None


def link_transforms(urdf_text, root=BASE_FRAME, source='robot_description'):
    """Every link's 4x4 pose in ``root`` with all joints at zero, from the URDF's joint origins."""
    robot = parse_urdf(urdf_text, source)
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


def fixed_joints(urdf_text, source='robot_description'):
    """[(parent link, child link, (x, y, z) m, quaternion (x, y, z, w))] of every fixed joint, as
    robot_state_publisher sends them on /tf_static."""
    robot = parse_urdf(urdf_text, source)
    out = []
    for joint in robot.findall('joint'):
        parent, child = joint.find('parent'), joint.find('child')
        if joint.get('type') != 'fixed' or parent is None or child is None:
            continue
        m = _origin_matrix(joint)
        out.append((parent.get('link'), child.get('link'), tuple(float(v) for v in m[:3, 3]),
                    matrix_quaternion(m[:3, :3].tolist())))
    return out


def _shape_corners(geometry, source):
    """Points (in the shape's own frame) whose xy hull bounds the shape seen from above, or None. A mesh's are its
    vertices as pybullet takes them (``closed_loop.description``)."""
    box, cylinder, sphere = geometry.find('box'), geometry.find('cylinder'), geometry.find('sphere')
    mesh = geometry.find('mesh')
    if mesh is not None:
        return description.mesh_points(*description.mesh_file(mesh, source))
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


@functools.lru_cache(maxsize=32)
def footprint(urdf_text, source='robot_description', base_frame=BASE_FRAME):
    """The :class:`Footprint` around every ``<collision>`` box, cylinder, sphere and mesh of the robot.

    A robot with no collision shape is refused. Worked out once per description (an episode asks for it at
    every start).
    """
    robot, poses = link_transforms(urdf_text, base_frame, source)
    points = []
    for link in robot.findall('link'):
        pose = poses.get(link.get('name'))
        if pose is None:
            continue
        for collision in link.findall('collision'):
            geometry = collision.find('geometry')
            corners = _shape_corners(geometry, source) if geometry is not None else None
            if corners is None:
                raise RobotModelError('%s: link %r: a collision needs a box, cylinder, sphere or mesh'
                                      % (source, link.get('name')))
            m = pose @ _origin_matrix(collision)
            points.append(corners @ m[:3, :3].T + m[:3, 3])
    if not points:
        raise RobotModelError('%s: no collision shapes under %r' % (source, base_frame))
    xy = np.vstack(points)[:, :2]
    return Footprint(float(xy[:, 0].min()), float(xy[:, 0].max()), float(xy[:, 1].min()), float(xy[:, 1].max()))


@functools.lru_cache(maxsize=64)
def frame_pose_2d(urdf_text, frame, source='robot_description', base_frame=BASE_FRAME):
    """The planar pose (x, y, yaw) of ``frame`` in the base frame (worked out once per description and frame)."""
    _robot, poses = link_transforms(urdf_text, base_frame, source)
    if frame not in poses:
        raise RobotModelError('%s: link %r is missing or not below %r' % (source, frame, base_frame))
    m = poses[frame]
    return Pose2D(float(m[0, 3]), float(m[1, 3]), math.atan2(m[1, 0], m[0, 0]))
