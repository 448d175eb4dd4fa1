"""Run a sweep of episodes on Dask: ``rosrun closed_loop sweep SPEC.yaml`` or
``python3 -m closed_loop.batch.sweep SPEC.yaml``.

The sweep file (``closed_loop.batch.sweep_file``) is checked whole before anything runs. The episodes
(``closed_loop.batch.episode.run_episode``) then run on a Dask cluster: by default a local one started here,
one single-threaded worker process per core, listening on 127.0.0.1 only; ``--scheduler
tcp://HOST:PORT`` sends them to a cluster already running (``dask scheduler`` and ``dask worker``
on machines that have this package installed). Each finished episode is one row of
``OUTPUT/rows.csv`` at once (the spec, as JSON and one column per grid key, and the result), so an
interrupted sweep keeps what it did, and ``--resume`` runs only what is missing. An episode that
raises is a row with outcome ``error`` and its message; the sweep goes on. At the end: a summary table
(also ``OUTPUT/summary.txt``) and ``OUTPUT/plot.png``. A graph episode (a controller that is a launch file
or a node: ``closed_loop.batch.graph_episode``) keeps its files in ``OUTPUT/graphs/episode-INDEX``; when a
local cluster closes, done or interrupted, the sweep waits for those graphs to be down.
"""
import argparse
import csv
import json
import math
import os
import sys
import time

import numpy

from closed_loop.batch import graph_keeper, sweep_file
from closed_loop.sim import quiet
from closed_loop.batch.episode import EpisodeSpec, run_episode

RESULT_COLUMNS = ('outcome', 'mode', 'time_s', 'contacts', 'min_clearance_m', 'final_x', 'final_y', 'final_yaw',
                  'goal_error_m', 'path_m', 'peak_decel_mps2', 'wall_s', 'error', 'why', 'logs')
_CACHE = {}     # per worker process: worlds and profiles loaded once


def row_key(spec):
    """A row's identity: its spec, as canonical JSON."""
    return json.dumps(spec.to_dict(), sort_keys=True)


def run_row(spec_fields, logs=None):
    """One episode on a worker: the result columns (never raises; an episode that did is outcome 'error').
    A graph episode's files go into the folder ``logs``."""
    try:
        r = run_episode(EpisodeSpec.from_dict(spec_fields), _CACHE, logs)
        row = {'outcome': r.outcome, 'mode': r.mode, 'time_s': r.time_s, 'contacts': r.contacts,
               'min_clearance_m': r.min_clearance_m, 'final_x': r.final_pose[0], 'final_y': r.final_pose[1],
               'final_yaw': r.final_pose[2], 'goal_error_m': r.goal_error_m, 'path_m': r.path_m,
               'peak_decel_mps2': r.peak_decel_mps2, 'wall_s': r.wall_s, 'error': r.error or '', 'why': r.why,
               'logs': r.logs or ''}
        if r.trajectory is not None:
            row['trajectory'] = r.trajectory
        return row
    except Exception as error:      # recorded in its row; the sweep goes on
        return dict({c: '' for c in RESULT_COLUMNS}, outcome='error', error='%s: %s' % (type(error).__name__, error))


class Progress:
    """A progress line on stderr: counts, errors, elapsed and an estimated finish."""

    def __init__(self, total, done=0, stream=sys.stderr):
        self.total, self.done, self.errors, self.stream = total, done, 0, stream
        self.started, self.first, self.shown = time.monotonic(), done, 0.0
        self.tty = hasattr(stream, 'isatty') and stream.isatty()

    def update(self, outcome):
        self.done += 1
        self.errors += outcome == 'error'
        now = time.monotonic()
        if self.tty and now - self.shown < 0.2 and self.done < self.total:
            return
        if not self.tty and self.done < self.total and (self.done * 10) // self.total == ((self.done - 1) * 10) // self.total:
            return
        self.shown = now
        elapsed = now - self.started
        rate = (self.done - self.first) / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        line = 'sweep %d/%d [%s%s] %3.0f%%  %d errors  %s elapsed, %s left' % (
            self.done, self.total, '#' * filled, '-' * (width - filled), 100.0 * self.done / max(self.total, 1),
            self.errors, _clock(elapsed), _clock(left) if math.isfinite(left) else '?')
        self.stream.write(('\r' + line) if self.tty else line + '\n')
        if self.tty and self.done >= self.total:
            self.stream.write('\n')
        self.stream.flush()


def _clock(seconds):
    seconds = int(round(seconds))
    return '%d:%02d:%02d' % (seconds // 3600, seconds // 60 % 60, seconds % 60) if seconds >= 3600 \
        else '%d:%02d' % (seconds // 60, seconds % 60)


def read_rows(path):
    """The rows of a sweep's CSV file, as dicts of strings ([] if it does not exist)."""
    if not os.path.exists(path):
        return []
    with open(path, newline='') as f:
        return list(csv.DictReader(f))


def _client(scheduler, workers):
    import distributed
    if scheduler:
        return distributed.Client(scheduler, timeout='20s'), None
    cluster = distributed.LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                                       processes=True, host='127.0.0.1', dashboard_address=None)
    return distributed.Client(cluster), cluster


def run(sweep, output, scheduler=None, workers=None, resume=False, stream=sys.stderr):
    """Run ``sweep`` (a ``sweep_file.Sweep``) into the directory ``output``; returns all its rows."""
    import distributed
    os.makedirs(output, exist_ok=True)
    rows_path = os.path.join(output, 'rows.csv')
    existing = read_rows(rows_path)
    if existing and not resume:
        raise sweep_file.SweepError('%s: already holds a sweep\'s rows: --resume to go on with it, or choose '
                                    'another --output' % rows_path)
    done = {row['spec'] for row in existing}
    columns = ['index', 'spec'] + list(sweep.keys) + list(RESULT_COLUMNS)
    todo = [(i, a, s) for i, (a, s) in enumerate(sweep.specs) if row_key(s) not in done]
    progress = Progress(len(sweep.specs), len(sweep.specs) - len(todo), stream)
    new_file = not existing
    with open(rows_path, 'a', newline='') as f, open(os.path.join(output, 'trajectories.jsonl'), 'a') as traj:
        writer = csv.DictWriter(f, columns, extrasaction='ignore')
        if new_file:
            writer.writeheader()
            f.flush()
        if todo:
            client, cluster = _client(scheduler, workers)
            logs_root = os.path.abspath(os.path.join(output, 'graphs'))
            try:
                futures = {client.submit(run_row, s.to_dict(), os.path.join(logs_root, 'episode-%05d' % i),
                                         key='episode-%d-%s' % (i, _digest(s)), pure=False): (i, a, s)
                           for i, a, s in todo}
                for future in distributed.as_completed(futures):
                    i, assignment, spec = futures.pop(future)
                    result = future.result()
                    row = dict({k: _cell(v) for k, v in assignment.items()}, index=i, spec=row_key(spec),
                               **{c: result.get(c, '') for c in RESULT_COLUMNS})
                    writer.writerow(row)
                    f.flush()
                    if 'trajectory' in result:
                        traj.write(json.dumps({'index': i, 'trajectory': result['trajectory']}) + '\n')
                        traj.flush()
                    progress.update(result['outcome'])
            finally:
                for future in list(futures):
                    future.cancel()
                client.close()
                if cluster is not None:
                    cluster.close()
                    _wait_graphs_down(logs_root)
    return read_rows(rows_path)


def _wait_graphs_down(logs_root, timeout_s=graph_keeper.GRACE_S + 5.0):
    """After a local cluster has closed (done, or Ctrl-C): the keepers of graph episodes it was running shut
    their graphs down once their workers are gone; wait for that, then kill whatever is left of them."""
    prefix = logs_root + os.sep
    deadline = time.monotonic() + timeout_s
    while graph_keeper.marked_processes(prefix) and time.monotonic() < deadline:
        time.sleep(0.2)
    graph_keeper.kill_marked(prefix)


def _digest(spec):
    import hashlib
    return hashlib.sha1(row_key(spec).encode()).hexdigest()[:12]


def _cell(value):
    return json.dumps(value) if isinstance(value, (dict, list, tuple)) else value


def summarize(rows, keys):
    """Lines of a table: per combination of the grid's keys but ``seed``, the episodes, their outcomes,
    contact rate, least clearance and mean time."""
    group_keys = [k for k in keys if k != 'seed']
    groups = {}
    for row in rows:
        groups.setdefault(tuple(row.get(k, '') for k in group_keys), []).append(row)
    header = group_keys + ['episodes', 'outcomes', 'contact rate', 'min clearance', 'mean time']
    lines = [header]
    for values, members in sorted(groups.items(), key=lambda item: [_sortable(v) for v in item[0]]):
        outcomes = {}
        for row in members:
            outcomes[row['outcome']] = outcomes.get(row['outcome'], 0) + 1
        clear = [float(r['min_clearance_m']) for r in members if r['outcome'] != 'error']
        times = [float(r['time_s']) for r in members if r['outcome'] != 'error']
        contacts = [int(r['contacts']) > 0 for r in members if r['outcome'] != 'error']
        lines.append(list(values) + [str(len(members)), ' '.join('%s %d' % kv for kv in sorted(outcomes.items())),
                                     '%.2f' % numpy.mean(contacts) if contacts else '-',
                                     '%.3f m' % min(clear) if clear else '-',
                                     '%.1f s' % numpy.mean(times) if times else '-'])
    widths = [max(len(str(line[i])) for line in lines) for i in range(len(header))]
    return ['  '.join(str(cell).ljust(w) for cell, w in zip(line, widths)).rstrip() for line in lines]


def _sortable(value):
    try:
        return (0, float(value), '')
    except (TypeError, ValueError):
        return (1, 0.0, str(value))


def plot(rows, x_key, line_key, path, title):
    """Contact rate and least clearance against ``x_key``, one line per value of ``line_key``, as a PNG."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    lines = {}
    for row in rows:
        if row['outcome'] == 'error':
            continue
        group = lines.setdefault(row.get(line_key, '') if line_key else '', {})
        group.setdefault(float(row[x_key]), []).append(row)
    figure, (top, bottom) = pyplot.subplots(2, 1, figsize=(7, 6.5), sharex=True)
    for label, points in sorted(lines.items(), key=lambda item: _sortable(item[0])):
        xs = sorted(points)
        name = '%s = %s' % (line_key.split('.')[-1], label) if line_key else None
        top.plot(xs, [numpy.mean([int(r['contacts']) > 0 for r in points[x]]) for x in xs], 'o-', label=name)
        bottom.plot(xs, [min(float(r['min_clearance_m']) for r in points[x]) for x in xs], 'o-', label=name)
    top.set_ylabel('contact rate')
    top.set_ylim(-0.05, 1.05)
    bottom.set_ylabel('least clearance (m, ground truth)')
    bottom.axhline(0.0, color='grey', linewidth=0.8)
    bottom.set_xlabel(x_key)
    for axes in (top, bottom):
        axes.grid(True, alpha=0.3)
        if line_key:
            axes.legend()
    top.set_title(title)
    figure.tight_layout()
    figure.savefig(path, dpi=100)
    pyplot.close(figure)


def report(sweep, rows, output, stream=sys.stdout):
    """The summary table (printed and in ``summary.txt``) and the plot, if the sweep has an x to plot."""
    lines = summarize(rows, sweep.keys)
    text = '\n'.join(lines) + '\n'
    stream.write(text)
    with open(os.path.join(output, 'summary.txt'), 'w') as f:
        f.write(text)
    choice = sweep.plot or _default_plot(sweep.keys, rows)
    if choice is not None:
        path = os.path.join(output, 'plot.png')
        plot(rows, choice['x'], choice.get('lines'), path, sweep.name)
        stream.write('plot: %s\n' % path)


def _default_plot(keys, rows):
    numeric = [k for k in keys if k != 'seed' and rows and all(_sortable(r.get(k))[0] == 0 for r in rows)]
    if not numeric:
        return None
    return {'x': numeric[0], 'lines': numeric[1] if len(numeric) > 1 else None}


def add_cluster_arguments(parser):
    """The options every sweep command has: where it runs, and --resume."""
    parser.add_argument('--scheduler', help='tcp://HOST:PORT of a running Dask scheduler (default: a local '
                        'cluster of one worker process per core)')
    parser.add_argument('--workers', type=int, help='local cluster size (default: the number of cores)')
    parser.add_argument('--resume', action='store_true', help='go on with the rows already in --output')
    parser.add_argument('--verbose', action='store_true', help="let pybullet's own output (its banner, its URDF "
                        'importer warnings) through to the terminal')


def run_command(prog, make, output, args):
    """What a sweep command does: build the sweep (``make()``), run it into ``output`` (default
    sweeps/NAME) and report. Returns (exit status, sweep, rows); a refused sweep (2) or Ctrl-C (130)
    is said on stderr, with no sweep or rows."""
    quiet.set_verbose(args.verbose)
    try:
        built = make()
        output = output or os.path.join('sweeps', built.name)
        print('%s %s: %d episodes -> %s' % (prog, built.name, len(built.specs), output), flush=True)
        rows = run(built, output, args.scheduler, args.workers, args.resume)
    except sweep_file.SweepError as error:
        print('%s: %s' % (prog, error), file=sys.stderr)
        return 2, None, None
    except KeyboardInterrupt:
        print('\n%s: interrupted; the rows done are kept: run again with --resume to finish' % prog, file=sys.stderr)
        return 130, None, None
    report(built, rows, output)
    return 0, built, rows


def main(argv=None):
    parser = argparse.ArgumentParser(prog='sweep', description=__doc__.splitlines()[0])
    parser.add_argument('spec', help='the sweep file (YAML)')
    parser.add_argument('--output', help='directory for rows.csv, summary.txt and plot.png '
                        '(default: sweeps/NAME in the current directory)')
    add_cluster_arguments(parser)
    args = parser.parse_args(argv)
    status, _, rows = run_command('sweep', lambda: sweep_file.load(args.spec), args.output, args)
    if status:
        return status
    errors = sum(r['outcome'] == 'error' for r in rows)
    print('episodes: %d, errors: %d' % (len(rows), errors))
    return 1 if errors else 0


if __name__ == '__main__':
    sys.exit(main())
