#!/usr/bin/env python3
"""Graph episodes (a controller run as a ROS graph: closed_loop.batch.graph_episode): what one costs, and how
fast the simulator may run in them while the results still agree with the controller's core in process.

Run: ``python3 test/bench/bench_graph.py`` inside ``source env.sh`` (``make bench`` does that).

1. Start-up: from the runner's start to the judge's first command from the controller (wall s), and the
   shut-down after the verdict, for stop_on_obstacle run as its node (median of 3).
2. A 20 s scenario (stop_on_obstacle's node, judged for all 20 s) at the default real_time_factor: wall s,
   start-up included, and simulated s per wall s while it ran. Target: at most 10 s of wall time.
3. Agreement against the core in process, one graph at a time, at real_time_factor 1, 2, 4 and 8:
   stop_on_obstacle in ``wall`` at 0.3, 0.5 and 1.0 m/s (gap of the rest positions, mm; of the times to
   rest, s), and avoid_obstacles' outcome in 5 worlds at 2 and 4.

Figures, not pass/fail: the exit status is non-zero only when something could not run.
"""
import os
import re
import statistics
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop.batch import graph_episode  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402

TARGET_20S_WALL = 10.0
#: A log line's stamps: [wall epoch, simulated s].
STAMPS = re.compile(r'\[(\d+\.\d+), (\d+\.\d+)\] \[/scenario_judge\]: (.*)')
AVOID_WORLDS = ('obstacle_left', 'obstacle_right', 'slalom', 'obstacle_course', 'dead_end')


def judge_lines(folder):
    """{what the judge said first with each prefix: (wall epoch, simulated s)} from the graph's output."""
    found = {}
    with open(os.path.join(folder, 'graph.log'), errors='replace') as f:
        for match in STAMPS.finditer(f.read()):
            for key in ('the controller is up', 'first command', 'verdict'):
                if match.group(3).startswith(key) and key not in found:
                    found[key] = (float(match.group(1)), float(match.group(2)))
    return found


def timed(spec, root):
    folder = tempfile.mkdtemp(dir=root)
    os.rmdir(folder)
    started = time.time()
    result = run_episode(spec, logs=folder)
    ended = time.time()
    if result.outcome == 'error':
        raise SystemExit('bench_graph: the episode did not run: %s' % result.error)
    return result, judge_lines(folder), started, ended


def startup(root):
    print('1. start-up and shut-down: stop_on_obstacle as its node, in wall')
    firsts, downs = [], []
    for _ in range(3):
        _, lines, started, ended = timed(EpisodeSpec(world='wall', controller={'node': 'stop_on_obstacle'},
                                                     time_limit_s=30), root)
        firsts.append(lines['first command'][0] - started)
        downs.append(ended - lines['verdict'][0])
    print('   start-up to the first command: %.2f s (median of 3: %s)' % (
        statistics.median(firsts), ', '.join('%.2f' % f for f in firsts)))
    print('   verdict to everything down:    %.2f s' % statistics.median(downs))


def twenty_seconds(root):
    rtf = graph_episode.REAL_TIME_FACTOR
    print('2. a 20 s scenario at real_time_factor %g (stop_on_obstacle, judged for all 20 s)' % rtf)
    walls = []
    for _ in range(3):
        result, lines, started, ended = timed(EpisodeSpec(
            world='wall', controller={'node': 'stop_on_obstacle', 'end_at_rest': False}, time_limit_s=20), root)
        (w0, s0), (w1, s1) = lines['the controller is up'], lines['verdict']
        walls.append(ended - started)
        print('   %.1f s simulated in %.2f s of wall time, start-up included (%.2f sim s per wall s while it ran)'
              % (result.time_s, ended - started, (s1 - s0) / (w1 - w0)))
    wall = statistics.median(walls)
    print('   median %.2f s: target <= %.0f s: %s' % (wall, TARGET_20S_WALL, 'met' if wall <= TARGET_20S_WALL else
                                                      'NOT met'))


def agreement(root):
    print('3. agreement with the core in process, one graph at a time')
    for cruise in (0.3, 0.5, 1.0):
        core = run_episode(EpisodeSpec(world='wall', controller='stop_on_obstacle', time_limit_s=30,
                                       settings={'cruise_speed': cruise}))
        cells = []
        for rtf in (1, 2, 4, 8):
            r, _, started, ended = timed(EpisodeSpec(world='wall', controller={'node': 'stop_on_obstacle'},
                                                     time_limit_s=30, settings={'cruise_speed': cruise},
                                                     real_time_factor=rtf), root)
            same = r.outcome == core.outcome
            cells.append('x%g: %s%.0f mm, %+.2f s (%.1f s wall)' % (
                rtf, '' if same else r.outcome + '! ', 1000 * abs(r.final_pose[0] - core.final_pose[0]),
                r.time_s - core.time_s, ended - started))
        print('   stop %.1f m/s: %s' % (cruise, '; '.join(cells)))
    for rtf in (2, 4):
        same = 0
        for world in AVOID_WORLDS:
            core = run_episode(EpisodeSpec(world=world, controller='avoid_obstacles', time_limit_s=60))
            r, _, _, _ = timed(EpisodeSpec(world=world, controller={'node': 'avoid_obstacles'}, time_limit_s=60,
                                           real_time_factor=rtf), root)
            same += r.outcome == core.outcome
            if r.outcome != core.outcome:
                print('   avoid x%g %s: graph %s, core %s' % (rtf, world, r.why, core.why))
        print('   avoid_obstacles x%g: the same outcome in %d of %d worlds' % (rtf, same, len(AVOID_WORLDS)))


def main():
    with tempfile.TemporaryDirectory() as root:
        startup(root)
        twenty_seconds(root)
        agreement(root)
    return 0


if __name__ == '__main__':
    sys.exit(main())
