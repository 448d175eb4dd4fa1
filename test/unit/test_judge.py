"""The judge's rules (closed_loop.batch.judge), the rostest checker's comparison (scenario_test), and how a
graph episode's controller and launch file are made (closed_loop.batch.graph_episode)."""
import dataclasses
import math
import xml.etree.ElementTree as ET

import pytest

from closed_loop.batch import graph_episode
from closed_loop.batch.episode import EpisodeError, EpisodeSpec, prepare
from closed_loop.batch.spec import parse_controller
from closed_loop.batch.judge import Judge, JudgeSettings, Verdict
from closed_loop.controllers import controller_classes
from closed_loop.batch.judge import problems


def drive(judge, track, dt=0.1):
    """Feed ``track``: a list of (x, speed, command, mode) per period; returns the verdict at the end."""
    t = 0.0
    for x, speed, command, mode in track:
        if command is not None:
            judge.on_command(command)
        if judge.due(t) and judge.observe(t, x, 0.0, 0.0, speed, 0.0, command, mode):
            break
        t += dt
    return judge.verdict(t)


def test_a_robot_at_rest_for_the_hold_is_stopped_from_when_it_came_to_rest():
    judge = Judge(JudgeSettings(rest_hold=1.0))
    moving = [(0.1 * i, 0.5, (0.5, 0.0), None) for i in range(10)]
    resting = [(1.0, 0.0, (0.0, 0.0), None)] * 20
    verdict = drive(judge, moving + resting)
    assert verdict.outcome == 'stopped' and verdict.time_s == pytest.approx(1.0)
    assert verdict.path_m == pytest.approx(1.0) and verdict.commands == 21


def test_an_episode_ended_at_rest_is_what_it_was_when_it_came_to_rest():
    """The track, the path and the least clearance stop where the robot came to rest: its creep while it is held
    there (closer to an obstacle, here) is not the episode's, so a picture's times are within its time."""
    judge = Judge(JudgeSettings(rest_hold=1.0), keep_track=True)
    t = 0.0
    for i in range(30):
        moving = i < 10
        x = 0.1 * i if moving else 1.0 + 0.0004 * (i - 9)         # 0.4 mm a period while held at rest
        judge.on_clearance(1.5 - x)
        command = (0.5, 0.0) if moving else (0.0, 0.0)
        judge.on_command(command)
        if judge.due(t) and judge.observe(t, x, 0.0, 0.0, 0.5 if moving else 0.004, 0.0, command, None):
            break
        t += 0.1
    verdict = judge.verdict(t)
    assert verdict.outcome == 'stopped' and verdict.time_s == pytest.approx(1.0)
    assert judge.track[-1][0] == pytest.approx(1.0) and max(row[0] for row in judge.track) <= verdict.time_s
    assert verdict.min_clearance_m == pytest.approx(1.5 - 1.0004) and verdict.path_m == pytest.approx(1.0004)
    assert min(row[8] for row in judge.track) == verdict.min_clearance_m


def test_a_robot_rocking_where_it_came_to_rest_is_at_rest_and_one_that_moves_off_is_not():
    # Under a zero command, after coming to rest at x = 1: rocking on its wheels (speed and yaw rate swinging
    # past rest_speed and rest_yaw_rate, 1 mm back and forth) is at rest, and the scenario ends as stopped from
    # when it came to rest; drifting 2 cm off it is not (it times out), nor is a yaw rate over
    # rest_rock_yaw_rate.
    def run(rock, drift_mps=0.0, yaw_rate=0.06):
        judge, t, rows = Judge(JudgeSettings(rest_hold=1.0, time_limit=6.0)), 0.0, []
        for i in range(80):
            x = 0.1 * min(i, 10) + drift_mps * 0.1 * max(i - 11, 0) + (0.001 * (-1) ** i if rock and i > 11 else 0.0)
            speed = 0.5 if i < 10 else (0.0 if i == 11 or not rock else 0.01 * (-1) ** i)
            w = 0.0 if i <= 11 or not rock else yaw_rate * (-1) ** i
            command = (0.5, 0.0) if i < 10 else (0.0, 0.0)
            judge.on_command(command)
            if judge.due(t) and judge.observe(t, x, 0.0, 0.0, speed, w, command, None):
                break
            t += 0.1
        return judge.verdict(t)
    rocking = run(True)
    assert rocking.outcome == 'stopped' and rocking.time_s == pytest.approx(1.1)
    assert run(True, drift_mps=0.02).outcome == 'timed_out'
    assert run(True, yaw_rate=0.2).outcome == 'timed_out'


def test_a_zero_command_is_needed_for_rest_and_no_command_counts_as_zero():
    creeping = drive(Judge(JudgeSettings(time_limit=3.0)), [(0.0, 0.0, (0.1, 0.0), None)] * 40)
    assert creeping.outcome == 'timed_out'
    silent = drive(Judge(JudgeSettings()), [(0.0, 0.0, None, None)] * 40)
    assert silent.outcome == 'stopped' and silent.why.endswith('no command ever reached the base')


def test_at_rest_within_the_radius_is_reached_and_a_navigator_waiting_elsewhere_is_not_stopped():
    # (given only zeros, it is judged once first_command_wait is over, at the time it came to rest)
    near = drive(Judge(JudgeSettings(), goal=(1.2, 0.0)), [(1.0, 0.0, (0.0, 0.0), None)] * 40)
    assert near.outcome == 'reached' and near.goal_error_m == pytest.approx(0.2) and near.time_s == 0.0
    waiting = drive(Judge(JudgeSettings(end_at_rest=False, time_limit=5.0), goal=(5.0, 0.0)),
                    [(1.0, 0.0, (0.0, 0.0), None)] * 60)
    assert waiting.outcome == 'timed_out' and waiting.time_s == pytest.approx(5.0)


def test_the_controllers_word_counts_only_where_ground_truth_agrees():
    said_reached_far = drive(Judge(JudgeSettings(), goal=(5.0, 0.0)), [(1.0, 0.0, (0.0, 0.0), 'REACHED')] * 5)
    assert said_reached_far.outcome == 'failed'
    gave_up = drive(Judge(JudgeSettings()), [(1.0, 0.0, (0.0, 0.0), 'FAILED')] * 5)
    assert gave_up.outcome == 'failed' and gave_up.mode == 'FAILED'


def test_a_contact_wins_over_everything_and_can_end_the_scenario():
    judge = Judge(JudgeSettings(end_on_contact=True), goal=(1.0, 0.0))
    judge.on_contact(0.5)
    assert judge.ended
    verdict = judge.verdict(0.5, (1.0, 0.0, 0.0))
    assert verdict.outcome == 'collided' and verdict.contacts == 1 and verdict.time_s == 0.5


def test_clearance_and_peak_deceleration_are_kept_and_the_verdict_survives_json():
    judge = Judge(JudgeSettings())
    judge.on_clearance(0.8)
    judge.on_clearance(0.3)
    judge.on_clearance(0.5)
    verdict = drive(judge, [(0.0, 1.0, (1.0, 0.0), None), (0.1, 0.5, (0.0, 0.0), None)]
                    + [(0.15, 0.0, (0.0, 0.0), None)] * 20)
    assert verdict.min_clearance_m == 0.3 and verdict.peak_decel_mps2 == pytest.approx(5.0)
    assert Verdict.from_dict(verdict.to_dict()) == verdict
    assert Verdict.from_dict(Verdict('timed_out').to_dict()).min_clearance_m == math.inf


def test_scenario_test_names_each_expectation_the_verdict_breaks():
    verdict = {'outcome': 'stopped', 'contacts': 2, 'min_clearance_m': 0.02, 'time_s': 40.0}
    expect = {'outcomes': ['reached'], 'max_contacts': 0, 'min_clearance': 0.05, 'within': 30.0}
    assert problems(verdict, expect) == ['outcome stopped, expected reached', '2 contacts, at most 0 allowed',
                                         'least clearance 0.020 m, at least 0.050 m required',
                                         'after 40.0 s, within 30.0 s required']
    fine = dict(verdict, outcome='reached', contacts=0, min_clearance_m=None, time_s=10.0)
    assert problems(fine, dict(expect, outcomes=['stopped', 'reached'])) == []


@pytest.mark.parametrize('controller, message', [
    ({'launch': 'pkg/x.launch', 'node': 'stop_on_obstacle'}, 'one of them'),
    ({'launch': 'x.launch'}, 'a package name, then a path'),
    ({'launch': 'pkg/../x.launch'}, 'a package name, then a path'),
    ({'launch': 'pkg/x.py'}, 'expected PKG/path/file.launch'),
    ({'launch': '/tmp/$(eval 1)/x.launch'}, 'substitution'),
    ({'launch': 'pkg/x.launch', 'args': {'speed': '$(env HOME)'}}, 'no $(...) substitution'),
    ({'launch': 'pkg/x.launch', 'args': {'bad name': 1}}, 'not an arg name'),
    ({'launch': 'pkg/x.launch', 'ergs': {}}, 'controller.ergs'),
    ({'node': 'no_such_controller'}, 'controller.node: expected one of'),
])
def test_a_graph_controller_that_cannot_be_run_is_refused_naming_the_field(controller, message):
    with pytest.raises(EpisodeError, match=r'controller') as caught:
        parse_controller(controller, controller_classes())
    assert message in str(caught.value)


def test_the_episode_launch_file_passes_the_args_and_sets_no_substitution_from_data(tmp_path):
    spec = EpisodeSpec(world='obstacle_left', controller={'launch': 'my_pkg/launch/c.launch', 'args': {'speed': 0.4}},
                       goal=(6.0, 0.0), time_limit_s=30)
    text = graph_episode.launch_text(spec, prepare(spec), str(tmp_path))
    root = ET.fromstring(text)
    args = {a.get('name'): a.get('value') for a in root.findall('arg')}
    assert args['goal_x'] == '6.0' and args['time_limit'] == '30' and args['world'] == 'obstacle_left'
    # In lockstep by default, commands reaching the wheels as the spec says; a real_time_factor selects real time.
    assert args['lockstep'] == 'true' and 'real_time_factor' not in args and args['command_delay'] == '0.01'
    real_time = graph_episode.launch_text(dataclasses.replace(spec, real_time_factor=2.0), prepare(spec), str(tmp_path))
    real_args = {a.get('name'): a.get('value') for a in ET.fromstring(real_time).findall('arg')}
    assert real_args['lockstep'] == 'false' and real_args['real_time_factor'] == '2.0'
    include = [i for i in root.findall('include') if 'my_pkg' in i.get('file')][0]
    assert include.get('file') == '$(find my_pkg)/launch/c.launch' and include.get('pass_all_args') == 'true'
    assert [(a.get('name'), a.get('value')) for a in include.findall('arg')] == [('speed', '0.4')]
    with pytest.raises(EpisodeError, match='verdict_file'):
        graph_episode.launch_text(spec, prepare(spec), str(tmp_path / '$(env HOME)'))


def test_a_robot_no_command_has_reached_yet_is_not_stopped_before_the_first_command_wait():
    """A graph's controller answering its first scan late (seen: 1.3 simulated s at real_time_factor 8 on a
    loaded machine) is not judged 'stopped, no command' meanwhile; a silent one still is, once the wait is over."""
    judge = Judge(JudgeSettings(first_command_wait=3.0, time_limit=4.0))
    t = 0.0
    for step in range(45):                      # no command for 1.5 s (at rest), then driving at 0.5 m/s
        command = None if step < 15 else (0.5, 0.0)
        if command is not None:
            judge.on_command(command)
        if judge.due(t) and judge.observe(t, 0.0, 0.0, 0.0, 0.0 if command is None else 0.5, 0.0, command, None):
            break
        t += 0.1
    verdict = judge.verdict(t)
    assert verdict.outcome == 'timed_out' and verdict.commands > 0, verdict
    silent = drive(Judge(JudgeSettings(first_command_wait=3.0)), [(0.0, 0.0, None, None)] * 60)
    assert silent.outcome == 'stopped' and silent.why.endswith('no command ever reached the base')
    assert silent.time_s == 0.0            # at rest from the start: the wait delays the verdict, not its time


def test_a_robot_given_only_zeros_so_far_is_not_stopped_before_the_first_command_wait():
    """A controller that sends zeros until its first scan and odometry (a user's C++ node, seen judged 'stopped'
    at its start line on a loaded machine at real_time_factor 4) drives off once they come; one that only
    ever sends zeros is still judged stopped once the wait is over, at the time it came to rest."""
    waiting = [(0.0, 0.0, (0.0, 0.0), None)] * 15 + [(0.05 * i, 0.5, (0.5, 0.0), None) for i in range(30)]
    judge = Judge(JudgeSettings(first_command_wait=3.0, time_limit=4.0))
    verdict = drive(judge, waiting)
    assert verdict.outcome == 'timed_out' and judge.moves == verdict.commands - 15 > 0, verdict
    still = drive(Judge(JudgeSettings(first_command_wait=3.0)), [(0.0, 0.0, (0.0, 0.0), None)] * 60)
    assert still.outcome == 'stopped' and still.time_s == 0.0 and still.commands > 0, still


def test_due_from_is_where_due_turns_true_and_never_once_it_is_over():
    judge = Judge(JudgeSettings(period=0.1, time_limit=0.35))
    t, seen = 0.0, 0
    while not judge.ended:
        # Simulated time as a loop adds it, step by step (not exact multiples of the period).
        assert judge.due(t) == (t >= judge.due_from())
        if judge.due(t):
            seen += 1
            judge.observe(t, 0.0, 0.0, 0.0, 0.5, 0.0, (0.5, 0.0))
            assert judge.due_from() > t and not judge.due(t)
        t += 0.01
    assert seen == 5 and judge.due_from() == math.inf and not judge.due(1e9)
