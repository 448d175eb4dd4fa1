#!/usr/bin/env python3
"""A sweep of graph episodes: 50 episodes of stop_on_obstacle run as its node (5 stop distances x 5 cruise
speeds x 2 worlds, each a ROS graph of its own at the default real_time_factor) on a local Dask cluster of
1 worker and of 2: episodes per minute of wall time, outcomes, errors, and what is left running afterwards.

Run: ``python3 test/bench/bench_graph_sweep.py`` inside ``source env.sh`` (``make bench`` does that).
Figures, not pass/fail: the exit status is non-zero only when something could not run.
"""
import collections
import os
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop import launcher  # noqa: E402
from closed_loop.batch import graph_episode, sweep, sweep_file  # noqa: E402

GRID = {'settings.stop_distance': [0.3, 0.4, 0.5, 0.6, 0.7], 'settings.cruise_speed': [0.3, 0.4, 0.5, 0.7, 1.0],
        'world': ['wall', 'red_box']}


def main():
    built = sweep_file.build('graph_sweep', {'controller': {'node': 'stop_on_obstacle'}, 'time_limit_s': 30.0}, GRID)
    print('%d graph episodes at real_time_factor %g' % (len(built.specs), graph_episode.REAL_TIME_FACTOR))
    per_minute = {}
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as out:
            started = time.monotonic()
            rows = sweep.run(built, out, workers=workers, stream=open(os.devnull, 'w'))
            wall = time.monotonic() - started
            outcomes = collections.Counter(r['outcome'] for r in rows)
            simulated = sum(float(r['time_s'] or 0) for r in rows)
            left = launcher.marked_processes(out)
        per_minute[workers] = 60.0 * len(rows) / wall
        print('%d worker%s: %d episodes in %.0f s: %.1f episodes per minute, %.1f simulated s per wall s; %s; '
              'left running: %d processes' % (workers, '' if workers == 1 else 's', len(rows), wall,
                                               per_minute[workers], simulated / wall,
                                               ', '.join('%s %d' % kv for kv in sorted(outcomes.items())), len(left)))
    print('2 workers / 1 worker: %.2fx' % (per_minute[2] / per_minute[1]))
    return 0


if __name__ == '__main__':
    sys.exit(main())
