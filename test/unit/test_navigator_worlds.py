"""The navigator's core (``avoid_obstacles``) in each shipped world, in process, judged on ground truth: it reaches
the goal without a contact, holds its start heading once past the obstacles when it has no goal, and gives up at
rest in a dead end. The node is this core behind ROS: that it decides as the core does, in lockstep, is proven
on a graph by the rostests ``episode_agreement`` and ``avoid_dead_end`` and by ``test_graph_agreement``; the
rostests ``avoid_*`` keep what only a graph has (the goal on ``move_base_simple/goal``, no goal in a world that
names one: ``avoid_hold_course``), and ``robot_burger``, ``robot_jackal`` the profiles through ``robot:=``."""
import math

import pytest

from closed_loop.batch.episode import EpisodeSpec, run_episode

GOAL_RADIUS_M = 0.4
HOLD_TOLERANCE_RAD = math.radians(10.0)
AT_REST_MPS = 0.01


def navigate(world, goal, limit_s, robot='closed_loop', **settings):
    return run_episode(EpisodeSpec(world=world, robot=robot, controller='avoid_obstacles', goal=goal,
                                   settings=settings, time_limit_s=limit_s, keep_trajectory=True))


@pytest.mark.parametrize('world, goal, robot, limit_s', [
    ('obstacle_left', (10.0, 0.0), 'closed_loop', 60.0), ('obstacle_right', (10.0, 0.0), 'closed_loop', 60.0),
    ('slalom', (10.0, 0.0), 'closed_loop', 60.0), ('obstacle_course', (7.0, 0.0), 'closed_loop', 60.0),
    ('obstacle_course', (7.0, 0.0), 'burger', 120.0), ('obstacle_course', (7.0, 0.0), 'jackal', 80.0)])
def test_the_navigator_reaches_the_goal_round_the_obstacles_without_contact(world, goal, robot, limit_s):
    result = navigate(world, goal, limit_s, robot)
    modes = {row[7] for row in result.trajectory}
    x, y, _ = result.final_pose
    assert result.outcome == 'reached' and result.contacts == 0, result.why
    assert 'AVOIDING' in modes and math.hypot(x - goal[0], y - goal[1]) < GOAL_RADIUS_M, (modes, result.final_pose)


@pytest.mark.parametrize('world, past_x, passed_by_m, window_m', [
    ('obstacle_left', 2.8, 3.0, 0.5), ('obstacle_right', 2.8, 3.0, 0.5), ('slalom', 8.2, 3.0, 0.5)])
def test_without_a_goal_the_navigator_is_back_on_its_start_heading_past_the_obstacles(world, past_x, passed_by_m,
                                                                                       window_m):
    result = navigate(world, None, 60.0, goal_distance=0.0)
    begin, end = past_x + passed_by_m, past_x + passed_by_m + window_m
    track = result.trajectory
    assert result.contacts == 0, result.why
    assert any(row[1] > end for row in track), 'never %g m past x = %g: at %s' % (end - past_x, past_x,
                                                                                 result.final_pose)
    last = next(i for i, row in enumerate(track) if row[1] > end)
    off = [(round(row[1], 2), round(math.degrees(row[3]), 1)) for row in track[:last + 1]
           if row[1] > begin and abs(row[3]) >= HOLD_TOLERANCE_RAD]
    assert off == [], 'off the start heading at (x, degrees): %s' % off
    assert 'REACHED' not in {row[7] for row in track}


def test_in_a_dead_end_the_navigator_recovers_then_gives_up_at_rest_without_contact():
    result = navigate('dead_end', None, 60.0, stuck_timeout=4.0, give_up_timeout=25.0)
    modes = [row[7] for row in result.trajectory]
    assert result.contacts == 0 and 'RECOVERING' in modes and 'REACHED' not in modes, result.why
    assert result.mode == 'FAILED' and abs(result.trajectory[-1][4]) < AT_REST_MPS, (result.why, modes[-1])
