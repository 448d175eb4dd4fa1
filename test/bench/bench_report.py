#!/usr/bin/env python3
"""Seeing failures, and what it costs: one episode's picture (a navigator in a generated cluttered world), a
sweep's report.html for 10,000 rows, and sweeps of 1,000, 10,000 and 100,000 episodes that all fail (0.2 s in an empty
world: every one times out) on a local cluster of 2 workers with the default report (100 pictures): wall
time, pictures written, trajectories sent back, and the sweep process's own peak memory, for the whole command: the
episodes, then the report (summary, plot and page, from one pass over rows.csv).

Run: ``python3 test/bench/bench_report.py [COUNT ...]`` inside ``source env.sh`` (``make bench`` does that, with
none: everything; the sweep of 100,000 takes about half an hour on 2 cores).
Figures, not pass/fail: the exit status is non-zero only when something could not run.
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import types

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop.batch import pictures, report_page  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402
from closed_loop.batch.tally import Tally  # noqa: E402

#: The sweeps whose client is measured: its memory and its time an episode should stay flat.
COUNTS = (1000, 10000, 100000)
def picture_cost():
    spec = EpisodeSpec(world={'generator': {'seed': 5, 'fill_ratio': 0.5}}, robot='jackal', controller='avoid_obstacles',
                       time_limit_s=40.0, keep_trajectory=True)
    result = run_episode(spec)
    cache, times, size = {}, [], 0
    for _ in range(10):
        started = time.process_time()
        size = len(pictures.episode_picture(spec, result, cache))
        times.append(time.process_time() - started)
    print('picture: %s in a generated world, %d track rows: %.0f ms CPU (median of 10), %.0f kB'
          % (result.outcome, len(result.trajectory), 1000 * statistics.median(times), size / 1024.0))


def page_cost():
    with tempfile.TemporaryDirectory() as out:
        os.makedirs(os.path.join(out, 'pictures'))
        rows = [{'index': str(i), 'spec': json.dumps({'seed': i}), 'seed': str(i), 'outcome': 'timed_out' if i % 3 else
                 'stopped', 'contacts': '0', 'why': 'timed_out at (0.00, 0.00) after 0.2 s'} for i in range(10000)]
        for i in range(1, 300, 3):
            open(os.path.join(out, 'pictures', 'episode-%05d.png' % i), 'wb').close()
        sweep = types.SimpleNamespace(name='page', keys=['seed'], report={'pictures': 'failures'}, text='name: page')
        started = time.process_time()
        tally = Tally.of(rows, sweep.keys, pictured=range(1, 300, 3))
        report_page.write(os.path.join(out, 'report.html'), sweep, tally, ['episodes'], [['10000']], None,
                          lambda i: os.path.join(out, 'pictures', 'episode-%05d.png' % int(i)))
        print('report.html of 10,000 rows (6,667 not as meant, 1,000 listed, 100 pictures): %.0f ms CPU, %.0f kB'
              % (1000 * (time.process_time() - started), os.path.getsize(os.path.join(out, 'report.html')) / 1024.0))


def large(count):
    with tempfile.TemporaryDirectory() as out:
        done = subprocess.run([sys.executable, os.path.join(ROOT, 'test', 'bench', 'large_sweep.py'), str(count),
                               os.path.join(out, 'sweep')], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              universal_newlines=True, timeout=60 + 0.1 * count)
        if done.returncode != 0:
            print(done.stdout[-3000:])
            raise SystemExit(1)
        figures = json.loads(done.stdout.strip().splitlines()[-1])
    print('the sweep command on %d failing episodes, 2 workers, its report included: %.0f s (%.0f a minute), %d '
          'pictures, %d bytes of trajectories sent back, report.html %.0f kB, sweep process peak %.0f MB'
          % (figures['rows'], figures['wall_s'], 60.0 * figures['rows'] / figures['wall_s'], figures['pictures'],
             figures['trajectory_bytes'], figures['page_bytes'] / 1024.0, figures['peak_mb']))
    return figures


def main(argv=None):
    """Everything, or (with counts given) only the sweeps of those many episodes."""
    counts = [int(a) for a in (sys.argv[1:] if argv is None else argv)]
    if not counts:
        picture_cost()
        page_cost()
    figures = [large(count) for count in counts or COUNTS]
    first = figures[0]
    for f in figures[1:]:
        print('the sweep process at %d episodes against %d: peak memory %.0f MB against %.0f MB (%.2fx), %.2f ms of '
              'wall time an episode against %.2f ms (%.2fx)'
              % (f['rows'], first['rows'], f['peak_mb'], first['peak_mb'], f['peak_mb'] / first['peak_mb'],
                 1e3 * f['wall_s'] / f['rows'], 1e3 * first['wall_s'] / first['rows'],
                 (f['wall_s'] / f['rows']) / (first['wall_s'] / first['rows'])))
    return 0


if __name__ == '__main__':
    sys.exit(main())
