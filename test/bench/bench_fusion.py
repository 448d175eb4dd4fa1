#!/usr/bin/env python3
"""The fusion controller over 50 seeded variants of person_crossing: contacts, wait-then-resume, time lost.

Run: ``python3 test/bench/bench_fusion.py`` inside ``source env.sh`` (``make bench`` does that).
Options: ``--variants N`` (default 50), ``--seed S`` (default 0), ``-v`` a line per variant.

Each variant is person_crossing with, drawn from a seeded generator: the walker's speed (0.5 to 1.5 m/s),
its crossing angle (60 to 120 degrees to the robot's line), where it starts along its way (its crossing
point 2.5 to 4.5 m ahead, and 2 to 4 m before that point), and its colour (red in three out of four,
grey otherwise, so the camera cannot tell). Each runs as an episode (``closed_loop.batch.episode``: the camera on,
the LIDAR at 720 rays), goal (7, 0), 60 s limit. Judged on ground truth:

- contacts (target: none in any run);
- reached: REACHED, ground truth within 0.4 m of the goal;
- wait-then-resume, over the variants where the walker is in the way: WAITING at least once, then REACHED
  (target: at least 95%). The walker is in the way when it occupies the robot's line (its radius plus the
  robot's half-width either side) at a time the robot, driving as in the empty world, is within the
  controller's look-ahead of the crossing point or on it; a walker that has crossed before the robot gets
  near needs no wait, and gets none;
- time lost: time to the goal less the time in an empty world (median);
- fusion cost per scan (tracking, association, beliefs) p99 (target under 5 ms at 720 rays).
Figures, not pass/fail: the exit status is non-zero only when an episode could not run.
"""
import argparse
import math
import os
import statistics
import sys
import tempfile

import numpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402
from closed_loop.control.fusion import WaitSettings  # noqa: E402

GOAL = (7.0, 0.0)
TIME_LIMIT_S = 60.0
SIM = {'scan_samples': 720}
TARGET_WAIT_RESUME, TARGET_FUSION_P99_MS = 0.95, 5.0
WALKER_RADIUS_M, ROBOT_HALF_WIDTH_M = 0.25, 0.14
LOOK_AHEAD_M = WaitSettings().look_ahead


def variant(rng, index):
    speed = rng.uniform(0.5, 1.5)
    angle = math.radians(rng.uniform(60.0, 120.0))         # the walker's heading against the robot's +x
    cross_x = rng.uniform(2.5, 4.5)
    before = rng.uniform(2.0, 4.0)
    side = rng.choice([-1.0, 1.0])                          # from the right, walking left, or the mirror
    dx, dy = math.cos(angle), side * math.sin(angle)
    start = (cross_x - before * dx, -before * dy)
    end = (cross_x + 40.0 * dx, 40.0 * dy)
    red = rng.random() < 0.75
    text = ('name: crossing_%02d\nrobot:\n  start: {x: 0.0, y: 0.0, yaw: 0.0}\nobstacles:\n'
            '  - {name: walker, type: cylinder, position: [%.3f, %.3f], radius: 0.25, height: 1.7, color: %s,\n'
            '     motion: {waypoints: [[%.3f, %.3f]], speed: %.3f, loop: false}}\n'
            % (index, start[0], start[1], 'red' if red else 'grey', end[0], end[1], speed))
    # While the walker is on the robot's line: its path meets y = 0 `before` m in, for its radius plus the
    # robot's half-width either side, stretched by the crossing angle.
    half = (WALKER_RADIUS_M + ROBOT_HALF_WIDTH_M) / abs(math.sin(angle))
    window = ((before - half) / speed, (before + half) / speed)
    return text, dict(speed=speed, angle_deg=math.degrees(angle), cross_x=cross_x, red=red, window=window)


def in_the_way(empty_rows, cross_x, window):
    """Whether the robot, driving as in the empty world, is within look-ahead of the crossing (or on it)
    while the walker is on its line."""
    near = cross_x - WALKER_RADIUS_M - LOOK_AHEAD_M
    far = cross_x + WALKER_RADIUS_M + ROBOT_HALF_WIDTH_M
    return any(window[0] <= row[0] <= window[1] and near <= row[1] <= far for row in empty_rows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--variants', type=int, default=50)
    parser.add_argument('--seed', type=int, default=0)
    parser.add_argument('-v', '--verbose', action='store_true')
    args = parser.parse_args()
    rng = numpy.random.default_rng(args.seed)
    empty = run_episode(EpisodeSpec(world='empty', controller='fusion_controller', goal=GOAL, sim=SIM,
                                    time_limit_s=TIME_LIMIT_S, keep_trajectory=True))
    contacts = resumed = reached = needed = waited_anyway = 0
    lost, costs, red_runs = [], [], 0
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.variants):
            text, what = variant(rng, i)
            path = os.path.join(tmp, 'crossing_%02d.yaml' % i)
            with open(path, 'w') as f:
                f.write(text)
            r = run_episode(EpisodeSpec(world=path, controller='fusion_controller', goal=GOAL, sim=SIM,
                                        time_limit_s=TIME_LIMIT_S, keep_trajectory=True))
            modes = [row[7] for row in r.trajectory]
            waited = 'WAITING' in modes
            way = in_the_way(empty.trajectory, what['cross_x'], what['window'])
            contacts += r.contacts > 0
            reached += r.outcome == 'reached'
            needed += way
            resumed += way and waited and r.outcome == 'reached'
            waited_anyway += waited and not way
            red_runs += what['red']
            if r.outcome == 'reached':
                lost.append(r.time_s - empty.time_s)
            costs.extend(r.timings.get('fusion_ms', []))
            if args.verbose:
                print('  %02d speed %.2f m/s, %3.0f deg, crossing x %.2f, %-4s, in the way %-5s: %-9s waited %-5s '
                      'contacts %d, %.1f s, clearance %.3f m' % (
                          i, what['speed'], what['angle_deg'], what['cross_x'], 'red' if what['red'] else 'grey',
                          way, r.outcome, waited, r.contacts, r.time_s, r.min_clearance_m), flush=True)
    n = args.variants
    print('fusion_controller over %d variants of person_crossing (%d with a red walker), 720 rays, camera on'
          % (n, red_runs))
    print('contacts: %d runs with contact (target 0)' % contacts)
    print('reached the goal: %d/%d' % (reached, n))
    print('wait-then-resume to the goal where the walker was in the way: %d/%d = %.0f%% (target at least %.0f%%); '
          'waits where it was not: %d' % (resumed, needed, 100.0 * resumed / max(needed, 1),
                                          100 * TARGET_WAIT_RESUME, waited_anyway))
    print('time to goal in an empty world %.1f s; time lost to the walker: median %.1f s, max %.1f s'
          % (empty.time_s, statistics.median(lost) if lost else math.nan, max(lost) if lost else math.nan))
    p50, p99 = numpy.percentile(costs, [50, 99])
    print('fusion cost per scan (tracking, association, beliefs) over %d scans: p50 %.2f ms, p99 %.2f ms '
          '(target p99 under %.0f ms, ratio %.2f)' % (len(costs), p50, p99, TARGET_FUSION_P99_MS,
                                                      p99 / TARGET_FUSION_P99_MS))
    return 0


if __name__ == '__main__':
    sys.exit(main())
