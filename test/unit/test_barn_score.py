"""The BARN benchmark's score (closed_loop.sim.barn_score): its formula, the world's path through the grid, the
judge's clock from 0.1 m off the start to within 1 m of the goal, a sweep's rows and its page's headline."""
import math

import numpy
import pytest

from closed_loop.batch import report_page
from closed_loop.batch.judge import BENCHMARK_GOAL_M, BENCHMARK_START_M, Judge, JudgeSettings
from closed_loop.batch.tally import Tally
from closed_loop.sim import barn, barn_score

SETTINGS = barn.BarnSettings(seed=0, fill=0.3)


def test_the_score_is_the_benchmarks_formula():
    ot = 5.0
    assert barn_score.score(0, 10.0, ot) == pytest.approx(0.5)          # T at 2 OT or less: the best
    assert barn_score.score(0, 6.0, ot) == pytest.approx(0.5)
    assert barn_score.score(0, 20.0, ot) == pytest.approx(0.25)
    assert barn_score.score(0, 80.0, ot) == pytest.approx(1 / 8)        # T at 8 OT or more: the least
    assert barn_score.score(0, 99.0, ot) == pytest.approx(1 / 8)
    assert barn_score.score(0, 100.5, ot) == 0.0                         # past 100 s: a failure
    assert barn_score.score(1, 12.0, ot) == 0.0 and barn_score.score(0, None, ot) == 0.0


def test_the_path_runs_from_the_start_through_the_grid_to_the_goal():
    layout = barn.Layout(SETTINGS)
    empty = numpy.zeros((SETTINGS.length_cells, SETTINGS.width_cells), bool)
    # Along the row of cells nearest the line: 0.075 m off it, the start and the goal joined straight.
    first_x, last_x = layout.post_centre(0, 0)[0], layout.post_centre(SETTINGS.length_cells - 1, 0)[0]
    straight = math.hypot(first_x, 0.075) + (last_x - first_x) + math.hypot(SETTINGS.goal_distance - last_x, 0.075)
    assert barn_score.path_m(SETTINGS, empty, 0.2) == pytest.approx(straight)
    # A wall across the field with one gap three cells wide near a side: the path goes through it.
    wall = empty.copy()
    wall[15, :] = True
    wall[15, 2:5] = False
    detour = barn_score.path_m(SETTINGS, wall, 0.0)
    gap_y = layout.post_centre(15, 3)[1]
    assert detour >= math.hypot(layout.post_centre(15, 3)[0], gap_y) + math.hypot(
        SETTINGS.goal_distance - layout.post_centre(15, 3)[0], gap_y) - 1e-9
    # Grown by two cells each side (a Jackal's half-width) the gap closes; the path is the one with less growth.
    assert barn_score.path_m(SETTINGS, wall, 0.2155) == pytest.approx(barn_score.path_m(SETTINGS, wall, 0.15))
    assert math.isfinite(barn_score.path_m(SETTINGS, wall, 0.2155))
    blocked = empty.copy()
    blocked[15, :] = True
    assert barn_score.path_m(SETTINGS, blocked, 0.0) == math.inf


def test_a_worlds_optimal_time_is_its_path_at_two_metres_a_second():
    ot = barn_score.optimal_s(SETTINGS)
    assert SETTINGS.goal_distance / 2.0 <= ot < 1.2 * SETTINGS.goal_distance / 2.0


def test_the_judge_clocks_the_run_from_a_tenth_of_a_metre_off_the_start_to_a_metre_from_the_goal():
    judge = Judge(JudgeSettings(time_limit=60.0), goal=(5.0, 0.0))
    t, x = 0.0, 0.0
    while not judge.ended and t < 60.0:
        if t >= 2.0:                        # it stands 2 s before it sets off at 0.5 m/s
            x = min(0.05 * (round((t - 2.0) / 0.1) + 1), 5.0)
        moving = 2.0 <= t and x < 5.0
        judge.on_command((0.5, 0.0) if moving else (0.0, 0.0))
        if judge.due(t):
            judge.observe(t, x, 0.0, 0.0, 0.5 if moving else 0.0, 0.0, (0.5, 0.0) if moving else (0.0, 0.0), None)
        t = round(t + 0.1, 10)
    verdict = judge.verdict(t)
    started = 2.0 + BENCHMARK_START_M / 0.05 * 0.1 - 0.1            # the first instant 0.1 m off
    arrived = 2.0 + (5.0 - BENCHMARK_GOAL_M) / 0.05 * 0.1 - 0.1      # the first within 1 m
    assert verdict.outcome == 'reached' and verdict.benchmark_time_s == pytest.approx(arrived - started)
    assert Judge(JudgeSettings(), goal=(5.0, 0.0)).verdict(0.0).benchmark_time_s is None


def test_the_headline_gives_the_mean_score_where_rows_have_one():
    rows = [dict(index=str(i), outcome='reached', contacts='0', time_s='20.0', min_clearance_m='0.5',
                 benchmark_score=s) for i, s in enumerate(('0.25', '0.125', ''))]
    assert ("the BARN benchmark's score: mean 0.188 over 2 episodes (at most 0.5)"
            in report_page._outcomes(Tally.of(rows, [])))
    assert 'benchmark' not in report_page._outcomes(Tally.of([dict(rows[0], benchmark_score='')], []))


def test_a_sweep_row_scores_a_barn_method_world_and_no_other():
    from closed_loop.batch.sweep import run_row
    from closed_loop.batch.episode import EpisodeSpec
    world = {'generator': {'method': 'barn', 'seed': 0, 'fill': 0.2}}
    row = run_row(EpisodeSpec(world=world, robot='jackal', controller='avoid_obstacles', time_limit_s=3.0).to_dict())
    assert row['outcome'] == 'timed_out' and row['benchmark_score'] == 0.0 and row['benchmark_time_s'] == ''
    other = run_row(EpisodeSpec(world='wall', controller='stop_on_obstacle', time_limit_s=3.0).to_dict())
    assert other['benchmark_score'] == ''
