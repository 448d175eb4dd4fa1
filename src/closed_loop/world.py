"""World files: the YAML format, its validating loader, and where moving obstacles are at a time.

A world file describes the ground, the robot's start pose and a list of obstacles (boxes, cylinders
and walls, which become boxes). Units and axes follow REP 103: metres, radians, x forward, y left,
z up, yaw counter-clockwise about +z. The format is documented in the README; in short::

    name: wall
    description: "A wall 3 m ahead"
    ground: {color: [0.55, 0.55, 0.55, 1.0]}
    robot: {start: {x: 0.0, y: 0.0, yaw: 0.0}}
    obstacles:
      - {name: front_wall, type: box, position: [3.05, 0.0], size: [0.1, 4.0, 1.0]}

Validation is strict because a typo in a world file otherwise shows up as a robot that behaves
oddly: unknown keys, duplicate keys, non-finite numbers and numbers given as strings or booleans are
all errors. Every error is a :class:`WorldError` whose message names the file, the field and what
was expected.

This module is ROS-free: it needs only the standard library and PyYAML.
"""
import math
import os
from dataclasses import dataclass
from typing import Optional, Tuple

import yaml

from closed_loop.obstacles import disk_overlaps, footprint_overlaps

#: The robot as seen by the start-pose check when its footprint is not known (a world checked on its
#: own): a disk of this radius (m) around base_footprint. With the robot's footprint (the simulator
#: passes the rectangle from its URDF), the check is that rectangle grown by START_MARGIN_M.
ROBOT_CLEARANCE_RADIUS_M = 0.25
START_MARGIN_M = 0.05

#: Limits checked before anything is built, so a wrong file (a log, a binary, a generated monster) is
#: refused in moments rather than loaded for minutes: the largest world file (bytes) and the most
#: obstacles. A world at the limits loads in about 2 s.
MAX_WORLD_FILE_BYTES = 1024 * 1024
MAX_OBSTACLES = 2000
#: At most this many characters of an offending value are quoted in an error message.
MAX_QUOTE_CHARS = 120

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

_TOP_KEYS = ('name', 'description', 'ground', 'robot', 'obstacles')
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

# Marks a required key that is absent, so messages can say so instead of printing a value.
_MISSING = object()


class WorldError(ValueError):
    """A world file (or world name) is unusable.

    The message reads ``"<file>: <field path>: expected <what>, got <value!r>"``, for example
    ``"worlds/wall.yaml: obstacles[0].size: expected 3 numbers > 0 (m), got [0.1, 4.0]"``.
    The parts are kept as attributes ``source``, ``field``, ``expected`` and ``got`` (the
    offending value, or None when the field is missing).
    """

    def __init__(self, source, field, expected, got=_MISSING):
        self.source = source
        self.field = field
        self.expected = expected
        self.got = None if got is _MISSING else got
        told = 'nothing (the key is missing)' if got is _MISSING else quote(got)
        super().__init__('%s: %s: expected %s, got %s' % (source, field, expected, told))


def quote(value, limit=MAX_QUOTE_CHARS):
    """``repr(value)`` on one line, cut to ``limit`` characters with the total length said."""
    text = repr(value)
    if len(text) <= limit:
        return text
    return '%s... (%d characters in all)' % (text[:limit], len(text))


@dataclass(frozen=True)
class Pose2D:
    """A pose on the ground plane: x, y in m, yaw in rad (counter-clockwise from +x)."""
    x: float
    y: float
    yaw: float


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


# --- YAML reading ------------------------------------------------------------------------------

_MERGE_TAG = 'tag:yaml.org,2002:merge'


class _StrictLoader(yaml.SafeLoader):
    """PyYAML's safe loader, except that a key repeated in one mapping is an error.

    PyYAML keeps the last of two equal keys without a word, which hides typos such as an obstacle
    given two ``position`` lines.
    """

    def construct_mapping(self, node, deep=False):
        if isinstance(node, yaml.MappingNode):
            seen = set()
            for key_node, _ in node.value:
                # Merge keys (<<) may legitimately repeat keys; only literal keys are checked.
                if not isinstance(key_node, yaml.ScalarNode) or key_node.tag == _MERGE_TAG:
                    continue
                key = self.construct_object(key_node, deep=True)
                if key in seen:
                    raise yaml.constructor.ConstructorError(
                        'while constructing a mapping', node.start_mark,
                        'found duplicate key %r' % (key,), key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)


def _load_yaml(text, source):
    """Parse YAML ``text``; a syntax error becomes a WorldError naming ``source`` and the line."""
    try:
        return yaml.load(text, Loader=_StrictLoader)
    except yaml.MarkedYAMLError as error:
        mark = error.problem_mark or error.context_mark
        where = 'line %d, column %d' % (mark.line + 1, mark.column + 1) if mark else 'somewhere'
        problem = error.problem or error.context or 'a syntax error'
        if error.context and error.context_mark and error.context_mark is not mark:
            # The start of the unclosed bracket or block is often the real culprit.
            problem = '%s (%s started on line %d)' % (problem, error.context,
                                                      error.context_mark.line + 1)
        raise WorldError(source, where, 'valid YAML', problem) from None
    except yaml.YAMLError as error:
        raise WorldError(source, '(file)', 'valid YAML', str(error)) from None


# --- field checks ------------------------------------------------------------------------------

class _Checker:
    """Field checks that all report errors against one source file."""

    def __init__(self, source):
        self.source = source

    def fail(self, field, expected, got=_MISSING):
        raise WorldError(self.source, field, expected, got)

    def mapping(self, value, field, allowed):
        """``value`` must be a mapping whose keys are all in ``allowed``."""
        if not isinstance(value, dict):
            self.fail(field, 'a mapping', value)
        for key in value:
            if key not in allowed:
                sub = '%s.%s' % (field, key) if field != '(top level)' else str(key)
                self.fail(sub, 'a known key (%s)' % ', '.join(allowed), key)
        return value

    def number(self, value, field, what='a finite number', positive=False):
        """A finite int or float (not a bool, not a string), as float; ``positive``: also > 0."""
        number = _finite_float(value)
        if number is None or (positive and not number > 0.0):
            self.fail(field, what, value)
        return number

    def string(self, value, field):
        if not isinstance(value, str) or not value.strip():
            self.fail(field, 'a non-empty string', value)
        return value

    def numbers(self, value, field, counts, what, positive=False):
        """A list of ``counts`` (a tuple of allowed lengths) numbers, as a tuple of floats."""
        if not isinstance(value, (list, tuple)) or len(value) not in counts:
            self.fail(field, what, value)
        numbers = tuple(_finite_float(item) for item in value)
        # Report the whole list: "got [1.0, nan]" is clearer than an index into it.
        if any(n is None or (positive and not n > 0.0) for n in numbers):
            self.fail(field, what, value)
        return numbers

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


def _finite_float(value):
    """``value`` as a float if it is a finite int or float, else None.

    Booleans are refused although Python counts them as ints (``size: [true, 1, 1]`` is a typo,
    not 1.0), and so are strings: YAML 1.1 reads ``1e3`` (no dot) as a string.
    """
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if math.isfinite(number) else None


def _get(checker, data, key, field, default=_MISSING):
    """``data[key]``, or ``default``; a missing required key (no default) is an error."""
    if key in data:
        return data[key]
    if default is _MISSING:
        checker.fail(field, 'a value for the required key %r' % key)
    return default


# --- parsing -----------------------------------------------------------------------------------

def parse_world(data, source='<string>', footprint=None):
    """Validate an already-loaded YAML object and return a :class:`World`.

    ``source`` names the file in error messages. Raises :class:`WorldError` on the first problem:
    a wrong type, an unknown key, a non-finite number, a size, radius, height, thickness or speed
    that is not > 0, a bad colour, duplicate obstacle names, a wall of zero length, motion on a
    wall, or a robot start pose where the robot would overlap an obstacle's footprint (moving
    obstacles at their start position): the robot is ``footprint`` (an object with x_min, x_max,
    y_min, y_max in m, e.g. :class:`closed_loop.robot_model.Footprint`) grown by ``START_MARGIN_M``,
    or, without one, a disk of ``ROBOT_CLEARANCE_RADIUS_M``.
    """
    check = _Checker(source)
    top = check.mapping(data, '(top level)', _TOP_KEYS)
    name = check.string(_get(check, top, 'name', 'name'), 'name')
    description = top.get('description', '')
    if not isinstance(description, str):
        check.fail('description', 'a string', description)

    ground_color = DEFAULT_GROUND_COLOR
    if 'ground' in top:
        ground = check.mapping(top['ground'], 'ground', _GROUND_KEYS)
        if 'color' in ground:
            ground_color = check.color(ground['color'], 'ground.color')

    start = Pose2D(0.0, 0.0, 0.0)
    if 'robot' in top:
        robot = check.mapping(top['robot'], 'robot', _ROBOT_KEYS)
        if 'start' in robot:
            start = _parse_start(check, robot['start'], 'robot.start')

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

    for index, obstacle in enumerate(obstacles):
        if footprint is None and disk_overlaps(obstacle, start.x, start.y, ROBOT_CLEARANCE_RADIUS_M):
            check.fail('robot.start',
                       'a pose at least %g m (the robot clearance radius) from obstacles[%d] %r'
                       % (ROBOT_CLEARANCE_RADIUS_M, index, obstacle.name),
                       {'x': start.x, 'y': start.y, 'yaw': start.yaw})
        if footprint is not None and footprint_overlaps(obstacle, start, footprint, START_MARGIN_M):
            check.fail('robot.start',
                       'a pose where the robot (%.2f x %.2f m, plus %g m) is clear of obstacles[%d] %r'
                       % (footprint.x_max - footprint.x_min, footprint.y_max - footprint.y_min,
                          START_MARGIN_M, index, obstacle.name),
                       {'x': start.x, 'y': start.y, 'yaw': start.yaw})

    return World(name=name, description=description, source=source, ground_color=ground_color,
                 robot_start=start, obstacles=tuple(obstacles))


def _parse_start(check, value, field):
    start = check.mapping(value, field, _START_KEYS)
    x = check.number(_get(check, start, 'x', field + '.x'), field + '.x', 'a finite number (m)')
    y = check.number(_get(check, start, 'y', field + '.y'), field + '.y', 'a finite number (m)')
    yaw = check.number(start.get('yaw', 0.0), field + '.yaw', 'a finite number (rad)')
    return Pose2D(x, y, yaw)


def _parse_obstacle(check, raw, field):
    if not isinstance(raw, dict):
        check.fail(field, 'a mapping (an obstacle)', raw)
    # The type decides which keys are allowed, so it is checked first.
    kind = _get(check, raw, 'type', field + '.type')
    if kind not in OBSTACLE_TYPES:
        check.fail(field + '.type', 'one of %s' % ', '.join(OBSTACLE_TYPES), kind)
    if kind == 'wall' and 'motion' in raw:
        check.fail(field + '.motion', 'no motion on a wall (walls are static; use a box to move)',
                   raw['motion'])
    check.mapping(raw, field, _OBSTACLE_KEYS[kind])
    name = check.string(_get(check, raw, 'name', field + '.name'), field + '.name')
    color = DEFAULT_OBSTACLE_COLOR
    if 'color' in raw:
        color = check.color(raw['color'], field + '.color')

    if kind == 'wall':
        return _parse_wall(check, raw, field, name, color)

    if kind == 'box':
        size = check.numbers(_get(check, raw, 'size', field + '.size'), field + '.size', (3,),
                             '[x, y, z]: 3 numbers > 0 (m, full extents)', positive=True)
        yaw = check.number(raw.get('yaw', 0.0), field + '.yaw', 'a finite number (rad)')
        radius = 0.0
    else:
        radius = check.number(_get(check, raw, 'radius', field + '.radius'), field + '.radius',
                              'a finite number > 0 (m)', positive=True)
        height = check.number(_get(check, raw, 'height', field + '.height'), field + '.height',
                              'a finite number > 0 (m)', positive=True)
        size = (2.0 * radius, 2.0 * radius, height)
        yaw = 0.0

    xyz = check.numbers(_get(check, raw, 'position', field + '.position'), field + '.position',
                        (2, 3), '[x, y] or [x, y, z]: finite numbers (m)')
    position = xyz if len(xyz) == 3 else (xyz[0], xyz[1], size[2] / 2.0)

    motion = None
    if 'motion' in raw:
        motion = _parse_motion(check, raw['motion'], field + '.motion', (position[0], position[1]))
    return Obstacle(name=name, shape=kind, position=position, yaw=yaw, size=size, radius=radius,
                    color=color, motion=motion)


def _parse_wall(check, raw, field, name, color):
    """A wall is a box along its centre line from ``start`` to ``end``, standing on the ground."""
    point = '[x, y]: 2 finite numbers (m)'
    start = check.numbers(_get(check, raw, 'start', field + '.start'), field + '.start', (2,),
                          point)
    end = check.numbers(_get(check, raw, 'end', field + '.end'), field + '.end', (2,), point)
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
    raw_points = _get(check, motion, 'waypoints', field + '.waypoints')
    if not isinstance(raw_points, list) or not raw_points:
        check.fail(field + '.waypoints', 'a list of at least one point [x, y] (m)', raw_points)
    points = tuple(check.numbers(p, '%s.waypoints[%d]' % (field, i), (2,),
                                 '[x, y]: 2 finite numbers (m)')
                   for i, p in enumerate(raw_points))
    if all(p == origin for p in points):
        # A path of zero length would make the obstacle silently static.
        check.fail(field + '.waypoints', 'at least one point away from the position %r'
                   % (list(origin),), raw_points)
    speed = check.number(_get(check, motion, 'speed', field + '.speed'), field + '.speed',
                         'a finite number > 0 (m/s)', positive=True)
    loop = motion.get('loop', True)
    if not isinstance(loop, bool):
        check.fail(field + '.loop', 'true or false', loop)
    return Motion(waypoints=points, speed=speed, loop=loop)


# --- files and names ---------------------------------------------------------------------------

def load_world(path, footprint=None):
    """Read the world file at ``path`` and return a :class:`World` (``source`` is ``path``).

    A missing or unreadable file, one over ``MAX_WORLD_FILE_BYTES``, a YAML syntax error (with its
    line) and every problem :func:`parse_world` finds (more than ``MAX_OBSTACLES`` obstacles among
    them) raise :class:`WorldError`, whose message is one line and quotes at most a short excerpt.
    """
    path = os.fspath(path)
    try:
        with open(path, 'r', encoding='utf-8') as stream:
            size = os.fstat(stream.fileno()).st_size
            if size > MAX_WORLD_FILE_BYTES:
                raise WorldError(path, '(file)', 'a world file of at most %d bytes' % MAX_WORLD_FILE_BYTES,
                                 '%d bytes' % size)
            # One byte more than the limit tells a file that grows (or a pipe) from one that fits.
            text = stream.read(MAX_WORLD_FILE_BYTES + 1)
            if len(text.encode('utf-8')) > MAX_WORLD_FILE_BYTES:
                raise WorldError(path, '(file)', 'a world file of at most %d bytes'
                                 % MAX_WORLD_FILE_BYTES, 'more')
    except OSError as error:
        raise WorldError(path, '(file)', 'a readable world file',
                         error.strerror or str(error)) from None
    except UnicodeDecodeError as error:
        raise WorldError(path, '(file)', 'UTF-8 text', str(error)) from None
    return parse_world(_load_yaml(text, path), path, footprint)


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
