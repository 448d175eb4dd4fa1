"""A controller run as a graph (its node, beside the simulator node, on simulated time at the graph episodes'
default real_time_factor, two at a time) and its core run in process agree: stop_on_obstacle stops at the same
place (within 3 cm) at 0.3, 0.5 and 1.0 m/s; avoid_obstacles comes to the same outcome in 5 worlds."""
import math
import os

from closed_loop.batch.episode import EpisodeSpec, run_episode
from conftest import graph_leftovers, run_sweep

AVOID_WORLDS = ('obstacle_left', 'obstacle_right', 'slalom', 'obstacle_course', 'dead_end')


def test_stop_on_obstacle_stops_within_3_cm_of_its_core_in_process(tmp_path):
    sweep = tmp_path / 'stop.yaml'
    sweep.write_text('name: stop\nbase: {world: wall, controller: {node: stop_on_obstacle}, time_limit_s: 30}\n'
                     'grid:\n  settings.cruise_speed: [0.3, 0.5, 1.0]\n')
    done, rows = run_sweep(os.environ, sweep, tmp_path / 'out', '--workers', '2')
    assert done.returncode == 0, done.stdout[-3000:]
    for row in rows.values():
        cruise = float(row['settings.cruise_speed'])
        core = run_episode(EpisodeSpec(world='wall', controller='stop_on_obstacle', time_limit_s=30,
                                       settings={'cruise_speed': cruise}))
        assert row['outcome'] == core.outcome == 'stopped', (row, core)
        gap = math.hypot(float(row['final_x']) - core.final_pose[0], float(row['final_y']) - core.final_pose[1])
        assert gap < 0.03, (cruise, gap, row['why'], core.why)
    assert graph_leftovers(tmp_path / 'out') == {'processes': [], 'listening': []}


def test_avoid_obstacles_comes_to_the_same_outcome_as_its_core_in_five_worlds(tmp_path):
    sweep = tmp_path / 'avoid.yaml'
    sweep.write_text('name: avoid\nbase: {controller: {node: avoid_obstacles}, time_limit_s: 40}\n'
                     'grid:\n  world: [%s]\n' % ', '.join(AVOID_WORLDS))
    done, rows = run_sweep(os.environ, sweep, tmp_path / 'out', '--workers', '2')
    assert done.returncode == 0, done.stdout[-3000:]
    assert sorted(r['world'] for r in rows.values()) == sorted(AVOID_WORLDS)
    for row in rows.values():
        core = run_episode(EpisodeSpec(world=row['world'], controller='avoid_obstacles', time_limit_s=40))
        assert row['outcome'] == core.outcome, (row['world'], row['why'], core.why)
        assert row['contacts'] == '0', row
    assert graph_leftovers(tmp_path / 'out') == {'processes': [], 'listening': []}
