"""A controller run as a graph in lockstep (its node beside the simulator node, two graphs at a time) gives the
same result on an idle machine and on a loaded one, and the result of its core in process with the same command
latency: stop_on_obstacle (its node runs on a 10 Hz timer of simulated time) at 1.0 m/s with command latencies
of 0.01 and 0.1 s; avoid_obstacles (it answers each scan) in obstacle_course (more speeds, worlds and repeats in
test/bench/bench_graph.py). The core's timer is given the phase a rospy.Timer has (its first tick one period
after the start).
Each sweep's rows are written as the sweep writes them (repr of the floats), so "the same" is to the bit."""
import math
import os

from closed_loop.batch.episode import EpisodeSpec, run_episode
from conftest import LOAD, busy, graph_leftovers, run_sweep, same_rows

#: A rospy.Timer of 10 Hz first fires 0.1 s after the node starts (simulated time 0).
TIMER_PHASE_S = 0.1
STOP = ('name: stop\nbase: {world: wall, controller: {node: stop_on_obstacle}, time_limit_s: 30}\n'
        'grid:\n  settings.cruise_speed: [1.0]\n  command_delay_s: [0.01, 0.1]\n')
AVOID = ('name: avoid\nbase: {world: obstacle_course, goal: [7.0, 0.0], controller: {node: avoid_obstacles}, '
         'time_limit_s: 40}\ngrid:\n  seed: [0]\n')


def sweep_twice(tmp_path, name, text, loaded_text=None):
    """The sweep ``text`` run on this machine as it is, then ``loaded_text`` (the same, or a part of it) beside
    ``LOAD`` busy processes: (rows, rows), each by its grid's values."""
    runs = []
    for load, out, sweep in ((0, 'idle', text), (LOAD, 'loaded', loaded_text or text)):
        path = tmp_path / (name + out + '.yaml')
        path.write_text(sweep)
        with busy(load):
            done, rows = run_sweep(os.environ, path, tmp_path / name / out, '--workers', '2')
        assert done.returncode == 0, done.stdout[-3000:]
        assert all(r['missed_ticks'] == '0' for r in rows.values()), [r['why'] for r in rows.values()]
        assert graph_leftovers(tmp_path / name / out) == {'processes': [], 'listening': []}
        grid = [line.split(':')[0].strip() for line in sweep.split('grid:')[1].splitlines() if ':' in line]
        runs.append({tuple(r[g] for g in grid): r for r in rows.values()})
    return runs


def core_of(**spec):
    return run_episode(EpisodeSpec(timer_phase_s=TIMER_PHASE_S, **spec))


def agrees(row, core):
    gap = math.hypot(float(row['final_x']) - core.final_pose[0], float(row['final_y']) - core.final_pose[1])
    same_tick = abs(float(row['time_s']) - core.time_s) < 0.005     # (the judge's time of a 10 ms step, as a float)
    return row['outcome'] == core.outcome and same_tick and gap < 0.01, (row['why'], core.why, row['time_s'],
                                                                         core.time_s, gap)


def test_stop_on_obstacle_is_the_same_loaded_or_not_and_its_cores_result_with_the_same_latency(tmp_path):
    idle, loaded = sweep_twice(tmp_path, 'stop', STOP, STOP.replace('[0.01, 0.1]', '[0.1]'))
    assert len(loaded) == 1 and same_rows({case: idle[case] for case in loaded}, loaded) == []
    rest = {}
    for row in idle.values():
        cruise, delay = float(row['settings.cruise_speed']), float(row['command_delay_s'])
        core = core_of(world='wall', controller='stop_on_obstacle', settings={'cruise_speed': cruise}, command_delay_s=delay,
                       time_limit_s=30)
        ok, why = agrees(row, core)
        assert ok and row['outcome'] == 'stopped', (cruise, delay, why)
        rest[cruise, delay] = float(row['final_x'])
    # The latency is felt: with each command a tenth of a second later, the robot stops further on (it slowed
    # down first: by a few mm).
    assert rest[1.0, 0.1] > rest[1.0, 0.01] + 0.001, rest


def test_avoid_obstacles_is_the_same_loaded_or_not_and_its_cores_result(tmp_path):
    idle, loaded = sweep_twice(tmp_path, 'avoid', AVOID)
    assert same_rows(idle, loaded) == []
    (row,) = idle.values()
    core = core_of(world='obstacle_course', goal=(7.0, 0.0), controller='avoid_obstacles', time_limit_s=40)
    ok, why = agrees(row, core)
    assert ok and row['outcome'] == 'reached', why

