"""Did my change make it worse? One scenario set, two controllers, the episodes paired.

    rosrun closed_loop compare SWEEP.yaml --a settings.stop_distance=0.5 --b settings.stop_distance=0.3
    rosrun closed_loop compare my_sweep.yaml --a controller='{launch: my_pkg/old.launch}' \\
                                             --b controller='{launch: my_pkg/new.launch}' --max-regressions 0
    rosrun closed_loop compare my_sweep.yaml --a controller.workspace=/home/me/ws_main \\
                                             --b controller.workspace=/home/me/ws_branch

The sweep file's grid is the scenario set, or the episodes that failed in a search's folder (or a sweep's:
``compare searches/NAME --b ...`` asks whether B fails where the search found A failing); ``--a`` and ``--b`` each
put ``KEY=VALUE`` into the base (into each episode of a folder; the keys a grid takes: an episode field,
``settings.NAME``, ``sim.NAME``, ``args.NAME``, ``controller.workspace`` (the same launch file as another catkin
workspace has it, ``closed_loop.batch.workspace``), ``world.generator.NAME``, ``start.x`` ...; the value read as
YAML). Each side runs as a sweep of its own (``OUTPUT/a``, ``OUTPUT/b``: rows, pictures of what failed,
its page, resumable with ``--resume``), on the same Dask cluster a sweep takes; then the episodes are paired by
their place in the grid. A pair is a *regression* where A went as meant and B did not (collided, failed, timed
out, could not run, or touched anything), a *fix* the other way round. Beside the counts: McNemar's exact test
on the pairs that differ (``scipy.stats.binomtest``: how likely so many regressions against so few fixes, or
more lopsided, if A and B were as good), the share of regressions among them with its exact 95% interval, and
the mean change (B - A) of the least clearance and of the time over the pairs where both went as meant, each
with its 95% interval (``scipy.stats.ttest_rel``). ``OUTPUT/compare.html`` shows the pairs, regressions first,
each with the pictures of A and B side by side (A's drawn again: episodes are deterministic).

The exit status is 1 where B has more regressions than ``--max-regressions`` (default 0), so a CI job can gate a
change on it; 2 for a refused sweep file or key.
"""
import dataclasses
import json
import math
import os
import sys

import yaml

from closed_loop import cli
from closed_loop.batch import compare_page, pictures, sweep, sweep_file, sweep_report
from closed_loop.batch.episode import EpisodeSpec, run_episode

#: The regressions drawn (A and B side by side) on the page, at most.
MAX_PAIR_PICTURES = 12
CONFIDENCE = 0.95


@dataclasses.dataclass
class Pair:
    """One scenario of the set, as A and as B did it (their rows of rows.csv)."""
    index: int
    a: dict
    b: dict

    @property
    def kind(self):
        """'regression', 'fix', 'both' (as meant both times) or 'neither'."""
        ok_a = not pictures.is_failure(self.a['outcome'], self.a.get('contacts'))
        ok_b = not pictures.is_failure(self.b['outcome'], self.b.get('contacts'))
        return {(True, False): 'regression', (False, True): 'fix', (True, True): 'both'}.get((ok_a, ok_b), 'neither')


@dataclasses.dataclass
class Comparison:
    """The pairs and what they say (see the module's docstring)."""
    pairs: list
    regressions: int
    fixes: int
    p_value: float                 # McNemar's exact test, two-sided (1 where no pair differs)
    regression_share: tuple        # (share of regressions among the pairs that differ, low, high); None if none
    clearance_change: tuple        # (mean of B - A, low, high) m; None with fewer than two pairs
    time_change: tuple             # the same for time_s, s

    def lines(self):
        """The comparison in a few lines of text."""
        out = ['%d pairs: %d regressions (A as meant, B not), %d fixes, %d as meant both times, %d neither'
               % (len(self.pairs), self.regressions, self.fixes, sum(p.kind == 'both' for p in self.pairs),
                  sum(p.kind == 'neither' for p in self.pairs))]
        if self.regression_share is not None:
            out.append("McNemar's exact test: p = %.4g; regressions are %.0f%% of the pairs that differ (%.0f%% "
                       'interval %.0f%% to %.0f%%)' % (self.p_value, 100 * self.regression_share[0], 100 * CONFIDENCE,
                                                      100 * self.regression_share[1], 100 * self.regression_share[2]))
        for what, change, unit in (('least clearance', self.clearance_change, 'm'), ('time', self.time_change, 's')):
            if change is not None:
                out.append('%s, B - A over the pairs as meant both times: %+.3f %s (%.0f%% interval %+.3f to %+.3f)'
                           % (what, change[0], unit, 100 * CONFIDENCE, change[1], change[2]))
        return out


def parse_changes(items, side):
    """{key: value} of ``KEY=VALUE`` strings (the value read as YAML); SweepError naming the side and the item."""
    changes = {}
    for item in items or ():
        key, sep, text = item.partition('=')
        if not sep or not key:
            raise sweep_file.SweepError('--%s %s: expected KEY=VALUE' % (side, item))
        try:
            changes[key] = yaml.safe_load(text) if text else ''
        except yaml.YAMLError as error:
            raise sweep_file.SweepError('--%s %s: the value is not YAML (%s)' % (side, item, str(error).split('\n')[0]))
    return changes


def scenario_set(source, changes=None, suffix='', progress=None):
    """The sweep one side runs: a sweep file's grid (``source`` a file, or the name of a shipped one) with
    ``changes`` in its base; or the episodes that failed in a search's or a sweep's folder (``source`` a folder
    holding rows.csv), ``changes`` put into each."""
    if not os.path.isdir(source):
        return sweep_file.load(source, progress, changes, suffix)
    rows = [r for r in sweep.read_rows(os.path.join(source, 'rows.csv'))
            if r.get('failing') == 'True' or r.get('failing') is None and pictures.is_failure(r['outcome'],
                                                                                            r.get('contacts'))]
    if not rows:
        raise sweep_file.SweepError('%s: no failing episode in its rows.csv to compare on' % source)
    for key in changes or ():
        sweep_file.check_key(source, key, '--%s %s' % (suffix.lstrip('-'), key) if suffix else key)
    specs = [({'failed_as': int(r['index'])},
              EpisodeSpec.from_dict(sweep_file.apply(json.loads(r['spec']), changes or {}), source)) for r in rows]
    name = os.path.basename(os.path.normpath(source)) + '-failures'
    return sweep_file.Sweep(name + suffix, ['failed_as'], specs, text='the episodes that failed in %s' % source)


def pair(rows_a, rows_b):
    """The :class:`Comparison` of two sides' rows (dicts of rows.csv) of one grid, paired by index."""
    from scipy import stats
    by_index = {int(r['index']): r for r in rows_b}
    pairs = [Pair(int(r['index']), r, by_index[int(r['index'])]) for r in sorted(rows_a, key=lambda r: int(r['index']))
             if int(r['index']) in by_index]
    regressions = sum(p.kind == 'regression' for p in pairs)
    fixes = sum(p.kind == 'fix' for p in pairs)
    p_value, share = 1.0, None
    if regressions + fixes:
        test = stats.binomtest(regressions, regressions + fixes, 0.5)
        interval = test.proportion_ci(CONFIDENCE, method='exact')
        p_value, share = float(test.pvalue), (regressions / (regressions + fixes), interval.low, interval.high)

    def change(column):
        both = [(float(p.a[column]), float(p.b[column])) for p in pairs if p.kind == 'both'
                and _finite(p.a.get(column)) and _finite(p.b.get(column))]
        if len(both) < 2:
            return None
        a, b = zip(*both)
        diffs = [y - x for x, y in both]
        if max(diffs) == min(diffs):                    # no spread: the interval is the value itself
            return (diffs[0], diffs[0], diffs[0])
        interval = stats.ttest_rel(b, a).confidence_interval(CONFIDENCE)
        return (sum(diffs) / len(diffs), float(interval.low), float(interval.high))
    return Comparison(pairs, regressions, fixes, p_value, share, change('min_clearance_m'), change('time_s'))


def _finite(text):
    try:
        return math.isfinite(float(text))
    except (TypeError, ValueError):
        return False


def draw_a(pair_, output):
    """The picture of side A's episode of a regression (drawn again: it went as meant, so its sweep drew none),
    into ``output``; its path, or None where it cannot be drawn."""
    path = os.path.join(output, 'pairs', 'episode-%05d-a.png' % pair_.index)
    if os.path.exists(path):
        return path
    try:
        spec = dataclasses.replace(EpisodeSpec.from_dict(json.loads(pair_.a['spec'])), keep_trajectory=True)
        logs = os.path.join(output, 'pairs', 'logs-%05d-a' % pair_.index)
        result = run_episode(spec, {}, logs)
        png = pictures.episode_picture(spec, result, label='A, episode %d' % pair_.index)
    except Exception as error:      # a picture that cannot be drawn is said on the page, not a failed compare
        sys.stderr.write('compare: episode %d of A not drawn: %s\n' % (pair_.index, error))
        return None
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'wb') as f:
        f.write(png)
    return path


def main(argv=None):
    parser = cli.parser('compare', ' '.join(__doc__.split('\n\n')[0].split()))
    parser.add_argument('spec', help='the sweep file whose grid is the scenario set (YAML), or the name of one this '
                        "package ships; or a search's (or a sweep's) folder: the episodes that failed in it")
    parser.add_argument('--a', action='append', metavar='KEY=VALUE', help="side A's change to the base (repeat it "
                        'for more)')
    parser.add_argument('--b', action='append', metavar='KEY=VALUE', help="side B's change to the base")
    parser.add_argument('--output', help='directory for a/, b/ and compare.html (default: sweeps/NAME-compare)')
    parser.add_argument('--max-regressions', type=int, default=0, help='exit 1 where B has more regressions')
    sweep.add_cluster_arguments(parser)
    args = parser.parse_args(argv)
    try:
        changes = {side: parse_changes(getattr(args, side), side) for side in ('a', 'b')}
        for side in ('a', 'b'):             # both sides checked before either runs
            scenario_set(args.spec, changes[side], '-' + side)
        name = scenario_set(args.spec).name
    except sweep_file.SweepError as error:
        print('compare: %s' % error, file=sys.stderr)
        return 2
    output = args.output or os.path.join('sweeps', name + '-compare')
    rows, built = {}, {}
    for side in ('a', 'b'):
        status, built[side], rows[side] = sweep.run_command(
            'compare: %s' % side.upper(), lambda s=side: scenario_set(args.spec, changes[s], '-' + s,
                                                                       sweep.checking),
            os.path.join(output, side), args)
        if status:
            return status
    comparison = pair(rows['a'], rows['b'])
    drawn = {p.index: (draw_a(p, output), sweep_report.picture_path(os.path.join(output, 'b'), p.index))
             for p in [p for p in comparison.pairs if p.kind == 'regression'][:MAX_PAIR_PICTURES]}
    page = compare_page.write(os.path.join(output, 'compare.html'), name, built['a'].keys, changes, comparison,
                              drawn)
    for line in comparison.lines():
        print('compare: %s' % line)
    worse = comparison.regressions > args.max_regressions
    print('compare: %s -> %s' % (page, 'B regressed: %d regressions, more than --max-regressions %d'
                                 % (comparison.regressions, args.max_regressions) if worse else
                                 'B holds: %d regressions (--max-regressions %d)'
                                 % (comparison.regressions, args.max_regressions)))
    return 1 if worse else 0
