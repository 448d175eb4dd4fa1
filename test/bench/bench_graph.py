#!/usr/bin/env python3
"""Graph episodes in lockstep (a controller run as a ROS graph: closed_loop.batch.graph_episode, its simulator
in lockstep with it): what one costs, how fast it runs, whether it gives the same result on any machine, and
whether it gives its core's result in process.

Run: ``python3 test/bench/bench_graph.py`` inside ``source env.sh`` (``make bench`` does that).

1. Start-up and shut-down: from the runner's start to the judge's first command from the controller (wall s),
   and from the verdict to everything down, for stop_on_obstacle run as its node (median of 3). Target: a
   start-up under 1.5 s.
2. A 20 s scenario of the avoid_obstacles node (10 Hz, it answers each scan) in obstacle_course, to its goal
   in about 19 s: wall s from the simulation's start to the verdict (the graph up), against the same episode in
   process. Target: at most 2 s of wall time for 20 s once the graph is up.
3. Determinism: each of six episodes 10 times on this machine as it is and 10 times beside two busy processes
   (2 workers): avoid_obstacles in obstacle_course; stop_on_obstacle (a 10 Hz timer of simulated time) in wall
   at 0.3, 0.5 and 1.0 m/s; the fixtures' rospy tb3_obstacle and C++ goal_seeker (built as a user's package).
   How many distinct results (outcome, time, final pose to the bit), the spread of the final poses, the
   instants missed. Target: one result each, poses within 1 mm.
4. Agreement with the core in process at the same command latency (its timer at the phase a rospy.Timer has):
   stop_on_obstacle at the three speeds with latencies 0.01 and 0.1 s, avoid_obstacles in obstacle_course and
   4 more worlds: the same outcome, the time to the tick, the rest position's gap. Target: within 1 cm.

Figures, not pass/fail: the exit status is non-zero only when something could not run.
"""
import math
import os
import pathlib
import re
import statistics
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
sys.path.insert(0, os.path.join(ROOT, 'test', 'system'))

from closed_loop.batch import graph_episode, sweep, sweep_file  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402
from conftest import busy, fixture_workspace  # noqa: E402  (the tests' own: a user's package, a loaded machine)

TARGET_STARTUP_S, TARGET_20S_WALL = 1.5, 2.0
#: A log line's stamps: [wall epoch, simulated s].
STAMPS = re.compile(r'\[(\d+\.\d+), (\d+\.\d+)\] \[/scenario_judge\]: (.*)')
AVOID_WORLDS = ('obstacle_left', 'obstacle_right', 'slalom', 'dead_end')
TIMER_PHASE_S = 0.1
REPEATS = 10
#: The six episodes of 3. (name, base spec, core spec for 4. or None).
AVOID = {'world': 'obstacle_course', 'goal': [7.0, 0.0], 'time_limit_s': 40}
EPISODES = [('avoid_obstacles, obstacle_course', dict(AVOID, controller={'node': 'avoid_obstacles'}))] + [
    ('stop_on_obstacle, wall, %.1f m/s' % v, {'world': 'wall', 'controller': {'node': 'stop_on_obstacle'},
                                              'settings': {'cruise_speed': v}, 'time_limit_s': 30})
    for v in (0.3, 0.5, 1.0)] + [
    ('tb3_obstacle (rospy), wall', {'world': 'wall', 'robot': 'burger', 'time_limit_s': 30,
                                    'controller': {'launch': 'fixture_controllers/launch/tb3_obstacle.launch'}}),
    ('goal_seeker (C++), wall', {'world': 'wall', 'robot': 'burger', 'time_limit_s': 30, 'goal': [2.0, 1.0],
                                 'controller': {'launch': 'fixture_controllers/launch/goal_seeker.launch',
                                                'args': {'max_speed': 0.3}}})]


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
    """(result, the judge's lines, start, end) of ``spec``; (the kept graph's last teardown done first: timed apart)"""
    folder = tempfile.mkdtemp(dir=root)
    os.rmdir(folder)
    graph_episode.settle_kept_graph()
    started = time.time()
    result = run_episode(spec, logs=folder)
    ended = time.time()
    if result.outcome == 'error':
        raise SystemExit('bench_graph: the episode did not run: %s' % result.error)
    return result, judge_lines(folder), started, ended


def startup(root):
    print('1. start-up and shut-down: stop_on_obstacle as its node, in wall (the first episode starts the kept graph)')
    firsts, downs = [], []
    for _ in range(4):
        _, lines, started, ended = timed(EpisodeSpec(world='wall', controller={'node': 'stop_on_obstacle'},
                                                     time_limit_s=30), root)
        firsts.append(lines['first command'][0] - started)
        graph_episode.settle_kept_graph()
        downs.append(time.time() - lines['verdict'][0])
    first = statistics.median(firsts[1:])
    print('   start-up to the first command, the graph kept: %.2f s (median of 3: %s; with the graph\'s own start: '
          '%.2f s); target < %.1f s: %s' % (first, ', '.join('%.2f' % f for f in firsts[1:]), firsts[0],
                                             TARGET_STARTUP_S, 'met' if first < TARGET_STARTUP_S else 'NOT met'))
    print('   verdict to the row, the episode\'s nodes down and the graph as before: %.2f s (median of 4)'
          % statistics.median(downs))
    fresh = []
    for _ in range(3):
        _, lines, started, ended = timed(EpisodeSpec(world='wall', time_limit_s=30, controller={
            'node': 'stop_on_obstacle', 'fresh_graph': True}), root)
        fresh.append((lines['first command'][0] - started, ended - lines['verdict'][0]))
    print('   a graph of its own (fresh_graph): start-up %.2f s, verdict to everything down %.2f s (medians of 3)' % (
        statistics.median(f for f, _ in fresh), statistics.median(d for _, d in fresh)))


def twenty_seconds(root):
    print('2. a 20 s scenario: avoid_obstacles as its node in obstacle_course, to its goal (7, 0) in about 19 s')
    spec = dict(world='obstacle_course', goal=(7.0, 0.0), time_limit_s=20.0, controller={'node': 'avoid_obstacles'})
    walls = []
    for _ in range(3):
        result, lines, started, ended = timed(EpisodeSpec(**spec), root)
        (w0, _), (w1, s1) = lines['the controller is up'], lines['verdict']
        walls.append(w1 - w0)
        print('   %.1f s simulated in %.2f s of wall time once the graph was up (%.1fx real time), %.2f s in all; '
              '%s' % (s1, w1 - w0, s1 / (w1 - w0), ended - started, result.why))
    core_spec = dict(spec, controller='avoid_obstacles', timer_phase_s=TIMER_PHASE_S)
    core = run_episode(EpisodeSpec(**core_spec))
    wall = statistics.median(walls)
    per_20 = wall * 20.0 / s1
    print('   median %.2f s, %.2f s for 20 s: target <= %.0f s: %s; the same episode in process: %.2f s of wall time '
          '(%.0fx real time); the graph takes %.1fx its time' % (
              wall, per_20, TARGET_20S_WALL, 'met' if per_20 <= TARGET_20S_WALL else 'NOT met', core.wall_s,
              core.time_s / core.wall_s, wall / core.wall_s))


def repeated(name, base, out, load):
    built = sweep_file.build('bench_graph', base, {'seed': list(range(REPEATS))}, report={'pictures': 'none',
                                                                                          'max_pictures': 0})
    with busy(load):
        rows = list(sweep.run(built, out, workers=2, stream=open(os.devnull, 'w')))
    errors = [r['error'] for r in rows if r['outcome'] == 'error']
    if errors:
        raise SystemExit('bench_graph: %s did not run: %s' % (name, errors[0]))
    return rows


def determinism(root):
    print('3. each episode %d times as the machine is and %d times beside two busy processes (2 workers)'
          % (REPEATS, REPEATS))
    for i, (name, base) in enumerate(EPISODES):
        rows = []
        for load in (0, 2):
            rows += repeated(name, base, os.path.join(root, 'det-%d-%d' % (i, load)), load)
        results = {(r['outcome'], r['time_s'], r['final_x'], r['final_y']) for r in rows}
        xs, ys = [float(r['final_x']) for r in rows], [float(r['final_y']) for r in rows]
        spread = math.hypot(max(xs) - min(xs), max(ys) - min(ys))
        missed = sum(int(r['missed_ticks'] or 0) for r in rows)
        print('   %-36s %d distinct result%s of %d (%s after %s s), poses within %.3g mm, %d instants missed; wall '
              '%.1f s a run (median)' % (name, len(results), '' if len(results) == 1 else 's', len(rows),
                                         rows[0]['outcome'], rows[0]['time_s'], 1000 * spread, missed,
                                         statistics.median(float(r['wall_s']) for r in rows)))


def agreement(root):
    print('4. against the core in process at the same latency (its timer first at %.1f s, as a rospy.Timer of 10 Hz)'
          % TIMER_PHASE_S)
    cases = []
    for v in (0.3, 0.5, 1.0):
        for delay in (0.01, 0.1):
            spec = dict(world='wall', settings={'cruise_speed': v}, time_limit_s=30, command_delay_s=delay)
            cases.append(('stop_on_obstacle %.1f m/s, latency %g s' % (v, delay), 'stop_on_obstacle', spec))
    cases.append(('avoid_obstacles, obstacle_course', 'avoid_obstacles', dict(AVOID, goal=(7.0, 0.0))))
    cases += [('avoid_obstacles, %s' % w, 'avoid_obstacles', dict(world=w, time_limit_s=40)) for w in AVOID_WORLDS]
    for name, controller, spec in cases:
        graph = run_episode(EpisodeSpec(controller={'node': controller}, **spec), logs=tempfile.mkdtemp(dir=root))
        core = run_episode(EpisodeSpec(controller=controller, timer_phase_s=TIMER_PHASE_S, **spec))
        gap = math.hypot(graph.final_pose[0] - core.final_pose[0], graph.final_pose[1] - core.final_pose[1])
        print('   %-40s graph %s after %.2f s, core %s after %.2f s: %s; rest %s' % (
            name, graph.outcome, graph.time_s, core.outcome, core.time_s,
            'the same' if graph.outcome == core.outcome and abs(graph.time_s - core.time_s) < 0.005 else 'DIFFERENT',
            'to the bit' if gap == 0 else '%.3g mm apart' % (1000 * gap)))


PARTS = {'startup': startup, 'twenty': twenty_seconds, 'determinism': determinism, 'agreement': agreement}


def main(argv):
    """``bench_graph.py [PART ...]``: the parts named (startup, twenty, determinism, agreement), or all."""
    unknown = [a for a in argv if a not in PARTS]
    if unknown:
        raise SystemExit('bench_graph: no part %s (the parts: %s)' % (unknown[0], ', '.join(PARTS)))
    os.environ.update(fixture_workspace(pathlib.Path(tempfile.mkdtemp())))    # the fixtures' package, for the workers
    with tempfile.TemporaryDirectory() as root:
        for name, part in PARTS.items():
            if not argv or name in argv:
                part(root)
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
