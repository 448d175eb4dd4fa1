"""Run a sweep of episodes on Dask: ``rosrun closed_loop sweep SPEC.yaml`` or
``python3 -m closed_loop.batch.sweep SPEC.yaml``.

The sweep file (``closed_loop.batch.sweep_file``) is checked whole before anything runs. The episodes
(``closed_loop.batch.episode.run_episode``) then run on a Dask cluster: by default a local one started here,
one single-threaded worker process per core, listening on 127.0.0.1 only; ``--scheduler
tcp://HOST:PORT`` (or ``tls://HOST:PORT --tls DIR``) sends them to a cluster already running (``dask scheduler``
and ``dask worker`` on machines that have this package installed; ``closed_loop.batch.cluster``). Each finished episode is one row of
``OUTPUT/rows.csv`` at once, whole or not at all (the spec, as JSON and one column per grid key, and the
result; ``closed_loop.batch.rows_file``), so an interrupted sweep keeps what it did, and ``--resume`` sets
aside a row it left torn and runs only what is missing. An episode that
raises is a row with outcome ``error`` and its message; the sweep goes on. Episodes not as meant (collided, failed, timed
out, error, any contact) get a picture, drawn where they ran (``OUTPUT/pictures/episode-INDEX.png``; the sweep
file's ``report:`` chooses, ``closed_loop.batch.pictures``). At the end: a summary table (also
``OUTPUT/summary.txt``), ``OUTPUT/plot.png`` and ``OUTPUT/report.html`` (``closed_loop.batch.sweep_report``). A graph episode (a controller that is a launch file
or a node: ``closed_loop.batch.graph_episode``) keeps its files in ``OUTPUT/graphs/episode-INDEX``; when a
local cluster closes, done or interrupted, the sweep waits for those graphs to be down.
"""
import dataclasses
import json
import logging
import math
import os
import sys
import itertools
import time

from closed_loop import cli
from closed_loop.batch import graph_episode, logs_back, pictures, rows_file, sweep_file, sweep_report, worker_check
from closed_loop.batch.graph_episode import set_aside
from closed_loop.batch.cluster import add_arguments as add_cluster_arguments, client_for, scheduler_of
from closed_loop.sim import quiet
from closed_loop.batch.episode import EpisodeSpec, run_episode
from closed_loop.batch.spec import benchmark_score

RESULT_COLUMNS = ('outcome', 'mode', 'time_s', 'contacts', 'min_clearance_m', 'final_x', 'final_y', 'final_yaw',
                  'goal_error_m', 'path_m', 'peak_decel_mps2', 'missed_ticks', 'benchmark_time_s', 'benchmark_score',
                  'wall_s', 'error', 'why', 'logs')
_CACHE = {}     # per worker process: worlds and profiles loaded once
#: Episodes handed to the cluster ahead of the results: this many per worker thread (at least WINDOW_MIN),
#: topped up in one batch once half of them have come back, so that neither this process nor the scheduler holds a
#: task per episode of a sweep of thousands, and a sweep that has drawn its last picture stops asking for more
#: within that many.
WINDOW_PER_THREAD, WINDOW_MIN = 8, 16
#: Every this many episodes, Dask's memo of task names is emptied (see _run_todo).
FORGET_NAMES_EVERY = 5000
#: What the rest of a sweep is thought to need on disk before any is measured: a row, a picture (bytes), and
#: the report at the end (summary, plot, page).
ROW_BYTES, PICTURE_BYTES, REPORT_BYTES = 1024, 64 * 1024, 512 * 1024


def row_key(spec):
    """A row's identity: its spec, as canonical JSON."""
    return json.dumps(spec.to_dict(), sort_keys=True)


def run_row(spec_fields, logs=None, choice='none', token=None, expected=None):
    """One episode on a worker: the result columns (never raises; an episode that did is outcome 'error').
    A graph episode's files go into the folder ``logs``, or, where this worker does not see the client's files
    (``token``: ``closed_loop.batch.logs_back``), into a folder of its own that comes back packed with the row.
    ``expected``: the client's fingerprint; a worker that differs runs nothing (``closed_loop.batch.worker_check``).
    ``choice``: which episodes get a picture (``report.pictures``): the picture is drawn here, from a trajectory
    kept only for it, and comes back as PNG bytes (``picture_png``); the trajectory comes back only if the spec
    asks for it (``keep_trajectory``)."""
    local = None
    wrong = worker_check.matches(expected)
    if wrong:
        import distributed
        return {'wrong_worker': wrong, 'worker': distributed.get_worker().address}
    try:
        spec = EpisodeSpec.from_dict(spec_fields)
        if token is not None and logs and isinstance(spec.controller, dict) and \
                not logs_back.shares(os.path.dirname(logs), token):
            local = logs_back.local_folder()
        r = run_episode(dataclasses.replace(spec, keep_trajectory=True) if choice != 'none' else spec, _CACHE,
                        os.path.join(local, 'episode') if local else logs)
        row = {'outcome': r.outcome, 'mode': r.mode, 'time_s': r.time_s, 'contacts': r.contacts,
               'min_clearance_m': r.min_clearance_m, 'final_x': r.final_pose[0], 'final_y': r.final_pose[1],
               'final_yaw': r.final_pose[2], 'goal_error_m': r.goal_error_m, 'path_m': r.path_m,
               'peak_decel_mps2': r.peak_decel_mps2, 'missed_ticks': r.missed_ticks,
               'benchmark_time_s': _blank(r.benchmark_time_s), 'benchmark_score': _blank(benchmark_score(spec, r)),
               'wall_s': r.wall_s, 'error': r.error or '',
               'why': r.why, 'logs': (logs if local else r.logs) or ''}
        if local:
            logs_back.send_back(os.path.join(local, 'episode'), row)
        if spec.keep_trajectory:
            row['trajectory'] = r.trajectory
        if pictures.wanted(choice, r.outcome, r.contacts):
            row['picture_png'] = pictures.episode_picture(spec, r, _CACHE)
        return row
    except Exception as error:      # recorded in its row; the sweep goes on
        return dict({c: '' for c in RESULT_COLUMNS}, outcome='error', error='%s: %s' % (type(error).__name__, error))
    finally:
        if local:
            _remove_empty(local)


def _remove_empty(folder):
    try:
        os.rmdir(folder)
    except OSError:
        pass


class Progress:
    """A progress line on stderr: counts, errors (``what`` failing, for a search), elapsed and an estimated
    finish."""

    def __init__(self, total, done=0, stream=sys.stderr, label='sweep', what='error'):
        self.total, self.done, self.errors, self.stream = total, done, 0, stream
        self.label, self.what = label, what
        self.started, self.first, self.shown = time.monotonic(), done, 0.0
        self.tty = hasattr(stream, 'isatty') and stream.isatty()

    def update(self, outcome):
        self.done += 1
        self.errors += outcome == self.what
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
        line = '%s %d/%d [%s%s] %3.0f%%  %d %ss  %s elapsed, %s left' % (
            self.label, self.done, self.total, '#' * filled, '-' * (width - filled),
            100.0 * self.done / max(self.total, 1), self.errors, self.what, _clock(elapsed),
            _clock(left) if math.isfinite(left) else '?')
        self.stream.write(('\r' + line) if self.tty else line + '\n')
        if self.tty and self.done >= self.total:
            self.stream.write('\n')
        self.stream.flush()


def _clock(seconds):
    seconds = int(round(seconds))
    return '%d:%02d:%02d' % (seconds // 3600, seconds // 60 % 60, seconds % 60) if seconds >= 3600 \
        else '%d:%02d' % (seconds // 60, seconds % 60)


def read_rows(path):
    """The rows of a sweep's CSV file, as a list of dicts of strings ([] if it does not exist); to read them one
    at a time, ``closed_loop.batch.rows_file.Rows``."""
    return list(rows_file.Rows(path)) if os.path.exists(path) else []


def run(sweep, output, scheduler=None, workers=None, resume=False, stream=sys.stderr):
    """Run ``sweep`` (a ``sweep_file.Sweep``) into the directory ``output``; returns its rows, read from the file
    as they are iterated (``rows_file.Rows``). A disk too full for the next row raises ``rows_file.NoRoom`` (every
    row before it whole)."""
    os.makedirs(output, exist_ok=True)
    rows_path = os.path.join(output, 'rows.csv')
    if not resume and has_rows(rows_path):
        raise sweep_file.SweepError('%s: already holds a sweep\'s rows: --resume to go on with it, or choose '
                                    'another --output' % rows_path)
    columns = ['index', 'spec'] + list(sweep.keys) + list(RESULT_COLUMNS)
    try:
        done = set()                # the episodes already run: their specs' digests (a row's memory, not its text)
        rows, _ = rows_file.open_rows(rows_path, columns, lambda row: done.add(_key_digest(row['spec'])))
        traj = rows_file.open_trajectories(os.path.join(output, 'trajectories.jsonl'))
        os.makedirs(os.path.join(output, sweep_report.PICTURES), exist_ok=True)
    except OSError as error:
        if error.errno in rows_file.NO_ROOM:
            raise rows_file.no_room(output, REPORT_BYTES) from None
        raise
    if rows.torn:
        stream.write('sweep: %d torn or corrupt line(s) of %s set aside in %s.torn; their episodes run again\n'
                     % (rows.torn, rows_path, rows_path))
    # The grid's episodes are made as they are handed out (a sweep of a million does not make them first).
    todo = ((i, a, s) for i, (a, s) in enumerate(sweep.specs) if _key_digest(row_key(s)) not in done)
    total = len(sweep.specs)
    left = max(0, total - len(done))
    writing = Writing(output, rows, traj, columns, left, sweep.report)
    try:
        if left:
            _run_todo(todo, writing, Progress(total, total - left, stream), scheduler, workers)
    finally:
        rows.close()
        traj.close()
    return rows_file.Rows(rows_path)


def has_rows(path):
    """Whether the rows file at ``path`` holds anything past its header line."""
    try:
        with open(path, 'rb') as f:
            f.readline()
            return bool(f.read(1))
    except FileNotFoundError:
        return False


class Writing:
    """Where a sweep's results go: each row whole to rows.csv, its picture and trajectory beside it; a full
    disk becomes ``rows_file.NoRoom`` with the room the rest needs."""

    def __init__(self, output, rows, traj, columns, left, report):
        self.output, self.rows, self.traj, self.columns, self.left = output, rows, traj, columns, left
        self.keep = report['max_pictures'] - len(os.listdir(os.path.join(output, sweep_report.PICTURES)))
        self.choice = report['pictures'] if self.keep > 0 else 'none'
        self.row_bytes, self.picture_bytes = ROW_BYTES, PICTURE_BYTES          # the largest yet

    def needed(self):
        """About how many bytes the rest of the sweep needs: its rows, its pictures, the report."""
        pictures = max(0, min(self.keep, self.left)) * self.picture_bytes if self.choice != 'none' else 0
        return self.left * self.row_bytes + pictures + REPORT_BYTES

    def write(self, i, assignment, spec, result):
        png = result.pop('picture_png', None)
        logs_back.receive(result, result.get('logs'), set_aside)
        row = dict({k: _cell(v) for k, v in assignment.items()}, index=i, spec=row_key(spec),
                   **{c: result.get(c, '') for c in RESULT_COLUMNS})
        line = rows_file.csv_line(self.columns, row)
        self.row_bytes = max(self.row_bytes, len(line.encode()))
        try:
            if png is not None and self.keep > 0:
                self.picture_bytes = max(self.picture_bytes, len(png))
                _write_whole(sweep_report.picture_path(self.output, i), png)
                self.keep -= 1
            if 'trajectory' in result:
                self.traj.append(json.dumps({'index': i, 'trajectory': result['trajectory']}) + '\n')
            self.rows.append(line)
        except OSError as error:
            if error.errno in rows_file.NO_ROOM:
                raise rows_file.no_room(self.output, self.needed()) from None
            raise
        self.left -= 1


def _write_whole(path, data):
    """``data`` to ``path`` whole or not at all (a file beside it, renamed)."""
    part = path + '.part'
    try:
        with open(part, 'wb') as f:
            f.write(data)
        os.replace(part, path)
    except OSError:
        if os.path.exists(part):
            os.remove(part)
        raise


def _run_todo(todo, writing, progress, scheduler, workers):
    """Run the episodes ``todo`` ((index, assignment, spec) each) on the cluster, handing it WINDOW_PER_THREAD
    per worker thread ahead, and write each result as it comes."""
    import distributed
    from dask import utils as dask_utils
    client, cluster = client_for(scheduler, workers)
    logs_root = os.path.abspath(os.path.join(writing.output, 'graphs'))
    token = logs_back.claim(logs_root)
    window = max(WINDOW_MIN, WINDOW_PER_THREAD * sum(client.nthreads().values()))
    refill = max(1, window // 2)        # the window is topped up once half of it has come back
    first = list(itertools.islice(todo, window))
    pending = itertools.chain(first, todo)
    futures = {}
    running = distributed.as_completed()
    expected = []

    def submit(count):
        batch = list(itertools.islice(pending, count))
        if not batch:
            return
        wanted = writing.choice if writing.keep > 0 else 'none'
        args = [(s.to_dict(), os.path.join(logs_root, 'episode-%05d' % i), wanted, token, expected[0])
                for i, _, s in batch]
        # Handed over in batches, each of one task group ('episode'): Dask's scheduler keeps a record of each
        # submission and of each task group for as long as the cluster lives, so one of either per episode
        # would grow the sweep's process with every episode.
        for future, (i, a, s), row_args in zip(client.map(run_row, *zip(*args), key=[('episode', i, _digest(s))
                                                                                  for i, _, s in batch], pure=False),
                                               batch, args):
            futures[future] = (i, a, s, row_args)
            running.add(future)
    try:
        expected.append(worker_check.expected(client, cluster, [s for _, _, s in first]))
        submit(window)
        for future in running:
            i, assignment, spec, args = futures.pop(future)
            result = worker_check.right_result(client, future, lambda: client.submit(run_row, *args, pure=False),
                                               progress.stream)
            writing.write(i, assignment, spec, result)
            progress.update(result['outcome'])
            if progress.done % FORGET_NAMES_EVERY == 0:
                # Dask memoises the name of every task key it has seen, up to 100,000 (dask.utils.key_split, a
                # functools cache), in this process, where a local cluster's scheduler runs; a sweep's keys are
                # each seen once, so the memo only grows the sweep's memory: emptied now and then.
                dask_utils.key_split.cache_clear()
            if window - len(futures) >= refill:
                submit(window - len(futures))
    finally:
        if sys.exc_info()[0] is not None and not quiet.verbose():
            # Interrupted (Ctrl-C, a full disk): the cluster goes down under running episodes, and Dask says so
            # at every level; the sweep says what happened itself.
            logging.getLogger('distributed').setLevel(logging.CRITICAL)
        for future in list(futures):
            future.cancel()
        graph_episode.close_kept_graphs(client, interrupted=sys.exc_info()[0] is not None)
        client.close()
        if cluster is not None:
            cluster.close()
            graph_episode.wait_graphs_down(logs_root)


def _digest(spec):
    return _digest_text(row_key(spec))


def _digest_text(text):
    import hashlib
    return hashlib.sha1(text.encode()).hexdigest()[:12]


def _key_digest(key):
    import hashlib
    return hashlib.sha1(key.encode()).digest()


def _cell(value):
    return json.dumps(value) if isinstance(value, (dict, list, tuple)) else value


def _blank(value):
    """A cell for what may not be there: '' for None."""
    return '' if value is None else value


def checking(done, total, stream=sys.stderr):
    """What a long check of a sweep file says: how far it is."""
    stream.write('checking the sweep file: %d of %d checks\n' % (done, total))
    stream.flush()


def run_command(prog, make, output, args, preface=None):
    """What a sweep command does: build the sweep (``make()``), run it into ``output`` (default
    sweeps/NAME) and report (``closed_loop.batch.sweep_report``; ``preface(rows)``: lines the page puts
    first). Returns (exit status, sweep, rows: a ``rows_file.Rows``, read as it is iterated); a refused sweep
    (2), a full disk (3: one line naming the folder and the room needed) or Ctrl-C (130) is said on stderr, with
    no sweep or rows."""
    quiet.set_verbose(args.verbose)
    try:
        built = make()
        output = output or os.path.join('sweeps', built.name)
        print('%s %s: %d episodes -> %s' % (prog, built.name, len(built.specs), output), flush=True)
        rows = run(built, output, scheduler_of(args.scheduler, args.tls), args.workers, args.resume)
        sweep_report.report(built, rows, output, preface=preface(rows) if preface else ())
    except rows_file.NoRoom as error:
        print('%s: %s' % (prog, error), file=sys.stderr)
        return 3, None, None
    except sweep_file.SweepError as error:
        print('%s: %s' % (prog, error), file=sys.stderr)
        return 2, None, None
    except (KeyboardInterrupt, RuntimeError) as error:
        if not cli.interrupted(error):
            raise
        print('\n%s: interrupted; the rows done are kept: run again with --resume to finish' % prog, file=sys.stderr)
        return 130, None, None
    except OSError as error:
        if error.errno not in rows_file.NO_ROOM:
            raise
        print('%s: %s' % (prog, rows_file.no_room(output, REPORT_BYTES)), file=sys.stderr)
        return 3, None, None
    return 0, built, rows


def main(argv=None):
    parser = cli.parser('sweep', ' '.join(__doc__.split('\n\n')[0].split()))
    parser.add_argument('spec', help='the sweep file (YAML), or the name of one this package ships (%s)'
                        % ', '.join(sweep_file.shipped()))
    parser.add_argument('--output', help='directory for rows.csv, summary.txt, plot.png, report.html and pictures/ '
                        '(default: sweeps/NAME in the current directory)')
    add_cluster_arguments(parser)
    args = parser.parse_args(argv)
    status, _, rows = run_command('sweep', lambda: sweep_file.load(args.spec, checking), args.output, args)
    if status:
        return status
    outcomes = [r['outcome'] == 'error' for r in rows]
    errors = sum(outcomes)
    print('episodes: %d, errors: %d' % (len(outcomes), errors))
    return 1 if errors else 0


if __name__ == '__main__':
    sys.exit(main())
