"""The smallest case that still fails: a failing episode reduced, automatically, while it fails the same way.

    rosrun closed_loop shrink sweeps/NAME INDEX [--output DIR]      # a row of a sweep's or a search's rows.csv
    rosrun closed_loop shrink --spec episode.json [--output DIR]     # an episode spec (JSON or YAML)

*The same way* is the same outcome (collided stays collided, timed_out stays timed_out). In turn, each step
kept only while the episode still fails so:

1. fewer obstacles: delta debugging over the world's obstacles (Zeller and Hildebrandt's ddmin, :func:`ddmin`:
   halves, then quarters, ..., of the list tried alone and left out, until no single obstacle can go), the
   robot's start and goal as they were;
2. a start nearer where it went wrong: where the robot was 1, 2, 4 or 8 s before the failure (the nearest that
   still fails; it starts there at rest);
3. a shorter time limit: a second past the end the failing episode came to;
4. its controller's settings rounded, each to two decimals (then one), where the failure holds.

The result, in ``OUTPUT`` (default: ``shrunk/NAME-INDEX``): ``world.yaml`` (the obstacles left, in this package's
world format), ``regression.test`` (a rostest of ``scenario.launch`` and ``scenario_test`` that expects the
episode to go as meant: it fails today, and passes once the controller is fixed; drop it and the world into
your package's ``test/``), ``episode.json`` (the shrunk spec), and ``picture.png``. A world given as a map or a
Gazebo world is shrunk as the boxes it is made of. Free of ROS (the episodes it runs may be graph episodes).
"""
import dataclasses
import json
import math
import os
import sys
import tempfile

import yaml

from closed_loop import cli
from closed_loop.batch import pictures, sweep
from closed_loop.batch.episode import EpisodeError, EpisodeSpec, prepare, run_episode

#: A shrunk episode's time limit: this long (s) past when the failing episode ended.
TIME_PAST_END_S = 1.0
#: How far (s) before the failure a shrunk episode may start, nearest first: where the robot was then (at rest).
START_BACK_S = (1.0, 2.0, 4.0, 8.0)
#: The most episodes a shrink may run.
MAX_EPISODES = 2000


class ShrinkError(ValueError):
    """What cannot be shrunk: an episode that does not fail, a row that is not there."""


def ddmin(items, fails):
    """The 1-minimal sublist of ``items`` for which ``fails(sublist)`` holds (it holds for ``items``): Zeller and
    Hildebrandt's delta debugging, each subset and each complement of ``n`` parts tried, ``n`` doubled where none
    fails, until every single item is needed."""
    n = 2
    while len(items) >= 2:
        size = int(math.ceil(len(items) / n))
        parts = [items[i:i + size] for i in range(0, len(items), size)]
        for i, part in enumerate(parts):
            if fails(part):
                items, n = part, 2
                break
            rest = [x for j, p in enumerate(parts) if j != i for x in p]
            if n > 2 and fails(rest):
                items, n = rest, max(n - 1, 2)
                break
        else:
            if n >= len(items):
                break
            n = min(2 * n, len(items))
    return items


class Shrinker:
    """Runs the candidate episodes of one shrink (at most MAX_EPISODES), each world written into ``folder``."""

    def __init__(self, spec, folder, stream=sys.stderr):
        self.spec, self.folder, self.stream, self.runs = spec, folder, stream, 0
        prepared = prepare(spec, {})
        world = prepared.world
        self.raw = {'name': 'shrunk_' + world.name, 'description': 'shrunk from %s' % world.name,
                    'robot': {'start': {'x': world.robot_start.x, 'y': world.robot_start.y,
                                        'yaw': world.robot_start.yaw}},
                    'obstacles': [_obstacle(o) for o in world.obstacles]}
        if world.goal is not None:
            self.raw['goal'] = {'x': world.goal[0], 'y': world.goal[1]}
        self.result = run_episode(spec, {})
        if not pictures.is_failure(self.result.outcome, self.result.contacts):
            raise ShrinkError('the episode went as meant (%s): nothing to shrink' % self.result.why)

    def world_file(self, obstacles, name='candidate'):
        path = os.path.join(self.folder, name + '.yaml')
        with open(path, 'w') as f:
            yaml.safe_dump(dict(self.raw, obstacles=list(obstacles)), f, sort_keys=False, default_flow_style=None)
        return path

    def fails(self, spec):
        """True if ``spec`` fails the way the original did."""
        if self.runs >= MAX_EPISODES:
            raise ShrinkError('more than %d episodes: stopped' % MAX_EPISODES)
        self.runs += 1
        try:
            result = run_episode(spec, {})
        except EpisodeError:
            return False
        self.last = result
        return result.outcome == self.result.outcome and (result.contacts > 0) == (self.result.contacts > 0)

    def shrink(self):
        """The shrunk (spec, obstacles)."""
        obstacles = ddmin(self.raw['obstacles'], lambda subset: self.fails(
            dataclasses.replace(self.spec, world=self.world_file(subset))))
        spec = dataclasses.replace(self.spec, world=self.world_file(obstacles))
        self.stream.write('shrink: %d of %d obstacles left (%d episodes)\n'
                          % (len(obstacles), len(self.raw['obstacles']), self.runs))
        ended_s = self.result.time_s
        traced = run_episode(dataclasses.replace(spec, keep_trajectory=True), {})
        for back in START_BACK_S:              # the nearest start to the failure from which it still fails
            rows = [r for r in traced.trajectory or () if r[0] <= traced.time_s - back]
            if traced.time_s - back <= 0.0 or not rows:
                continue
            moved = dataclasses.replace(spec, sim=dict(spec.sim, start='%.4f %.4f %.4f' % tuple(rows[-1][1:4])))
            if self.fails(moved):
                spec, ended_s = moved, self.last.time_s
                break
        shorter = min(spec.time_limit_s, math.ceil(ended_s + TIME_PAST_END_S))
        if shorter < spec.time_limit_s and self.fails(dataclasses.replace(spec, time_limit_s=float(shorter))):
            spec = dataclasses.replace(spec, time_limit_s=float(shorter))
        for key, value in sorted(spec.settings.items()):
            for digits in (2, 1):
                if isinstance(value, float) and round(value, digits) != value:
                    rounded = dataclasses.replace(spec, settings=dict(spec.settings, **{key: round(value, digits)}))
                    if self.fails(rounded):
                        spec = rounded
                        value = round(value, digits)
        return spec, obstacles


def _obstacle(o):
    """A world's obstacle as its world-file entry (static: a shrunk world keeps where each stood at 0)."""
    entry = {'name': o.name, 'type': o.shape, 'position': [float(v) for v in o.position], 'color': list(o.color)}
    if o.shape == 'cylinder':
        entry.update(radius=float(o.radius), height=float(o.size[2]))
    else:
        entry.update(size=[float(v) for v in o.size], yaw=float(o.yaw))
    return entry


def regression_test(spec, world_name='world.yaml'):
    """A rostest file for ``spec``'s shrunk world: scenario.launch with its controller, scenario_test expecting it
    to go as meant (no contact; stopped or reached)."""
    controller = spec.controller
    if isinstance(controller, dict) and 'launch' in controller:
        package, _, rest = controller['launch'].partition('/')
        how = '    <arg name="controller_launch" value="$(find %s)/%s"/>\n' % (package, rest)
        if controller.get('args'):
            how += '    <!-- its args: %s -->\n' % json.dumps(controller['args'])
    else:
        name = controller['node'] if isinstance(controller, dict) else controller
        how = ('    <arg name="controller_pkg" value="closed_loop"/>\n    <arg name="controller_type" value="%s"/>\n'
               '    <arg name="controller_name" value="controller"/>\n' % name)
    params = ''.join('  <param name="/controller/%s" value="%s"/>\n' % (k, v) for k, v in sorted(spec.settings.items()))
    goal = ''.join('    <arg name="goal_%s" value="%r"/>\n' % (axis, value)
                   for axis, value in zip('xy', spec.goal)) if spec.goal else ''
    if spec.sim.get('start'):
        goal += '    <arg name="start" value="%s"/>\n' % spec.sim['start']
    return ('<launch>\n  <!-- The smallest case found of a failure (rosrun closed_loop shrink): it fails until the '
            'controller is fixed. -->\n%s  <include file="$(find closed_loop)/launch/scenario.launch">\n'
            '    <arg name="world" value="$(dirname)/%s"/>\n    <arg name="robot" value="%s"/>\n%s%s'
            '    <arg name="time_limit" value="%g"/>\n  </include>\n'
            '  <test test-name="shrunk" pkg="closed_loop" type="scenario_test" time-limit="%d">\n'
            '    <param name="expect" value="stopped,reached"/>\n    <param name="max_contacts" value="0"/>\n'
            '  </test>\n</launch>\n' % (params, world_name, spec.robot, how, goal, spec.time_limit_s,
                                       int(60 + 3 * spec.time_limit_s)))


def main(argv=None):
    parser = cli.parser('shrink', ' '.join(__doc__.split('\n\n')[0].split()))
    parser.add_argument('rows', nargs='?', help="a sweep's or a search's folder (its rows.csv)")
    parser.add_argument('index', nargs='?', type=int, help='the row (episode index) to shrink')
    parser.add_argument('--spec', help='or: an episode spec file (JSON or YAML)')
    parser.add_argument('--output', help='directory for world.yaml, regression.test, episode.json and picture.png')
    args = parser.parse_args(argv)
    try:
        spec, name = _spec_of(args)
        output = args.output or os.path.join('shrunk', name)
        os.makedirs(output, exist_ok=True)
        with tempfile.TemporaryDirectory(prefix='closed_loop-shrink-') as folder:
            shrinker = Shrinker(spec, folder)
            small, obstacles = shrinker.shrink()
            world = shrinker.world_file(obstacles, 'world')
            with open(world) as f:
                text = f.read()
        with open(os.path.join(output, 'world.yaml'), 'w') as f:
            f.write('# %s: the smallest case found (rosrun closed_loop shrink)\n%s' % (name, text))
        small = dataclasses.replace(small, world=os.path.abspath(os.path.join(output, 'world.yaml')))
        with open(os.path.join(output, 'episode.json'), 'w') as f:
            json.dump(small.to_dict(), f, indent=1)
        with open(os.path.join(output, 'regression.test'), 'w') as f:
            f.write(regression_test(small))
        result = run_episode(dataclasses.replace(small, keep_trajectory=True), {})
        with open(os.path.join(output, 'picture.png'), 'wb') as f:
            f.write(pictures.episode_picture(small, result, label='shrunk'))
    except (ShrinkError, EpisodeError, OSError, ValueError) as error:
        print('shrink: %s' % error, file=sys.stderr)
        return 2
    print('shrink: %d obstacles (of %d), %s -> %s' % (len(obstacles), len(shrinker.raw['obstacles']), result.why,
                                                      output))
    return 0


def _spec_of(args):
    """(the episode spec to shrink, a name for it) from the command line."""
    if args.spec:
        with open(args.spec) as f:
            data = yaml.safe_load(f)
        return EpisodeSpec.from_dict(data, args.spec), os.path.splitext(os.path.basename(args.spec))[0]
    if args.rows is None or args.index is None:
        raise ShrinkError('expected a sweep\'s folder and a row index, or --spec FILE')
    rows = [r for r in sweep.read_rows(os.path.join(args.rows, 'rows.csv')) if int(r['index']) == args.index]
    if not rows:
        raise ShrinkError('%s: no row %d in rows.csv' % (args.rows, args.index))
    name = '%s-%d' % (os.path.basename(os.path.normpath(args.rows)), args.index)
    return EpisodeSpec.from_dict(json.loads(rows[0]['spec']), name), name
