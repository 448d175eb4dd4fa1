"""World files: the YAML format, its validating loader, and where moving obstacles are at a time.

A world file describes the ground, the robot's start pose and a list of obstacles (boxes, cylinders
and walls, which become boxes). Units and axes follow REP 103: metres, radians, x forward, y left,
z up, yaw counter-clockwise about +z. The format is documented in docs/simulator.md; in short::

    name: wall
    description: "A wall 3 m ahead"
    ground: {color: [0.55, 0.55, 0.55, 1.0]}
    robot: {start: {x: 0.0, y: 0.0, yaw: 0.0}}
    obstacles:
      - {name: front_wall, type: box, position: [3.05, 0.0], size: [0.1, 4.0, 1.0]}

or, for several robots in one world, each named (its ROS namespace and TF prefix), with its robot
profile and start::

    robots:
      - {name: r1, profile: closed_loop, start: {x: 0.0, y: 0.0, yaw: 0.0}}
      - {name: r2, profile: burger, start: {x: 4.0, y: 0.0, yaw: 3.14159}}

Validation is strict (a typo otherwise shows up as a robot that behaves oddly): unknown or duplicate keys,
non-finite numbers and numbers given as strings or booleans are errors, each a :class:`WorldError` naming the
file, the field and what was expected. A map_server map and a Gazebo world are worlds too (load_world).
ROS-free: the standard library and PyYAML.
"""
import dataclasses
import math
import os
from dataclasses import dataclass
from typing import Optional, Tuple

from closed_loop.geometry import Pose2D  # noqa: F401  (a world's start and goal poses; closed_loop.sim.world.Pose2D)
from closed_loop.sim import gazebo_world, occupancy_map, shapes
from closed_loop.sim.world_robots import RobotSpec, check_robots_apart, check_start, parse_robots
from closed_loop.yaml_check import Checker, FileError, load_yaml, read_text

#: Limits checked before anything is built, so a wrong file (a log, a binary, a generated monster) is
#: refused in moments rather than loaded for minutes: the largest world file (bytes) and the most
#: obstacles. A world at the limits loads in about 2 s.
MAX_WORLD_FILE_BYTES = 1024 * 1024
MAX_OBSTACLES = 2000

DEFAULT_GROUND_COLOR = (0.55, 0.55, 0.55, 1.0)
DEFAULT_OBSTACLE_COLOR = (0.5, 0.5, 0.5, 1.0)
DEFAULT_WALL_THICKNESS_M = 0.1
DEFAULT_WALL_HEIGHT_M = 1.0

#: Colours that may be given by name (RGBA, each in [0, 1]). Red matches what the red-object
#: detector is tuned for; no other named colour is close to it in hue.
NAMED_COLORS = {
    'red': (0.9, 0.05, 0.05, 1.0),
    'green': (0.1, 0.7, 0.2, 1.0),
    'blue': (0.1, 0.25, 0.85, 1.0),
    'yellow': (0.95, 0.85, 0.1, 1.0),
    'orange': (1.0, 0.55, 0.0, 1.0),
    'white': (0.95, 0.95, 0.95, 1.0),
    'black': (0.05, 0.05, 0.05, 1.0),
    'grey': DEFAULT_OBSTACLE_COLOR,
    'gray': DEFAULT_OBSTACLE_COLOR,
}

OBSTACLE_TYPES = ('box', 'cylinder', 'wall')
WORLD_FILE_SUFFIX = '.yaml'

_TOP_KEYS = ('name', 'description', 'ground', 'robot', 'robots', 'goal', 'obstacles', 'map')
_MAP_KEYS = ('file', 'unknown', 'height')
_GOAL_KEYS = ('x', 'y')
_GROUND_KEYS = ('color',)
_ROBOT_KEYS = ('start',)
_START_KEYS = ('x', 'y', 'yaw')
_MOTION_KEYS = ('waypoints', 'speed', 'loop')
_COMMON_OBSTACLE_KEYS = ('name', 'type', 'color')
_OBSTACLE_KEYS = {
    'box': _COMMON_OBSTACLE_KEYS + ('position', 'size', 'yaw', 'motion'),
    'cylinder': _COMMON_OBSTACLE_KEYS + ('position', 'radius', 'height', 'motion'),
    'wall': _COMMON_OBSTACLE_KEYS + ('start', 'end', 'thickness', 'height'),
}

class WorldError(FileError):
    """A world file (or world name) is unusable.

    The message reads ``"<file>: <field path>: expected <what>, got <value>"``, for example
    ``"worlds/wall.yaml: obstacles[0].size: expected 3 numbers > 0 (m), got [0.1, 4.0]"``, on one line
    and quoting at most a short excerpt (:class:`closed_loop.yaml_check.FileError`).
    """


@dataclass(frozen=True)
class Motion:
    """How an obstacle moves: at ``speed`` (m/s) along its start position then ``waypoints``.

    ``loop`` True: start -> waypoints... -> back to start, repeated. False: back and forth
    (ping-pong) along start -> waypoints.
    """
    waypoints: Tuple[Tuple[float, float], ...]
    speed: float
    loop: bool


@dataclass(frozen=True)
class Obstacle:
    """One obstacle, already normalised: walls are boxes, every field is filled in.

    ``position`` is the centre (m) at time 0; ``size`` the full extents along the obstacle's own
    x, y, z (a cylinder's is ``(2r, 2r, h)``); ``yaw`` in rad (0 for cylinders); ``radius`` in m
    (0.0 for boxes); ``color`` RGBA in [0, 1]; ``motion`` None for a static obstacle.
    """
    name: str
    shape: str
    position: Tuple[float, float, float]
    yaw: float
    size: Tuple[float, float, float]
    radius: float
    color: Tuple[float, float, float, float]
    motion: Optional[Motion]


@dataclass(frozen=True)
class World:
    """A validated world: ``source`` is the file it came from, or ``"<string>"``."""
    name: str
    description: str
    source: str
    ground_color: Tuple[float, float, float, float]
    robot_start: Pose2D
    obstacles: Tuple[Obstacle, ...]
    #: The robots of a multi-robot world (``robots:``), in file order; empty for a world with one unnamed
    #: robot (``robot:``), whose start is ``robot_start``. With robots, ``robot_start`` is the first's.
    robots: Tuple[RobotSpec, ...] = ()
    #: Where a navigator should go (x, y in the world frame, m), if the world says (``goal:``); None if not.
    goal: Optional[Tuple[float, float]] = None
    #: What a world of another kind (a Gazebo world) had that is left out or approximated (closed_loop.sim.gazebo_world).
    left_out: Tuple[str, ...] = ()


# --- parsing -----------------------------------------------------------------------------------

class _WorldChecker(Checker):
    """The generic field checks, errors as WorldError, plus colours."""

    def __init__(self, source):
        Checker.__init__(self, source, WorldError)

    def color(self, value, field):
        """``[r, g, b, a]`` each in [0, 1], or a name from NAMED_COLORS."""
        what = '[r, g, b, a] with each in [0, 1], or one of the names %s' % ', '.join(NAMED_COLORS)
        if isinstance(value, str):
            if value not in NAMED_COLORS:
                self.fail(field, what, value)
            return NAMED_COLORS[value]
        rgba = self.numbers(value, field, (4,), what)
        if not all(0.0 <= c <= 1.0 for c in rgba):
            self.fail(field, what, value)
        return rgba


def parse_world(data, source='<string>', footprint=None, check_starts=True, derived=()):
    """Validate an already-loaded YAML object and return a :class:`World`.

    ``source`` names the file in error messages. Raises :class:`WorldError` on the first problem:
    a wrong type, an unknown key, a non-finite number, a size, radius, height, thickness or speed
    that is not > 0, a bad colour, duplicate obstacle names, a wall of zero length, motion on a
    wall, or a robot start pose where the robot would overlap an obstacle's footprint (moving
    obstacles at their start position): the robot is ``footprint`` (an object with x_min, x_max,
    y_min, y_max in m, e.g. :class:`closed_loop.robot_model.Footprint`) grown by ``START_MARGIN_M``,
    or, without one, a disk of ``ROBOT_CLEARANCE_RADIUS_M`` (both in ``closed_loop.sim.world_robots``). For a world with ``robots:``, ``footprint``
    is {robot name: footprint} (a robot missing from it is a disk), and no two robots may start
    overlapping. ``check_starts`` False skips the start checks (to read which robots a world has before
    their footprints are known). ``derived``: boxes (obstacles' fields) made from the file beside its own (the
    footprints of a Gazebo world's meshes), after them.
    """
    check = _WorldChecker(source)
    top = check.mapping(data, '(top level)', _TOP_KEYS)
    name = check.string(check.get(top, 'name', 'name'), 'name')
    description = top.get('description', '')
    if not isinstance(description, str):
        check.fail('description', 'a string', description)

    ground_color = DEFAULT_GROUND_COLOR
    if 'ground' in top:
        ground = check.mapping(top['ground'], 'ground', _GROUND_KEYS)
        if 'color' in ground:
            ground_color = check.color(ground['color'], 'ground.color')

    start = Pose2D(0.0, 0.0, 0.0)
    if 'robot' in top and 'robots' in top:
        check.fail('robots', 'either robot (one robot) or robots (several, named), not both', top['robots'])
    if 'robot' in top:
        robot = check.mapping(top['robot'], 'robot', _ROBOT_KEYS)
        if 'start' in robot:
            start = _parse_start(check, robot['start'], 'robot.start')
    robots = parse_robots(check, top['robots'], _parse_start, Pose2D(0.0, 0.0, 0.0)) if 'robots' in top else ()
    if robots:
        start = robots[0].start

    raw_obstacles = top.get('obstacles')
    if raw_obstacles is None:
        # "obstacles:" with every item commented out loads as None; that means no obstacles.
        raw_obstacles = []
    if not isinstance(raw_obstacles, list):
        check.fail('obstacles', 'a list of obstacles', raw_obstacles)
    if len(raw_obstacles) > MAX_OBSTACLES:
        check.fail('obstacles', 'at most %d obstacles' % MAX_OBSTACLES,
                   '%d obstacles' % len(raw_obstacles))
    obstacles = []
    seen = {}
    for index, raw in enumerate(raw_obstacles):
        field = 'obstacles[%d]' % index
        obstacle = _parse_obstacle(check, raw, field)
        if obstacle.name in seen:
            check.fail(field + '.name',
                       'a name not already used by obstacles[%d]' % seen[obstacle.name],
                       obstacle.name)
        seen[obstacle.name] = index
        obstacles.append(obstacle)
    if 'map' in top:
        obstacles += _map_obstacles(check, top['map'], source)
    obstacles += [Obstacle(shape=box.pop('type'), radius=0.0, motion=None, **box) for box in map(dict, derived)]

    goal = None
    if 'goal' in top:
        raw_goal = check.mapping(top['goal'], 'goal', _GOAL_KEYS)
        goal = tuple(check.number(check.get(raw_goal, k, 'goal.' + k), 'goal.' + k, 'a finite number (m)')
                     for k in _GOAL_KEYS)
        inside = [ob.name for ob in obstacles if ob.motion is None and shapes.distance(ob, *goal) <= 0.0]
        if inside:
            check.fail('goal', 'a point outside every obstacle', '%r, inside %s' % (list(goal), inside[0]))

    if not check_starts:
        pass
    elif robots:
        footprints = footprint if isinstance(footprint, dict) else {}
        for index, spec in enumerate(robots):
            check_start(check, obstacles, spec.start, footprints.get(spec.name), 'robots[%d].start' % index)
        check_robots_apart(check, robots, footprints)
    else:
        check_start(check, obstacles, start, None if isinstance(footprint, dict) else footprint, 'robot.start')

    return World(name=name, description=description, source=source, ground_color=ground_color,
                 robot_start=start, obstacles=tuple(obstacles), robots=robots, goal=goal)


def _parse_start(check, value, field):
    start = check.mapping(value, field, _START_KEYS)
    x = check.number(check.get(start, 'x', field + '.x'), field + '.x', 'a finite number (m)')
    y = check.number(check.get(start, 'y', field + '.y'), field + '.y', 'a finite number (m)')
    yaw = check.number(start.get('yaw', 0.0), field + '.yaw', 'a finite number (rad)')
    return Pose2D(x, y, yaw)


def _parse_obstacle(check, raw, field):
    if not isinstance(raw, dict):
        check.fail(field, 'a mapping (an obstacle)', raw)
    # The type decides which keys are allowed, so it is checked first.
    kind = check.get(raw, 'type', field + '.type')
    if kind not in OBSTACLE_TYPES:
        check.fail(field + '.type', 'one of %s' % ', '.join(OBSTACLE_TYPES), kind)
    if kind == 'wall' and 'motion' in raw:
        check.fail(field + '.motion', 'no motion on a wall (walls are static; use a box to move)',
                   raw['motion'])
    check.mapping(raw, field, _OBSTACLE_KEYS[kind])
    name = check.string(check.get(raw, 'name', field + '.name'), field + '.name')
    color = DEFAULT_OBSTACLE_COLOR
    if 'color' in raw:
        color = check.color(raw['color'], field + '.color')

    if kind == 'wall':
        return _parse_wall(check, raw, field, name, color)

    if kind == 'box':
        size = check.numbers(check.get(raw, 'size', field + '.size'), field + '.size', (3,),
                             '[x, y, z]: 3 numbers > 0 (m, full extents)', positive=True)
        yaw = check.number(raw.get('yaw', 0.0), field + '.yaw', 'a finite number (rad)')
        radius = 0.0
    else:
        radius = check.number(check.get(raw, 'radius', field + '.radius'), field + '.radius',
                              'a finite number > 0 (m)', positive=True)
        height = check.number(check.get(raw, 'height', field + '.height'), field + '.height',
                              'a finite number > 0 (m)', positive=True)
        size = (2.0 * radius, 2.0 * radius, height)
        yaw = 0.0

    xyz = check.numbers(check.get(raw, 'position', field + '.position'), field + '.position',
                        (2, 3), '[x, y] or [x, y, z]: finite numbers (m)')
    position = xyz if len(xyz) == 3 else (xyz[0], xyz[1], size[2] / 2.0)

    motion = None
    if 'motion' in raw:
        motion = _parse_motion(check, raw['motion'], field + '.motion', (position[0], position[1]))
    return Obstacle(name=name, shape=kind, position=position, yaw=yaw, size=size, radius=radius,
                    color=color, motion=motion)


def _map_obstacles(check, value, source):
    """The static boxes of a map_server map (``map: {file, unknown, height}``: closed_loop.sim.occupancy_map)."""
    raw = check.mapping(value, 'map', _MAP_KEYS)
    name = check.string(check.get(raw, 'file', 'map.file'), 'map.file')
    path = name if os.path.isabs(name) else os.path.join(os.path.dirname(os.path.abspath(source)), name)
    unknown = raw.get('unknown', 'obstacle')
    if unknown not in ('obstacle', 'free'):
        check.fail('map.unknown', 'obstacle or free (what the map has not seen)', unknown)
    height = check.number(raw.get('height', DEFAULT_WALL_HEIGHT_M), 'map.height', 'a finite number > 0 (m)',
                          positive=True)
    cells, resolution, origin = occupancy_map.read_map(path, WorldError)
    boxes = occupancy_map.map_boxes(cells, resolution, origin, unknown == 'obstacle', height,
                                    error=lambda what, got: check.fail('map.file', what, got))
    return [Obstacle(shape='box', radius=0.0, color=occupancy_map.MAP_COLOR, motion=None, **box) for box in boxes]


def _parse_wall(check, raw, field, name, color):
    """A wall is a box along its centre line from ``start`` to ``end``, standing on the ground."""
    point = '[x, y]: 2 finite numbers (m)'
    start = check.numbers(check.get(raw, 'start', field + '.start'), field + '.start', (2,),
                          point)
    end = check.numbers(check.get(raw, 'end', field + '.end'), field + '.end', (2,), point)
    thickness = check.number(raw.get('thickness', DEFAULT_WALL_THICKNESS_M), field + '.thickness',
                             'a finite number > 0 (m)', positive=True)
    height = check.number(raw.get('height', DEFAULT_WALL_HEIGHT_M), field + '.height',
                          'a finite number > 0 (m)', positive=True)
    length = math.hypot(end[0] - start[0], end[1] - start[1])
    if not length > 0.0:
        check.fail(field + '.end', 'a point different from start %r' % (list(start),), list(end))
    centre = ((start[0] + end[0]) / 2.0, (start[1] + end[1]) / 2.0, height / 2.0)
    yaw = math.atan2(end[1] - start[1], end[0] - start[0])
    return Obstacle(name=name, shape='box', position=centre, yaw=yaw,
                    size=(length, thickness, height), radius=0.0, color=color, motion=None)


def _parse_motion(check, value, field, origin):
    motion = check.mapping(value, field, _MOTION_KEYS)
    raw_points = check.get(motion, 'waypoints', field + '.waypoints')
    if not isinstance(raw_points, list) or not raw_points:
        check.fail(field + '.waypoints', 'a list of at least one point [x, y] (m)', raw_points)
    points = tuple(check.numbers(p, '%s.waypoints[%d]' % (field, i), (2,),
                                 '[x, y]: 2 finite numbers (m)')
                   for i, p in enumerate(raw_points))
    if all(p == origin for p in points):
        # A path of zero length would make the obstacle silently static.
        check.fail(field + '.waypoints', 'at least one point away from the position %r'
                   % (list(origin),), raw_points)
    speed = check.number(check.get(motion, 'speed', field + '.speed'), field + '.speed',
                         'a finite number > 0 (m/s)', positive=True)
    loop = motion.get('loop', True)
    if not isinstance(loop, bool):
        check.fail(field + '.loop', 'true or false', loop)
    return Motion(waypoints=points, speed=speed, loop=loop)


# --- files and names ---------------------------------------------------------------------------

def load_world(path, footprint=None, check_starts=True):
    """Read the world file at ``path`` and return a :class:`World` (``source`` is ``path``).

    A missing or unreadable file, one over ``MAX_WORLD_FILE_BYTES``, a YAML syntax error (with its
    line) and every problem :func:`parse_world` finds (more than ``MAX_OBSTACLES`` obstacles among
    them) raise :class:`WorldError`, whose message is one line and quotes at most a short excerpt. A
    map_server map's YAML file is a world of its cells, the robot at (0, 0) (:mod:`closed_loop.sim.occupancy_map`).
    """
    path = os.fspath(path)
    text = read_text(path, MAX_WORLD_FILE_BYTES, WorldError, 'world file')
    if gazebo_world.is_gazebo_world(path):      # its static shapes, the robot at its origin
        data, left_out, derived = gazebo_world.world_data(path, text, WorldError)
        return dataclasses.replace(parse_world(data, path, footprint, check_starts, derived), left_out=left_out)
    data = load_yaml(text, path, WorldError)
    if occupancy_map.is_map(data):          # a map_server map as it is: its cells, the robot at its origin
        data = {'name': os.path.splitext(os.path.basename(path))[0], 'map': {'file': os.path.abspath(path)},
                'description': 'the map %s (unknown cells are obstacles)' % path}
    return parse_world(data, path, footprint, check_starts)


def available_worlds(worlds_dir):
    """The names (file stems) of the ``*.yaml`` worlds in ``worlds_dir``, sorted; [] if none."""
    try:
        entries = os.listdir(worlds_dir)
    except OSError:
        return []
    return sorted(entry[:-len(WORLD_FILE_SUFFIX)] for entry in entries
                  if entry.endswith(WORLD_FILE_SUFFIX)
                  and os.path.isfile(os.path.join(worlds_dir, entry)))


def resolve_world(name_or_path, worlds_dir):
    """The file for a world given by name (``'wall'`` -> ``<worlds_dir>/wall.yaml``) or by path.

    An existing file path is returned unchanged. Anything else is looked up as a name in
    ``worlds_dir``; an unknown name raises :class:`WorldError` listing the available names.
    """
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise WorldError(os.fspath(worlds_dir), 'world', 'a world name or a path to a world file',
                         name_or_path)
    name_or_path = os.fspath(name_or_path)
    if name_or_path and os.path.isfile(name_or_path):
        return name_or_path
    candidate = os.path.join(worlds_dir, name_or_path + WORLD_FILE_SUFFIX)
    if name_or_path and os.sep not in name_or_path and os.path.isfile(candidate):
        return candidate
    names = available_worlds(worlds_dir)
    raise WorldError(os.fspath(worlds_dir), 'world',
                     'an existing world file or one of the world names (%s)'
                     % (', '.join(names) if names else 'none found'), name_or_path)
