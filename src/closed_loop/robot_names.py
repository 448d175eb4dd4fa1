"""Which of a robot description's frames and joints play which part, found in the description itself where a
robot profile does not name them.

The parts are the simulator's parameters (``closed_loop.sim.simulation.SimSettings``: ``base_frame``,
``body_link``, ``scan_frame``, ``camera_frame``, ``camera_optical_frame``, ``left_wheel_joints``,
``right_wheel_joints``) and the controllers' and the guard's ``scan_frame``. For each part the profile does not
name, the default name is taken if the description has it; else the part is looked for:

- the base: the description's root link; the body: the link fixed to it;
- the drive: the continuous (or revolute) joints whose child link has a cylinder collision, left where the
  joint sits at y > 0 in the base, right where at y < 0 (two wheels, or four skid-steered);
- the LIDAR: the one link named like one (laser, lidar, scan, hokuyo, rplidar, sick, velodyne, ouster, lds),
  a link with none below it preferred over its mount;
- the camera: the one link named ``*camera*`` (not optical) and, below it, the one named ``*optical*``; none:
  the robot has no camera.

What is not found, or found twice, keeps the default name, and loading the robot then fails naming it (and
the profile key that names it). Free of ROS.
"""
import re

from closed_loop import robot_model

#: The defaults of the parts' parameters (the simulator's).
DEFAULTS = {'base_frame': robot_model.BASE_FRAME, 'body_link': robot_model.BODY_LINK,
            'scan_frame': robot_model.SCAN_FRAME, 'camera_frame': robot_model.CAMERA_FRAME,
            'camera_optical_frame': robot_model.CAMERA_OPTICAL_FRAME,
            'left_wheel_joints': robot_model.LEFT_WHEEL_JOINT, 'right_wheel_joints': robot_model.RIGHT_WHEEL_JOINT}
LIDAR_NAME = re.compile(r'laser|lidar|scan|hokuyo|rplidar|sick|velodyne|ouster|lds', re.I)


def parts(urdf, given=(), source='robot_description'):
    """{parameter: name} for every part (:data:`DEFAULTS`): ``given`` ({parameter: name}, what the profile or
    the node's parameters set) as it is, the rest as the description has them (see the module's doc)."""
    robot = robot_model.parse_urdf(urdf, source)
    links = {link.get('name') for link in robot.findall('link')}
    joints = [(j.get('name'), j.get('type'), j.find('parent').get('link'), j.find('child').get('link'))
              for j in robot.findall('joint') if j.find('parent') is not None and j.find('child') is not None]
    given = dict(given)
    found = dict(given)

    def default_or(param, finder):
        if param not in found:
            found[param] = DEFAULTS[param] if all(n in links for n in DEFAULTS[param].split()) else \
                (finder() or DEFAULTS[param])
    default_or('base_frame', lambda: _root(urdf, source))
    base = found['base_frame']
    default_or('body_link', lambda: _only([c for _, t, p, c in joints if p == base and t == 'fixed']))
    wheels = _wheels(urdf, base, joints, source) if base in links else ({}, {})
    if 'left_wheel_joints' not in given and 'right_wheel_joints' not in given and not (
            DEFAULTS['left_wheel_joints'] in _names(joints) and DEFAULTS['right_wheel_joints'] in _names(joints)):
        if wheels[0] and wheels[1]:
            found['left_wheel_joints'], found['right_wheel_joints'] = ' '.join(wheels[0]), ' '.join(wheels[1])
    for param in ('left_wheel_joints', 'right_wheel_joints'):
        found.setdefault(param, DEFAULTS[param])
    default_or('scan_frame', lambda: _lidar(links, {p for _, _, p, _ in joints}))
    if 'camera_frame' not in given and DEFAULTS['camera_frame'] not in links:
        camera = _only([n for n in links if 'camera' in n.lower() and 'optical' not in n.lower()])
        optical = _only([n for n in _below(camera, joints) if 'optical' in n.lower()]) if camera else None
        found['camera_frame'] = camera if camera and optical else ''
        found.setdefault('camera_optical_frame', optical or DEFAULTS['camera_optical_frame'])
    found.setdefault('camera_frame', DEFAULTS['camera_frame'])
    found.setdefault('camera_optical_frame', DEFAULTS['camera_optical_frame'])
    return found


def _names(joints):
    return {name for name, _, _, _ in joints}


def _only(candidates):
    candidates = sorted(set(candidates))
    return candidates[0] if len(candidates) == 1 else None


def _root(urdf, source):
    robot = robot_model.parse_urdf(urdf, source)
    children = {j.find('child').get('link') for j in robot.findall('joint') if j.find('child') is not None}
    roots = [link.get('name') for link in robot.findall('link') if link.get('name') not in children]
    if robot_model.BASE_FRAME in roots or len(roots) != 1:
        return robot_model.BASE_FRAME
    return roots[0]


def _below(link, joints):
    found, todo = [], [link]
    while todo:
        parent = todo.pop()
        for _, _, p, c in joints:
            if p == parent:
                found.append(c)
                todo.append(c)
    return found


def _lidar(links, parents):
    named = [n for n in links if LIDAR_NAME.search(n)]
    return _only([n for n in named if n not in parents]) or _only(named)


def _wheels(urdf, base, joints, source):
    """([left wheel joints], [right wheel joints]): continuous or revolute joints whose child has a cylinder
    collision, by the side of the base they sit on."""
    robot, poses = robot_model.link_transforms(urdf, base, source)
    cylinders = {link.get('name') for link in robot.findall('link')
                 if link.find('collision/geometry/cylinder') is not None}
    left, right = [], []
    for name, kind, _, child in joints:
        if kind in robot_model.WHEEL_JOINT_TYPES and child in cylinders and child in poses:
            y = float(poses[child][1, 3])
            (left if y > 0 else right if y < 0 else []).append(name)
    return sorted(left), sorted(right)
