"""Who starts where in a world file: the ``robots:`` list of a multi-robot world (names, profiles, starts),
and the checks that every robot starts clear of the obstacles and of the other robots, with its own
footprint where it is known. Used by ``closed_loop.sim.world``; errors go through its field checker, so they
name the file and the field. Free of ROS.
"""
import dataclasses
import math
import re
from dataclasses import dataclass

from closed_loop.sim.obstacles import disk_overlaps, footprint_overlaps
from closed_loop.sim.shapes import robot_corners, separated
from closed_loop.geometry import Pose2D
from closed_loop.yaml_check import Checker

#: The robot as seen by the start-pose check when its footprint is not known (a world checked on its
#: own): a disk of this radius (m) around base_footprint. With the robot's footprint (the simulator
#: passes the rectangle from its URDF), the check is that rectangle grown by START_MARGIN_M.
ROBOT_CLEARANCE_RADIUS_M = 0.25
START_MARGIN_M = 0.05

_ROBOTS_KEYS = ('name', 'profile', 'start')
#: A robot's name becomes its ROS namespace and TF prefix; a profile names files (urdf/NAME.urdf).
ROBOT_NAME = re.compile(r'^[A-Za-z][A-Za-z0-9_]*$')
PROFILE_NAME = re.compile(r'^[A-Za-z0-9_]+$')
DEFAULT_PROFILE = 'closed_loop'
MAX_ROBOTS = 16


@dataclass(frozen=True)
class RobotSpec:
    """One robot of a multi-robot world: its name (its ROS namespace and TF prefix), its robot profile
    (urdf/PROFILE.urdf, config/robots/PROFILE.yaml) and its start pose."""
    name: str
    profile: str
    start: object      # closed_loop.sim.world.Pose2D


def parse_robots(check, value, parse_start, default_start):
    """The ``robots:`` list as RobotSpecs (``check``: the world's field checker; ``parse_start(check, value,
    field)`` reads a start pose)."""
    if not isinstance(value, list) or not value:
        check.fail('robots', 'a list of at least one robot {name, profile, start}', value)
    if len(value) > MAX_ROBOTS:
        check.fail('robots', 'at most %d robots' % MAX_ROBOTS, '%d robots' % len(value))
    robots, seen = [], {}
    for index, raw in enumerate(value):
        field = 'robots[%d]' % index
        robot = check.mapping(raw, field, _ROBOTS_KEYS)
        name = check.get(robot, 'name', field + '.name')
        if not isinstance(name, str) or not ROBOT_NAME.match(name):
            check.fail(field + '.name', 'a name of letters, digits and _, starting with a letter (it becomes '
                       'the namespace and TF prefix)', name)
        if name in seen:
            check.fail(field + '.name', 'a name not already used by robots[%d]' % seen[name], name)
        seen[name] = index
        profile = robot.get('profile', DEFAULT_PROFILE)
        if not isinstance(profile, str) or not (PROFILE_NAME.match(profile) or profile.endswith(('.yaml', '.yml'))):
            check.fail(field + '.profile', 'a robot profile name (letters, digits, _; urdf/NAME.urdf), or a profile '
                       'file of yours (.yaml: a path or PKG/path)', profile)
        start = parse_start(check, robot['start'], field + '.start') if 'start' in robot else default_start
        robots.append(RobotSpec(name, profile, start))
    return tuple(robots)


def check_start(check, obstacles, start, footprint, field):
    """The robot at ``start`` (its ``footprint`` plus START_MARGIN_M, or a disk without one) is clear of
    every obstacle (moving ones at their start)."""
    for index, obstacle in enumerate(obstacles):
        if footprint is None and disk_overlaps(obstacle, start.x, start.y, ROBOT_CLEARANCE_RADIUS_M):
            check.fail(field,
                       'a pose at least %g m (the robot clearance radius) from obstacles[%d] %r'
                       % (ROBOT_CLEARANCE_RADIUS_M, index, obstacle.name),
                       {'x': start.x, 'y': start.y, 'yaw': start.yaw})
        if footprint is not None and footprint_overlaps(obstacle, start, footprint, START_MARGIN_M):
            check.fail(field,
                       'a pose where the robot (%.2f x %.2f m, plus %g m) is clear of obstacles[%d] %r'
                       % (footprint.x_max - footprint.x_min, footprint.y_max - footprint.y_min,
                          START_MARGIN_M, index, obstacle.name),
                       {'x': start.x, 'y': start.y, 'yaw': start.yaw})


def _rect(footprint):
    """The rectangle (x_min, x_max, y_min, y_max) a robot is checked with: its footprint plus the margin,
    or the square around the clearance disk without one."""
    if footprint is None:
        r = ROBOT_CLEARANCE_RADIUS_M
        return (-r, r, -r, r)
    m = START_MARGIN_M
    return (footprint.x_min - m, footprint.x_max + m, footprint.y_min - m, footprint.y_max + m)


def check_robots_apart(check, robots, footprints):
    """No two robots start overlapping."""
    for i, a in enumerate(robots):
        for j in range(i):
            b = robots[j]
            if not separated(robot_corners(a.start, _rect(footprints.get(a.name))),
                             robot_corners(b.start, _rect(footprints.get(b.name)))):
                check.fail('robots[%d].start' % i, 'a pose clear of robots[%d] %r' % (j, b.name),
                           {'x': a.start.x, 'y': a.start.y, 'yaw': a.start.yaw})


def with_start(world, start, footprint, error_class, field='start'):
    """``world`` (one robot) with its robot starting at ``start`` ((x, y, yaw): m, m, rad, in the world frame)
    in place of where its file says (a map's world says nothing: the origin), checked clear of the obstacles as a
    start in the file is; an error (``error_class``, naming the world's file and ``field``) otherwise."""
    check = Checker(world.source, error_class)
    if world.robots:
        check.fail(field, 'a world of one robot (a world with robots: gives each its start there)', start)
    if not isinstance(start, (list, tuple)) or len(start) != 3 or not all(
            isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in start):
        check.fail(field, '[x, y, yaw]: 3 finite numbers (m, m, rad)', start)
    pose = Pose2D(*(float(v) for v in start))
    check_start(check, world.obstacles, pose, footprint, field)
    return dataclasses.replace(world, robot_start=pose)
