"""Where does it fail? A search for failing scenarios, steered by the judge's margins.

    rosrun closed_loop search my_search.yaml [--output DIR] [--resume] [--scheduler tcp://HOST:PORT]

The search file is a sweep file's style (``closed_loop.batch.sweep_file``) with a space in place of a grid::

    name: avoid_search
    base: {world: {generator: {method: barn, fill: 0.3}}, robot: jackal, controller: avoid_obstacles}
    space:                                  # the free parameters (the keys a grid takes)
      world.generator.seed: {from: 0, to: 999, int: true}      # whole numbers
      start.x: {from: 0.0, to: 0.5}                            # the start (x and y both; yaw 0 unless given)
      start.y: {from: -1.0, to: 1.0}                           # and the goal (goal.x, goal.y), a coordinate each
      start.yaw: {from: -0.5, to: 0.5}
      settings.max_speed: {from: 0.3, to: 1.0}
      scan_noise: [0.0, 0.005]                                 # a list: one of these
    budget: 60                              # episodes, at most
    batch: 4                                # episodes asked for at once (the same search on any cluster)
    seed: 0
    sampler: tpe                            # tpe (default), cmaes, or random (uniform, to compare against)
    failure: {min_clearance: 0.05, max_time: 60, max_goal_error: 0.5}

An episode *fails* when it did not go as meant (collided, failed, timed out, could not run, touched anything;
``failure.outcomes`` narrows the outcomes), came closer than ``failure.min_clearance`` (m), took longer than
``failure.max_time`` (s), or ended farther than ``failure.max_goal_error`` (m) from its goal. The search steers by
how near each episode came to failing: its objective, which Optuna's sampler (TPE by default; CMA-ES; uniform
random) minimises, is -1 for a failure and otherwise the least of its margins, each in [0, 1]: the least clearance
above ``min_clearance`` (capped at 1 m), and the time left under ``max_time`` and the goal error left under
``max_goal_error``, each as a share of its limit. Batches of ``batch`` episodes run on the sweep's Dask cluster (local by default);
each episode is a row of ``OUTPUT/rows.csv`` as a sweep's (its parameters, ``objective``, ``failing``, the
result), ``--resume`` tells the sampler the rows already there and goes on, and the failures get pictures and
``OUTPUT/report.html``. Free of ROS (the episodes it runs may be graph episodes).
"""
import dataclasses
import itertools
import math
import os
import sys
import warnings

from closed_loop import cli
from closed_loop.batch import (graph_episode, logs_back, pictures, rows_file, sweep, sweep_file, sweep_report,
                               worker_check)
from closed_loop.yaml_check import Checker, FileError, load_yaml, quote, read_text

TOP_KEYS = ('name', 'base', 'space', 'budget', 'batch', 'seed', 'sampler', 'failure', 'report')
FAILURE_KEYS = ('outcomes', 'min_clearance', 'max_time', 'max_goal_error')
SAMPLERS = ('tpe', 'cmaes', 'random')
MAX_BUDGET, MAX_BATCH, MAX_CORNERS = 100000, 256, 64
#: Least clearance (m) beyond which more adds nothing to an episode's margin.
CLEARANCE_CAP_M = 1.0
#: TPE samples this many episodes at random before it steers (its startup), and models the parameters together
#: (multivariate): a failure often needs two of them at once (fast, and slowing late). The episodes of a batch
#: asked at once are told to it as the worst there is until they end (Optuna's constant liar), so that a batch
#: spreads out: 3.9x the distinct failures of chance with it, 3.6x without (docs/benchmarks.md, bench_search).
#: Its model of where failures are is drawn from the best GOOD_SHARE of the episodes so far (at most 25 of them;
#: Optuna's default is a tenth): with a quarter, more distinct failures in each of bench_search's three cases
#: (16.3, 16.2, 6.2 against 14.8, 13.2, 5.2 with a tenth; 17.7, -, 6.0 with 0.35; 15.3, -, 5.5 with 0.15).
STARTUP_TRIALS, GOOD_SHARE, GOOD_MAX = 4, 0.25, 25
EXTRA_COLUMNS = ('objective', 'failing')


@dataclasses.dataclass
class Search:
    """A checked search file (the module's docstring): its sweep-style ``sweep`` (name, keys, report; no grid)
    beside the space {key: ('float'|'int', low, high) or ('choice', values)}, the budget and batch, the sampler
    and its seed, the failure's definition, and the file's ``text``."""
    name: str
    base: dict
    space: dict
    budget: int
    batch: int
    seed: int
    sampler: str
    outcomes: tuple
    min_clearance: float
    max_time: float
    max_goal_error: float
    report: dict
    text: str

    @property
    def keys(self):
        return list(self.space)


def load(path):
    """The :class:`Search` of the file at ``path``; SweepError in one line naming the file and the field."""
    try:
        text = read_text(path, sweep_file.MAX_FILE_BYTES, what='search file')
        data = load_yaml(text, path)
        Checker(path).mapping(data, '(top level)', TOP_KEYS)
    except FileError as error:
        raise sweep_file.SweepError(str(error)) from None

    def fail(field, expected, got):
        raise sweep_file.SweepError('%s: %s: expected %s, got %s' % (path, field, expected, quote(got)))
    name = data.get('name')
    if not isinstance(name, str) or not sweep_file.NAME_PATTERN.match(name):
        fail('name', '1 to 64 letters, digits, _ or -', name)
    space = {}
    raw_space = data.get('space')
    if not isinstance(raw_space, dict) or not raw_space:
        fail('space', 'a mapping of keys to {from, to} ranges or lists of choices', raw_space)
    for key, raw in raw_space.items():
        sweep_file.check_key(path, str(key), 'space.%s' % key)
        space[str(key)] = _dimension(raw, 'space.%s' % key, fail)
    budget, batch, seed = data.get('budget'), data.get('batch', 4), data.get('seed', 0)
    for field, value, top in (('budget', budget, MAX_BUDGET), ('batch', batch, MAX_BATCH), ('seed', seed, 2 ** 31)):
        if isinstance(value, bool) or not isinstance(value, int) or not (0 if field == 'seed' else 1) <= value <= top:
            fail(field, 'a whole number from %d to %d' % (0 if field == 'seed' else 1, top), value)
    sampler = data.get('sampler', 'tpe')
    if sampler not in SAMPLERS:
        fail('sampler', 'one of %s' % ', '.join(SAMPLERS), sampler)
    failure = data.get('failure') or {}
    if not isinstance(failure, dict) or not set(failure) <= set(FAILURE_KEYS):
        fail('failure', 'a mapping of %s' % ', '.join(FAILURE_KEYS), failure)
    outcomes = tuple(failure.get('outcomes', pictures.FAILING))
    if not outcomes or not set(outcomes) <= set(pictures.FAILING):
        fail('failure.outcomes', 'some of %s' % ', '.join(pictures.FAILING), failure.get('outcomes'))
    limits = []
    for field in ('min_clearance', 'max_time', 'max_goal_error'):
        value = failure.get(field)
        if value is not None and (isinstance(value, bool) or not isinstance(value, (int, float))
                                  or not math.isfinite(value) or value <= 0):
            fail('failure.' + field, 'a number > 0', value)
        limits.append(None if value is None else float(value))
    base = data.get('base', {})
    if not isinstance(base, dict):
        fail('base', 'a mapping of episode fields', base)
    search = Search(name, base, space, budget, batch, seed, sampler, outcomes, *limits,
                    sweep_file.check_report(path, data.get('report')), text)
    # The corners of the space (each range's ends, each choice; with more than MAX_CORNERS of them, each key's
    # with the others at their first), checked as a sweep checks its grid's values, before anything runs.
    ends = {key: list(dim[1] if dim[0] == 'choice' else dim[1:]) for key, dim in space.items()}
    cache = {}
    if math.prod(len(v) for v in ends.values()) <= MAX_CORNERS:
        for values in itertools.product(*ends.values()):
            spec_of(search, dict(zip(ends, values)), path, cache)
    else:
        first = {key: values[0] for key, values in ends.items()}
        for key, values in ends.items():
            for value in values:
                spec_of(search, dict(first, **{key: value}), path, cache)
    return search


def _dimension(raw, field, fail):
    if isinstance(raw, list):
        if not raw:
            fail(field, 'a list of at least one choice', raw)
        return ('choice', tuple(raw))
    if not isinstance(raw, dict) or not {'from', 'to'} <= set(raw) or not set(raw) <= {'from', 'to', 'int'}:
        fail(field, '{from: LOW, to: HIGH} (int: true for whole numbers) or a list of choices', raw)
    low, high = raw['from'], raw['to']
    whole = raw.get('int', False)
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (low, high))
    if not numbers or not low < high or (whole and not all(float(v).is_integer() for v in (low, high))):
        fail(field, 'from < to, finite numbers%s' % (', whole' if whole else ''), raw)
    return ('int', int(low), int(high)) if whole else ('float', float(low), float(high))


def spec_of(search, assignment, source='<search>', cache=None):
    """The ``EpisodeSpec`` of ``search``'s base with ``assignment`` ({key: value}) put in; with ``cache``, checked
    as an episode checks itself before it runs (SweepError naming the values)."""
    return sweep_file.episode_spec(search.base, assignment, source, cache, 'space')


def judged(search, result):
    """(objective, failing) of an episode's ``result`` (a row's result columns): the module's docstring."""
    clearance = _number(result.get('min_clearance_m'), math.inf)
    time_s = _number(result.get('time_s'), 0.0)
    error = _number(result.get('goal_error_m'), None)
    failing = (result['outcome'] in search.outcomes or _number(result.get('contacts'), 0) > 0
               or search.min_clearance is not None and clearance < search.min_clearance
               or search.max_time is not None and time_s > search.max_time
               or search.max_goal_error is not None and error is not None and error > search.max_goal_error)
    if failing:
        return -1.0, True
    margins = [max(0.0, min(clearance, CLEARANCE_CAP_M) - (search.min_clearance or 0.0)) / CLEARANCE_CAP_M]
    for limit, value in ((search.max_time, time_s), (search.max_goal_error, error)):
        if limit is not None and value is not None:
            margins.append(max(0.0, limit - value) / limit)
    return min(margins), False


def _number(text, default):
    try:
        value = float(text)
    except (TypeError, ValueError):
        return default
    return value if value == value else default


def sampler_of(search):
    import optuna
    if search.sampler == 'random':
        return optuna.samplers.RandomSampler(seed=search.seed)
    if search.sampler == 'cmaes':
        return optuna.samplers.CmaEsSampler(seed=search.seed, warn_independent_sampling=False)
    with warnings.catch_warnings():         # (multivariate is "experimental" to Optuna since 2.2)
        warnings.simplefilter('ignore', optuna.exceptions.ExperimentalWarning)
        return optuna.samplers.TPESampler(seed=search.seed, n_startup_trials=min(STARTUP_TRIALS, search.budget),
                                          multivariate=True, warn_independent_sampling=False, constant_liar=True,
                                          gamma=good_count)


def good_count(episodes):
    """How many of ``episodes`` (told to TPE so far) its model of where failures are is drawn from."""
    return min(max(1, int(GOOD_SHARE * episodes)), GOOD_MAX)


def distributions(search):
    import optuna
    out = {}
    for key, dim in search.space.items():
        if dim[0] == 'choice':
            out[key] = optuna.distributions.CategoricalDistribution(dim[1])
        elif dim[0] == 'int':
            out[key] = optuna.distributions.IntDistribution(dim[1], dim[2])
        else:
            out[key] = optuna.distributions.FloatDistribution(dim[1], dim[2])
    return out


def run(search, output, scheduler=None, workers=None, resume=False, stream=sys.stderr):
    """Run ``search`` into ``output`` (rows.csv, pictures/, report.html); returns its rows."""
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    os.makedirs(output, exist_ok=True)
    rows_path = os.path.join(output, 'rows.csv')
    if not resume and sweep.has_rows(rows_path):
        raise sweep_file.SweepError('%s: already holds a search\'s rows: --resume to go on with it, or choose another '
                                    '--output' % rows_path)
    columns = ['index', 'spec'] + search.keys + list(EXTRA_COLUMNS) + list(sweep.RESULT_COLUMNS)
    rows, existing = rows_file.open_rows(rows_path, columns)
    traj = rows_file.open_trajectories(os.path.join(output, 'trajectories.jsonl'))
    os.makedirs(os.path.join(output, sweep_report.PICTURES), exist_ok=True)
    dists = distributions(search)
    study = optuna.create_study(direction='minimize', sampler=sampler_of(search))
    for row in sorted(existing, key=lambda r: int(r['index'])):
        params = {k: dists[k].to_external_repr(dists[k].to_internal_repr(_typed(search.space[k], row[k])))
                  for k in search.keys}
        study.add_trial(optuna.trial.create_trial(params=params, distributions=dists, value=float(row['objective'])))
    done = len(existing)
    writing = sweep.Writing(output, rows, traj, columns, search.budget - done, search.report)
    progress = sweep.Progress(search.budget, done, stream, 'search', 'failure')
    client, cluster = sweep.client_for(scheduler, workers)
    logs_root = os.path.abspath(os.path.join(output, 'graphs'))
    token = logs_back.claim(logs_root)
    try:
        expected = worker_check.expected(client, cluster, _corners(search))
        while done < search.budget:
            trials = [study.ask(dists) for _ in range(min(search.batch, search.budget - done))]
            specs = [(done + n, dict(t.params), spec_of(search, t.params)) for n, t in enumerate(trials)]
            args = [(s.to_dict(), os.path.join(logs_root, 'episode-%05d' % i),
                     writing.choice if writing.keep > 0 else 'none', token, expected) for i, _, s in specs]
            futures = [client.submit(sweep.run_row, *a, pure=False) for a in args]
            for trial, (i, assignment, spec), future, a in zip(trials, specs, futures, args):
                result = worker_check.right_result(client, future, lambda: client.submit(sweep.run_row, *a, pure=False),
                                                   progress.stream)
                objective, failing = judged(search, result)
                study.tell(trial, objective)
                if not failing:
                    result.pop('picture_png', None)
                writing.write(i, dict(assignment, objective=objective, failing=failing), spec, result)
                progress.update('failure' if failing else result['outcome'])
            done += len(trials)
    finally:
        graph_episode.close_kept_graphs(client, interrupted=sys.exc_info()[0] is not None)
        for handle in (rows, traj, client):
            handle.close()
        if cluster is not None:
            cluster.close()
    return sweep.read_rows(rows_path)


def _corners(search):
    """Episodes of ``search`` at its space's first values, one for each controller it may choose (what a worker is
    checked for)."""
    first = {k: d[1][0] if d[0] == 'choice' else d[1] for k, d in search.space.items()}
    controllers = search.space['controller'][1] if search.space.get('controller', ('',))[0] == 'choice' else [None]
    return [spec_of(search, dict(first, **({'controller': c} if c is not None else {}))) for c in controllers]


def _typed(dim, text):
    if dim[0] == 'int':
        return int(float(text))
    if dim[0] == 'float':
        return float(text)
    return next((v for v in dim[1] if str(v) == text), text)


def main(argv=None):
    parser = cli.parser('search', ' '.join(__doc__.split('\n\n')[0].split()))
    parser.add_argument('spec', help='the search file (YAML)')
    parser.add_argument('--output', help='directory for rows.csv, pictures/ and report.html (default: searches/NAME)')
    sweep.add_cluster_arguments(parser)
    args = parser.parse_args(argv)
    try:
        search = load(args.spec)
    except sweep_file.SweepError as error:
        print('search: %s' % error, file=sys.stderr)
        return 2
    output = args.output or os.path.join('searches', search.name)
    print('search %s: at most %d episodes, %s sampler -> %s' % (search.name, search.budget, search.sampler, output),
          flush=True)
    try:
        rows = run(search, output, sweep.scheduler_of(args.scheduler, args.tls), args.workers, args.resume)
    except sweep_file.SweepError as error:
        print('search: %s' % error, file=sys.stderr)
        return 2
    except (KeyboardInterrupt, RuntimeError) as error:
        if not cli.interrupted(error):
            raise
        print('\nsearch: interrupted; the rows done are kept: run again with --resume to go on', file=sys.stderr)
        return 130
    sweep_report.report(sweep_file.Sweep(search.name, search.keys, [], None, search.report, search.text), rows,
                        output)
    failing = [r for r in rows if r.get('failing') == 'True']
    first = min((int(r['index']) for r in failing), default=None)
    print('search %s: %d episodes, %d failing%s' % (search.name, len(rows), len(failing),
          '' if first is None else ' (the first at episode %d)' % first))
    return 0
