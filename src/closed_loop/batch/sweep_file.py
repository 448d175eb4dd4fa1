"""Sweep files: a grid of episodes (``closed_loop.batch.episode.EpisodeSpec``) in YAML, checked before anything
runs. Free of ROS.

.. code-block:: yaml

    name: stop_threshold            # names the output directory (letters, digits, _ and -)
    base:                           # EpisodeSpec fields every episode shares
      world: wall
      controller: stop_on_obstacle
      time_limit_s: 20
    grid:                           # every combination of these is one episode
      settings.stop_distance: {from: 0.1, to: 0.6, step: 0.1}
      settings.cruise_speed: [0.3, 0.5, 1.0]
      seed: {from: 0, to: 4, step: 1}
      scan_noise: [0.0, 0.01]
    plot: {x: settings.stop_distance, lines: settings.cruise_speed}     # optional
    report: {pictures: failures, max_pictures: 100}                     # optional; these are the defaults

A grid key is an EpisodeSpec field (``world``, ``robot``, ``controller``, ``seed``, ``scan_noise``,
``goal``, ``time_limit_s``, ...), or ``settings.NAME`` (a controller ``~parameter``), ``sim.NAME`` (a
simulator or sensor ``~parameter``), ``args.NAME`` (an arg of a graph controller's launch file,
``controller: {launch: PKG/path.launch}``) or ``world.generator.NAME`` (a generated world's ``method`` or
setting, ``closed_loop.sim.generators``). Its values are a list, or ``{from, to, step}`` (both ends
included). Each distinct value of each key is then checked as an episode would be (the controller's settings
by the class its node uses, the world loaded or its generator's settings checked), and every combination of
a grid of at most :data:`CHECK_ALL`; the first problem is an error that names the file, the field and what
was expected. The combinations are made lazily (:class:`Grid`); those of a larger grid are checked as their
episodes are made.

``report``: which episodes get a picture (``closed_loop.batch.pictures``), drawn where the episode ran:
``pictures: failures`` (those not as meant: collided, failed, timed out, error, or any contact), ``all`` or
``none``; at most ``max_pictures`` of them (the first to finish), the rest on request with ``rosrun
closed_loop episode_plot OUTPUT INDEX``.
"""
import itertools
import math
import os
import re
import time

import yaml

from closed_loop import paths
from closed_loop.batch.episode import EpisodeError, EpisodeSpec, prepare
from closed_loop.yaml_check import Checker, FileError, load_yaml, quote, read_text

SPEC_FIELDS = tuple(EpisodeSpec.__dataclass_fields__)
NAME_PATTERN = re.compile(r'^[A-Za-z0-9_-]{1,64}$')
#: A sweep file's keys, and its largest size (bytes).
TOP_KEYS, MAX_FILE_BYTES = ('name', 'base', 'grid', 'plot', 'report'), 1024 * 1024
#: Keys of a grid (or a search's space) that place the robot's start and its goal, a coordinate each.
POSE_KEYS = ('start.x', 'start.y', 'start.yaw', 'goal.x', 'goal.y')
#: The catkin workspace a graph controller's launch file comes from (``closed_loop.batch.workspace``).
WORKSPACE_KEY = 'controller.workspace'
#: A grid may not have more combinations than this (a typo in a range should not start a million).
MAX_EPISODES = 1000000
#: A grid of at most this many combinations has each one checked before anything runs (about 0.2 ms each);
#: a larger one has each key's values checked, and its combinations as their episodes are made.
CHECK_ALL = 10000
#: How often a long check says how far it is (s).
PROGRESS_S = 1.0
#: ``report:`` when a sweep file does not say; a picture is about 40 kB and 0.2 s of a worker's time.
REPORT_DEFAULTS = {'pictures': 'failures', 'max_pictures': 100}
PICTURE_CHOICES = ('failures', 'all', 'none')
#: The sweeps this package ships, each run by its name (``rosrun closed_loop sweep stop_thresholds``): NAME.yaml here.
SHIPPED = ('config', 'sweeps')


class SweepError(ValueError):
    """A sweep file that cannot be run; the message names the file, the field and what was expected."""


def _values(source, key, raw):
    where = '%s: grid.%s' % (source, key)
    if isinstance(raw, dict):
        if set(raw) != {'from', 'to', 'step'}:
            raise SweepError('%s: expected a list of values or {from, to, step}, got %s' % (where, quote(raw)))
        a, b, step = raw['from'], raw['to'], raw['step']
        for name, value in (('from', a), ('to', b), ('step', step)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SweepError('%s.%s: expected a number, got %s' % (where, name, quote(value)))
        if not step > 0 or b < a:
            raise SweepError('%s: expected step > 0 and to >= from, got %s' % (where, quote(raw)))
        count = int(math.floor((b - a) / step + 1e-9)) + 1
        if count > MAX_EPISODES:
            raise SweepError('%s: %d values is too many' % (where, count))
        return Range(a, step, count)
    if not isinstance(raw, list) or not raw:
        raise SweepError('%s: expected a non-empty list of values or {from, to, step}, got %s' % (where, quote(raw)))
    return list(raw)


class Range:
    """The values of ``{from, to, step}``, made when asked for (a range of a million seeds is not a list)."""

    def __init__(self, start, step, count):
        self.start, self.step, self.count = start, step, count
        self.integral = all(isinstance(v, int) for v in (start, step))

    def __len__(self):
        return self.count

    def __getitem__(self, i):
        if not 0 <= i < self.count:
            raise IndexError(i)
        value = self.start + i * self.step
        return value if self.integral else round(value, 10)

    def __iter__(self):
        return (self[i] for i in range(self.count))

    def distinct(self):
        """The values a check looks at: the two ends (every value lies between them, of the same type)."""
        return [self[0], self[self.count - 1]] if self.count > 1 else [self[0]]


def _distinct(values):
    if isinstance(values, Range):
        return values.distinct()
    seen = []
    for value in values:
        if value not in seen:
            seen.append(value)
    return seen


class Grid:
    """Every combination of a sweep's axes ([(key, values)]) over ``base``, as (assignment, EpisodeSpec), made
    when iterated (the last key varying fastest); ``len`` without making any."""

    def __init__(self, base, axes, source):
        self.base, self.axes, self.source = base, axes, source
        self.count = 1
        for _, values in axes:
            self.count *= len(values)

    def __len__(self):
        return self.count

    def __getitem__(self, index):
        if not 0 <= index < self.count:
            raise IndexError(index)
        assignment = {}
        for key, values in reversed(self.axes):
            index, i = divmod(index, len(values))
            assignment[key] = values[i]
        assignment = {key: assignment[key] for key, _ in self.axes}
        return assignment, episode_spec(self.base, assignment, self.source)

    def __iter__(self):
        return (self[i] for i in range(self.count))


def episode_spec(base, assignment, source, cache=None, part='grid'):
    """The EpisodeSpec of ``assignment`` over ``base``; with ``cache``, also prepared (every check an episode
    makes before it runs). A problem is a SweepError naming the combination (of the file's ``part``)."""
    where = '%s: %s (%s)' % (source, part, ', '.join('%s=%s' % (k, quote(v, 60)) for k, v in assignment.items()))
    try:
        spec = EpisodeSpec.from_dict(apply(base, assignment), where)
        if cache is not None:
            prepare(spec, cache)
    except EpisodeError as error:
        raise SweepError('%s: %s' % (where, error) if not str(error).startswith(where) else str(error))
    except TypeError as error:
        raise SweepError('%s: %s' % (where, error))
    return spec


def check_key(source, key, field=None):
    """A grid's key (or another place's, named ``field``) checked: what it can change of an episode."""
    head, _, rest = key.partition('.')
    if head in ('settings', 'sim', 'args') and rest and '.' not in rest:
        return
    if key.startswith('world.generator.') and key.count('.') == 2:
        return
    if key in POSE_KEYS or key == WORKSPACE_KEY:
        return
    if key in SPEC_FIELDS and key not in ('settings', 'sim'):
        return
    raise SweepError('%s: %s: expected an episode field (%s), settings.NAME, sim.NAME, args.NAME (a graph '
                     "controller's launch arg), controller.workspace, world.generator.NAME, start.x, start.y, start.yaw, goal.x or goal.y"
                     % (source, field or 'grid.' + key, ', '.join(f for f in SPEC_FIELDS if f not in ('settings', 'sim'))))


def apply(base, assignment):
    """The spec fields of ``base`` (a dict) with the grid's ``assignment`` ({key: value}) put in. ``start.x``,
    ``start.y`` and ``start.yaw`` make the simulator's ``sim.start`` ('x y yaw': x and y both, over a start the
    base gives; yaw 0 unless given), ``goal.x`` and ``goal.y`` the episode's ``goal``."""
    fields = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    _apply_poses(fields, {k: v for k, v in assignment.items() if k in POSE_KEYS})
    for key, value in assignment.items():
        head, _, rest = key.partition('.')
        if key in POSE_KEYS:
            continue
        if head in ('settings', 'sim'):
            fields[head] = dict(fields.get(head) or {}, **{rest: value})
        elif head == 'args':
            controller = fields.get('controller')
            if not isinstance(controller, dict) or 'launch' not in controller:
                raise SweepError('grid.%s: args vary a launch file\'s args: the base needs controller: '
                                 '{launch: PKG/path.launch}' % key)
            fields['controller'] = dict(controller, args=dict(controller.get('args') or {}, **{rest: value}))
        elif key == WORKSPACE_KEY:
            controller = fields.get('controller')
            if not isinstance(controller, dict):
                raise SweepError('%s: a workspace is where a graph controller comes from: the base needs controller: '
                                 '{launch: PKG/path.launch}' % key)
            fields['controller'] = dict(controller, workspace=value)
        elif head == 'world' and rest:
            world = fields.get('world')
            generator = dict(world['generator']) if isinstance(world, dict) and 'generator' in world else {}
            generator[rest.split('.', 1)[1]] = value
            fields['world'] = {'generator': generator}
        else:
            fields[key] = value
    return fields


class Sweep:
    """A checked sweep: ``name``, ``keys`` (the grid's, in file order), ``specs`` [(assignment, spec)],
    ``plot`` ({'x': key, 'lines': key} or None), ``report`` (:data:`REPORT_DEFAULTS`' keys), ``text`` (the
    sweep as its file says it, for the report)."""

    def __init__(self, name, keys, specs, plot=None, report=None, text=''):
        self.name, self.keys, self.specs, self.plot = name, keys, specs, plot
        self.report, self.text = dict(REPORT_DEFAULTS, **(report or {})), text


def check_report(source, raw):
    if raw is None:
        return dict(REPORT_DEFAULTS)
    if not isinstance(raw, dict) or not set(raw) <= set(REPORT_DEFAULTS):
        raise SweepError('%s: report: expected {pictures: failures|all|none, max_pictures: N}, got %s' % (source, quote(raw)))
    report = dict(REPORT_DEFAULTS, **raw)
    if report['pictures'] not in PICTURE_CHOICES:
        raise SweepError('%s: report.pictures: expected one of %s, got %s'
                         % (source, ', '.join(PICTURE_CHOICES), quote(report['pictures'])))
    count = report['max_pictures']
    if isinstance(count, bool) or not isinstance(count, int) or count < 0:
        raise SweepError('%s: report.max_pictures: expected a whole number >= 0, got %s' % (source, quote(count)))
    return report


def build(name, base, grid, plot=None, source='<sweep>', report=None, text=None, progress=None):
    """A :class:`Sweep` from a base spec (dict), a grid ({key: values}), a plot choice and a report choice,
    checked (:func:`_check`; ``progress(done, total)`` hears of a long check). ``text``: the sweep as written
    (default: those values as YAML)."""
    if not isinstance(name, str) or not NAME_PATTERN.match(name):
        raise SweepError('%s: name: expected 1 to 64 letters, digits, _ or -, got %s' % (source, quote(name)))
    if not isinstance(base, dict):
        raise SweepError('%s: base: expected a mapping of episode fields, got %s' % (source, quote(base)))
    if not isinstance(grid, dict) or not grid:
        raise SweepError('%s: grid: expected a mapping of keys to value lists, got %s' % (source, quote(grid)))
    axes = []
    for key, raw in grid.items():
        check_key(source, str(key))
        axes.append((str(key), _values(source, key, raw)))
    grid_specs = Grid(base, axes, source)
    if len(grid_specs) > MAX_EPISODES:
        raise SweepError('%s: grid: %d episodes is more than %d' % (source, len(grid_specs), MAX_EPISODES))
    if plot is not None:
        if not isinstance(plot, dict) or not set(plot) <= {'x', 'lines'} or 'x' not in plot:
            raise SweepError("%s: plot: expected {x: KEY, lines: KEY} (lines optional), got %s" % (source, quote(plot)))
        for part, key in plot.items():
            if key not in grid:
                raise SweepError('%s: plot.%s: expected one of the grid keys (%s), got %s'
                                 % (source, part, ', '.join(grid), quote(key)))
    _check(grid_specs, progress)
    if text is None:
        text = yaml.safe_dump({'name': name, 'base': base, 'grid': grid, 'plot': plot, 'report': report},
                              sort_keys=False, default_flow_style=None)
    return Sweep(name, [k for k, _ in axes], grid_specs, plot, check_report(source, report), text)


def _check(grid, progress):
    """Check the grid before anything runs: each distinct value of each key once (a range: its two ends), with
    the other keys at their first values; then every combination, if there are at most CHECK_ALL of them
    (more are checked as their episodes are made: a combination that breaks a rule is its episode's error
    row). ``progress(done, total)`` is told every PROGRESS_S of a long check."""
    cache, first = {}, {key: values[0] for key, values in grid.axes}
    trials = [dict(first, **{key: value}) for key, values in grid.axes for value in _distinct(values)]
    combinations = range(len(grid)) if len(grid) <= CHECK_ALL else ()
    total, told = len(trials) + len(combinations), time.monotonic()
    for done, assignment in enumerate(itertools.chain(trials, (grid[i][0] for i in combinations))):
        episode_spec(grid.base, assignment, grid.source, cache)
        if progress is not None and time.monotonic() - told > PROGRESS_S:
            progress(done + 1, total)
            told = time.monotonic()


def _apply_poses(fields, poses):
    """``sim.start`` and ``goal`` in ``fields`` from ``poses`` ({start.x: ..., goal.y: ...})."""
    start = {k[len('start.'):]: v for k, v in poses.items() if k.startswith('start.')}
    if start:
        given = str((fields.get('sim') or {}).get('start') or '').split()
        x, y, yaw = (given + ['0'] * 3)[:3] if len(given) == 3 else (None, None, '0')
        x, y, yaw = start.get('x', x), start.get('y', y), start.get('yaw', yaw)
        if x is None or y is None:
            raise SweepError('start.x, start.y: expected both (or a base with sim.start), got %s' % quote(start))
        fields['sim'] = dict(fields.get('sim') or {}, start='%s %s %s' % (x, y, yaw))
    goal = {k[len('goal.'):]: v for k, v in poses.items() if k.startswith('goal.')}
    if goal:
        given = fields.get('goal') or (None, None)
        x, y = goal.get('x', given[0]), goal.get('y', given[1])
        if x is None or y is None:
            raise SweepError('goal.x, goal.y: expected both (or a base with a goal), got %s' % quote(goal))
        fields['goal'] = [x, y]


def shipped():
    """The names of the sweeps this package ships (:data:`SHIPPED`)."""
    try:
        return sorted(f[:-len('.yaml')] for f in os.listdir(paths.data_path(*SHIPPED)) if f.endswith('.yaml'))
    except OSError:
        return []


def resolve(name_or_path):
    """The file of a sweep given by its path, or by the name of one this package ships; anything else is
    refused, naming the shipped ones."""
    name_or_path = os.fspath(name_or_path)
    if os.path.isfile(name_or_path):
        return name_or_path
    candidate = paths.data_path(*SHIPPED, name_or_path + '.yaml')
    if name_or_path and os.sep not in name_or_path and os.path.isfile(candidate):
        return candidate
    raise SweepError('%s: no such sweep file, and no sweep of this package has that name (%s)'
                     % (quote(name_or_path), ', '.join(shipped()) or 'none found'))


def load(path, progress=None, changes=None, suffix=''):
    """The :class:`Sweep` of the file at ``path``, or of the shipped sweep of that name (:func:`resolve`): at most
    MAX_FILE_BYTES of UTF-8 YAML, no key twice in a mapping. A file that is not a sweep file is refused without
    quoting it. ``changes``: {key: value} put into its base as a grid's keys are (``closed_loop.batch.compare``'s
    two sides), each key checked as a grid key; ``suffix``: added to its name."""
    path = resolve(path)
    try:
        text = read_text(path, MAX_FILE_BYTES, what='sweep file')
        data = load_yaml(text, path)
        Checker(path).mapping(data, '(top level)', TOP_KEYS)
    except FileError as error:
        raise SweepError(str(error)) from None
    base = data.get('base', {})
    if changes:
        for key in changes:
            check_key(path, key, '%s%s' % (suffix.lstrip('-') and '--%s ' % suffix.lstrip('-'), key))
        base = apply(base if isinstance(base, dict) else {}, changes)
    name = data.get('name')
    return build(name + suffix if isinstance(name, str) and suffix else name, base, data.get('grid'),
                 data.get('plot'), path, data.get('report'), text, progress)
