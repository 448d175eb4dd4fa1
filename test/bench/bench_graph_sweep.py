#!/usr/bin/env python3
"""A sweep of graph episodes in lockstep: 50 episodes of stop_on_obstacle run as its node (5 stop distances x
5 cruise speeds x 2 worlds, each a ROS graph of its own) on a local Dask cluster of 1 worker and of 2: episodes
per minute of wall time, outcomes, errors, instants missed and what is left running afterwards; and the same 50
episodes in process (its core, its timer at a rospy.Timer's phase), on 2 workers, in the same run: how many
give the same outcome and rest position. Target: at least 60 graph episodes a minute on 2 workers.

Run: ``python3 test/bench/bench_graph_sweep.py`` inside ``source env.sh`` (``make bench`` does that).
Figures, not pass/fail: the exit status is non-zero only when something could not run.
"""
import collections
import math
import os
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop import launcher  # noqa: E402
from closed_loop.batch import sweep, sweep_file  # noqa: E402

GRID = {'settings.stop_distance': [0.3, 0.4, 0.5, 0.6, 0.7], 'settings.cruise_speed': [0.3, 0.4, 0.5, 0.7, 1.0],
        'world': ['wall', 'red_box']}
BASE = {'time_limit_s': 30.0}
TARGET_PER_MINUTE = 60.0


def run(controller, workers, **base):
    """(rows, wall s, what is left running) of the sweep with ``controller``."""
    built = sweep_file.build('graph_sweep', dict(BASE, controller=controller, **base), GRID,
                             report={'pictures': 'none', 'max_pictures': 0})
    with tempfile.TemporaryDirectory() as out:
        started = time.monotonic()
        rows = list(sweep.run(built, out, workers=workers, stream=open(os.devnull, 'w')))
        wall = time.monotonic() - started
        left = launcher.marked_processes(out)
    return rows, wall, left


def describe(rows, wall):
    outcomes = collections.Counter(r['outcome'] for r in rows)
    simulated = sum(float(r['time_s'] or 0) for r in rows)
    return '%d episodes in %.0f s: %.1f episodes a minute, %.1f simulated s (to rest) per wall s; %s' % (
        len(rows), wall, 60.0 * len(rows) / wall, simulated / wall,
        ', '.join('%s %d' % kv for kv in sorted(outcomes.items())))


def main():
    print('%d graph episodes in lockstep' % len(sweep_file.build('graph_sweep', dict(
        BASE, controller={'node': 'stop_on_obstacle'}), GRID).specs))
    per_minute, graph_rows = {}, None
    for workers in (1, 2):
        rows, wall, left = run({'node': 'stop_on_obstacle'}, workers)
        per_minute[workers] = 60.0 * len(rows) / wall
        missed = sum(int(r['missed_ticks'] or 0) for r in rows)
        print('%d worker%s: %s; %d instants missed; left running: %d processes' % (
            workers, '' if workers == 1 else 's', describe(rows, wall), missed, len(left)))
        graph_rows = rows
    print('2 workers / 1 worker: %.2fx; target >= %.0f episodes a minute on 2 workers: %s' % (
        per_minute[2] / per_minute[1], TARGET_PER_MINUTE, 'met' if per_minute[2] >= TARGET_PER_MINUTE else 'NOT met'))
    rows, wall, _ = run('stop_on_obstacle', 2, timer_phase_s=0.1)
    print('in process, 2 workers: %s (%.0fx the graphs\' rate)' % (describe(rows, wall),
                                                                  60.0 * len(rows) / wall / per_minute[2]))
    core = {tuple(r[k] for k in GRID): r for r in rows}
    same = far = 0
    for row in graph_rows:
        twin = core[tuple(row[k] for k in GRID)]
        gap = math.hypot(float(row['final_x']) - float(twin['final_x']), float(row['final_y']) - float(twin['final_y']))
        same += row['outcome'] == twin['outcome'] and gap < 0.01
        far = max(far, gap)
    print('graph against in process: the same outcome and rest within 1 cm in %d of %d; the largest gap %.3g mm'
          % (same, len(graph_rows), 1000 * far))
    return 0


if __name__ == '__main__':
    sys.exit(main())
