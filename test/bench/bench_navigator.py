#!/usr/bin/env python3
"""The navigator in generated clutter: 50 worlds with the Jackal, goal 10 m ahead, 80 s of simulated time.

Run: ``python3 test/bench/bench_navigator.py`` inside ``source env.sh`` (``make bench`` does that).
Options: ``--seeds N`` per fill ratio (default 10), ``--robot NAME`` (default jackal), ``-v`` a line per world.

Worlds: ``closed_loop.sim.clutter`` with fill ratios 0.2, 0.4, 0.6, 0.8 and 1.0 and seeds 0 .. N-1 (its default
geometry: sites 1.1 m apart, narrowest gaps 1.3 robot widths, a corridor the robot fits at any heading).
Each episode is ``closed_loop.batch.episode.run_episode``: the simulator core and the navigator's core in
lockstep in this process, as the node drives it (on its timer, and at once on a scan that makes the command
being followed unsafe), the profile's parameters (720 rays over 270 degrees at 10 Hz, 0.8 m/s), the
navigator's defaults otherwise. Success: the navigator said REACHED and ground truth ends within 0.4 m of
the goal, with no contact. Decision cost: the wall time of each planning decision (``Navigator.update`` when
it plans), on this process's one core, twice: in the episode loop, between pybullet's physics steps,
and replayed afterwards, every run's recorded inputs in order through a fresh Navigator with nothing
else in the loop, as the node runs in its own process; the replay makes the same decisions.

Targets: success at least 90 %, zero contacts in every run, decision p99 under 5 ms. Figures, not pass/fail:
the exit status is non-zero only when an episode could not run.
"""
import argparse
import collections
import os
import sys
import time

import numpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop.sim.clutter import ClutterSettings, generate, narrowest_gap, robot_extent  # noqa: E402
from closed_loop.control import navigator as navigator_module  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402
from closed_loop.sim.profiles import load_profile  # noqa: E402

FILL_RATIOS = (0.2, 0.4, 0.6, 0.8, 1.0)
TIME_LIMIT_S = 80.0
TARGET_SUCCESS = 0.90
TARGET_DECISION_P99_MS = 5.0


class Recorder:
    """Keeps every Navigator's settings, start and goal and the inputs of its updates, to replay them."""

    def __init__(self):
        self.runs = []
        self._init = navigator_module.Navigator.__init__
        self._update = navigator_module.Navigator.update
        recorder = self

        def init(nav, settings, start_pose, goal_xy=None, on_transition=None):
            recorder._init(nav, settings, start_pose, goal_xy, on_transition)
            nav._bench_inputs = []
            recorder.runs.append((settings, start_pose, goal_xy, nav._bench_inputs))

        def update(nav, *args):
            nav._bench_inputs.append(args)
            return recorder._update(nav, *args)
        navigator_module.Navigator.__init__ = init
        navigator_module.Navigator.update = update

    def replay(self):
        """Each run's decisions again, in order, in a fresh Navigator with nothing else in the loop (as the
        node has its own process): the wall time (ms) of each update that planned."""
        navigator_module.Navigator.__init__ = self._init
        navigator_module.Navigator.update = self._update
        times = []
        for settings, start, goal, inputs in self.runs:
            nav = navigator_module.Navigator(settings, start, goal)
            for args in inputs:
                t0 = time.perf_counter()
                step = nav.update(*args)
                if step.plan is not None:
                    times.append((time.perf_counter() - t0) * 1e3)
        return times


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--seeds', type=int, default=10)
    parser.add_argument('--robot', default='jackal')
    parser.add_argument('-v', '--verbose', action='store_true')
    args = parser.parse_args()
    profile = load_profile(args.robot)
    width, _ = robot_extent(profile)
    rows = collections.defaultdict(list)
    decisions = []
    recorder = Recorder()
    started = time.monotonic()
    for fill in FILL_RATIOS:
        for seed in range(args.seeds):
            settings = ClutterSettings(seed=seed, fill_ratio=fill, profile=profile.name)
            raw = generate(settings, profile)
            result = run_episode(EpisodeSpec(world={'generator': {'seed': seed, 'fill_ratio': fill}},
                                             robot=profile.name, controller='avoid_obstacles',
                                             goal=(settings.length, 0.0), time_limit_s=TIME_LIMIT_S))
            decisions.extend(result.decision_ms)
            obstacles = len(raw['obstacles']) - 2
            rows[fill].append((result, obstacles, narrowest_gap(raw)))
            if args.verbose:
                print('  %-28s %-9s %-12s %5.1f s  contacts %d  clearance %.3f m  goal error %.2f m  path %.1f m'
                      % (raw['name'], result.outcome, result.mode, result.time_s, result.contacts,
                         result.min_clearance_m, result.goal_error_m, result.path_m), flush=True)
    print('%s, %d worlds, goal %.0f m ahead, %.0f s limit (%.0f s wall)'
          % (profile.name, sum(len(r) for r in rows.values()), ClutterSettings().length, TIME_LIMIT_S,
             time.monotonic() - started))
    print('%-6s %-10s %-12s %-9s %-9s %-13s %-14s %s' % ('fill', 'obstacles', 'narrowest', 'success', 'contacts',
                                                        'time to goal', 'min clearance', 'other outcomes'))
    total = successes = contacts = 0
    for fill, results in rows.items():
        reached = [r for r, _, _ in results if r.outcome == 'reached']
        others = collections.Counter(r.outcome for r, _, _ in results if r.outcome != 'reached')
        gap = min(g for _, _, g in results)
        print('%-6.1f %-10s %-12s %-9s %-9d %-13s %-14s %s' % (
            fill, '%.0f' % numpy.mean([n for _, n, _ in results]), '%.2f m %.2fw' % (gap, gap / width),
            '%d/%d' % (len(reached), len(results)), sum(r.contacts for r, _, _ in results),
            '%.1f s' % numpy.mean([r.time_s for r in reached]) if reached else '-',
            '%.3f m' % min(r.min_clearance_m for r, _, _ in results),
            ', '.join('%s %d' % kv for kv in sorted(others.items())) or '-'))
        total += len(results)
        successes += len(reached)
        contacts += sum(r.contacts for r, _, _ in results)
    p50, p99 = numpy.percentile(decisions, [50, 99])
    alone = recorder.replay()
    a50, a99 = numpy.percentile(alone, [50, 99])
    print('success %.0f%% (%d/%d; target at least %.0f%%), contacts %d (target 0)'
          % (100.0 * successes / total, successes, total, 100 * TARGET_SUCCESS, contacts))
    print('decision cost over %d decisions (target p99 under %.0f ms): p50 %.2f ms, p99 %.2f ms replayed alone '
          '(as the node, in its own process); p50 %.2f ms, p99 %.2f ms in the episode loop, between physics steps'
          % (len(alone), TARGET_DECISION_P99_MS, a50, a99, p50, p99))
    return 0


if __name__ == '__main__':
    sys.exit(main())
