"""Sweep files: a grid of episodes (``closed_loop.batch.episode.EpisodeSpec``) in YAML, checked whole before
anything runs. Free of ROS.

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
``controller: {launch: PKG/path.launch}``) or ``world.generator.NAME`` (a
``closed_loop.sim.clutter.ClutterSettings`` field). Its values are a list, or ``{from, to, step}`` (both ends included). Every combination is then
checked as an episode would be (the controller's settings by the class its node uses, the world loaded or
its generator's settings checked); the first problem is an error that names the file, the field and what
was expected.

``report``: which episodes get a picture (``closed_loop.batch.pictures``), drawn where the episode ran:
``pictures: failures`` (those not as meant: collided, failed, timed out, error, or any contact), ``all`` or
``none``; at most ``max_pictures`` of them (the first to finish), the rest on request with ``rosrun
closed_loop episode_plot OUTPUT INDEX``.
"""
import itertools
import math
import re

import yaml

from closed_loop.batch.episode import EpisodeError, EpisodeSpec, prepare

SPEC_FIELDS = tuple(EpisodeSpec.__dataclass_fields__)
NAME_PATTERN = re.compile(r'^[A-Za-z0-9_-]{1,64}$')
#: A grid may not have more combinations than this (a typo in a range should not start a million).
MAX_EPISODES = 1000000
#: ``report:`` when a sweep file does not say; a picture is about 40 kB and 0.2 s of a worker's time.
REPORT_DEFAULTS = {'pictures': 'failures', 'max_pictures': 100}
PICTURE_CHOICES = ('failures', 'all', 'none')


class SweepError(ValueError):
    """A sweep file that cannot be run; the message names the file, the field and what was expected."""


def _values(source, key, raw):
    where = '%s: grid.%s' % (source, key)
    if isinstance(raw, dict):
        if set(raw) != {'from', 'to', 'step'}:
            raise SweepError('%s: expected a list of values or {from, to, step}, got %r' % (where, raw))
        a, b, step = raw['from'], raw['to'], raw['step']
        for name, value in (('from', a), ('to', b), ('step', step)):
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise SweepError('%s.%s: expected a number, got %r' % (where, name, value))
        if not step > 0 or b < a:
            raise SweepError('%s: expected step > 0 and to >= from, got %r' % (where, raw))
        count = int(math.floor((b - a) / step + 1e-9)) + 1
        if count > MAX_EPISODES:
            raise SweepError('%s: %d values is too many' % (where, count))
        integral = all(isinstance(v, int) for v in (a, b, step))
        return [a + i * step if integral else round(a + i * step, 10) for i in range(count)]
    if not isinstance(raw, list) or not raw:
        raise SweepError('%s: expected a non-empty list of values or {from, to, step}, got %r' % (where, raw))
    return list(raw)


def _check_key(source, key):
    head, _, rest = key.partition('.')
    if head in ('settings', 'sim', 'args') and rest and '.' not in rest:
        return
    if key.startswith('world.generator.') and key.count('.') == 2:
        return
    if key in SPEC_FIELDS and key not in ('settings', 'sim'):
        return
    raise SweepError('%s: grid.%s: expected an episode field (%s), settings.NAME, sim.NAME, args.NAME (a graph '
                     "controller's launch arg) or world.generator.NAME"
                     % (source, key, ', '.join(f for f in SPEC_FIELDS if f not in ('settings', 'sim'))))


def apply(base, assignment):
    """The spec fields of ``base`` (a dict) with the grid's ``assignment`` ({key: value}) put in."""
    fields = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    for key, value in assignment.items():
        head, _, rest = key.partition('.')
        if head in ('settings', 'sim'):
            fields[head] = dict(fields.get(head) or {}, **{rest: value})
        elif head == 'args':
            controller = fields.get('controller')
            if not isinstance(controller, dict) or 'launch' not in controller:
                raise SweepError('grid.%s: args vary a launch file\'s args: the base needs controller: '
                                 '{launch: PKG/path.launch}' % key)
            fields['controller'] = dict(controller, args=dict(controller.get('args') or {}, **{rest: value}))
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


def _report(source, raw):
    if raw is None:
        return dict(REPORT_DEFAULTS)
    if not isinstance(raw, dict) or not set(raw) <= set(REPORT_DEFAULTS):
        raise SweepError('%s: report: expected {pictures: failures|all|none, max_pictures: N}, got %r' % (source, raw))
    report = dict(REPORT_DEFAULTS, **raw)
    if report['pictures'] not in PICTURE_CHOICES:
        raise SweepError('%s: report.pictures: expected one of %s, got %r'
                         % (source, ', '.join(PICTURE_CHOICES), report['pictures']))
    count = report['max_pictures']
    if isinstance(count, bool) or not isinstance(count, int) or count < 0:
        raise SweepError('%s: report.max_pictures: expected a whole number >= 0, got %r' % (source, count))
    return report


def build(name, base, grid, plot=None, source='<sweep>', report=None, text=None):
    """A :class:`Sweep` from a base spec (dict), a grid ({key: values}), a plot choice and a report choice,
    every combination checked. ``text``: the sweep as written (default: those values as YAML)."""
    if not isinstance(name, str) or not NAME_PATTERN.match(name):
        raise SweepError('%s: name: expected 1 to 64 letters, digits, _ or -, got %r' % (source, name))
    if not isinstance(base, dict):
        raise SweepError('%s: base: expected a mapping of episode fields, got %r' % (source, base))
    if not isinstance(grid, dict) or not grid:
        raise SweepError('%s: grid: expected a mapping of keys to value lists, got %r' % (source, grid))
    axes = []
    for key, raw in grid.items():
        _check_key(source, str(key))
        axes.append((str(key), _values(source, key, raw)))
    total = 1
    for _, values in axes:
        total *= len(values)
    if total > MAX_EPISODES:
        raise SweepError('%s: grid: %d episodes is more than %d' % (source, total, MAX_EPISODES))
    if plot is not None:
        if not isinstance(plot, dict) or not set(plot) <= {'x', 'lines'} or 'x' not in plot:
            raise SweepError("%s: plot: expected {x: KEY, lines: KEY} (lines optional), got %r" % (source, plot))
        for part, key in plot.items():
            if key not in grid:
                raise SweepError('%s: plot.%s: expected one of the grid keys (%s), got %r'
                                 % (source, part, ', '.join(grid), key))
    cache, specs = {}, []
    keys = [k for k, _ in axes]
    for combo in itertools.product(*[values for _, values in axes]):
        assignment = dict(zip(keys, combo))
        where = '%s: grid (%s)' % (source, ', '.join('%s=%r' % kv for kv in assignment.items()))
        try:
            spec = EpisodeSpec.from_dict(apply(base, assignment), where)
            prepare(spec, cache)
        except EpisodeError as error:
            raise SweepError('%s: %s' % (where, error) if not str(error).startswith(where) else str(error))
        except TypeError as error:
            raise SweepError('%s: %s' % (where, error))
        specs.append((assignment, spec))
    if text is None:
        text = yaml.safe_dump({'name': name, 'base': base, 'grid': grid, 'plot': plot, 'report': report},
                              sort_keys=False, default_flow_style=None)
    return Sweep(name, keys, specs, plot, _report(source, report), text)


def load(path):
    """The :class:`Sweep` of the file at ``path``."""
    try:
        with open(path) as f:
            text = f.read()
        data = yaml.safe_load(text)
    except OSError as error:
        raise SweepError('%s: cannot be read (%s)' % (path, error.strerror or error))
    except UnicodeDecodeError:
        raise SweepError('%s: not a sweep file (not UTF-8 text)' % path) from None
    except yaml.YAMLError as error:
        raise SweepError('%s: not valid YAML (%s)' % (path, error))
    if not isinstance(data, dict):
        raise SweepError('%s: expected a mapping with name, base, grid (and plot, report), got %r' % (path, data))
    unknown = sorted(set(data) - {'name', 'base', 'grid', 'plot', 'report'})
    if unknown:
        raise SweepError('%s: %s: expected only name, base, grid, plot and report' % (path, unknown[0]))
    return build(data.get('name'), data.get('base', {}), data.get('grid'), data.get('plot'), path,
                 data.get('report'), text)
