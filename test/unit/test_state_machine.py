"""The EXPLORING / BACKING_UP machine driven by injected time."""
import math

import pytest

from closed_loop.settings import SettingsError, check
from closed_loop.control.state_machine import (BackUpSettings, BackUpStateMachine, State,
                                       StateMachineError)

SETTINGS = check(BackUpSettings())
CLEAR = math.inf
CLOSE = 0.3
PERIOD_S = 0.1


def make_machine():
    transitions = []
    machine = BackUpStateMachine(SETTINGS, on_transition=lambda *args: transitions.append(args))
    return machine, transitions


def ticks(start_s, count):
    # integer multiples keep the times exact decimals (no accumulated float error)
    return [start_s + i * PERIOD_S for i in range(count)]


def test_defaults_are_the_lessons():
    assert SETTINGS.trigger_distance == 0.5
    assert (SETTINGS.explore_speed, SETTINGS.backup_speed) == (0.5, -0.3)
    assert SETTINGS.backup_duration == 2.0


def test_explores_while_clear():
    machine, transitions = make_machine()
    for now in ticks(0.0, 5):
        assert machine.update(CLEAR, now) == (State.EXPLORING, 0.5)
    assert machine.update(0.5, 1.0) == (State.EXPLORING, 0.5)   # trigger is strict "<"
    assert transitions == []


def test_backs_up_exactly_for_backup_duration_then_resumes():
    machine, transitions = make_machine()
    machine.update(CLEAR, 9.9)
    assert machine.update(CLOSE, 10.0) == (State.BACKING_UP, -0.3)
    assert transitions == [(State.EXPLORING, State.BACKING_UP, 10.0)]
    # The obstacle recedes as the robot reverses; it must keep reversing for the full 2 s.
    for now in ticks(10.1, 19):                     # 10.1 .. 11.9
        assert machine.update(CLEAR, now) == (State.BACKING_UP, -0.3), now
    assert machine.time_in_state(11.9) == pytest.approx(1.9)
    assert machine.update(CLEAR, 12.0) == (State.EXPLORING, 0.5)
    assert transitions[-1] == (State.BACKING_UP, State.EXPLORING, 12.0)
    assert len(transitions) == 2


def test_duration_is_not_stretched_by_float_rounding():
    machine, _ = make_machine()
    machine.update(CLOSE, 0.3)
    assert 2.3 - 0.3 < 2.0                          # the rounding this guards against
    assert machine.update(CLEAR, 2.3)[0] is State.EXPLORING


def test_obstacle_still_close_when_backup_ends_backs_up_again_without_a_forward_command():
    machine, transitions = make_machine()
    machine.update(CLOSE, 0.0)
    assert machine.update(CLOSE, 2.0) == (State.BACKING_UP, -0.3)
    assert [t[1] for t in transitions] == [State.BACKING_UP, State.EXPLORING, State.BACKING_UP]
    # and the new backing up lasts a full duration from 2.0
    assert machine.update(CLEAR, 3.9)[0] is State.BACKING_UP
    assert machine.update(CLEAR, 4.0)[0] is State.EXPLORING


def test_clock_jump_back_restarts_the_timer():
    machine, _ = make_machine()
    machine.update(CLOSE, 100.0)
    machine.update(CLEAR, 101.0)
    # /clock restarts from zero: without the restart the machine would see -101 s in state
    assert machine.update(CLEAR, 0.5) == (State.BACKING_UP, -0.3)
    assert machine.time_in_state(0.5) == 0.0
    assert machine.update(CLEAR, 2.4)[0] is State.BACKING_UP
    assert machine.update(CLEAR, 2.5)[0] is State.EXPLORING


def test_same_time_twice_is_not_a_jump():
    machine, _ = make_machine()
    machine.update(CLOSE, 5.0)
    machine.update(CLEAR, 6.0)
    machine.update(CLEAR, 6.0)
    assert machine.update(CLEAR, 7.0)[0] is State.EXPLORING


def test_minus_inf_distance_backs_up():
    machine, _ = make_machine()
    assert machine.update(-math.inf, 0.0)[0] is State.BACKING_UP


@pytest.mark.parametrize('distance, now, field', [
    (math.nan, 0.0, 'distance_m'), ('far', 0.0, 'distance_m'), (1.0, math.nan, 'now_s'),
    (1.0, math.inf, 'now_s'), (1.0, None, 'now_s')])
def test_bad_arguments_are_errors_and_leave_the_machine_alone(distance, now, field):
    machine, transitions = make_machine()
    machine.update(CLOSE, 1.0)
    with pytest.raises(StateMachineError, match='^%s:' % field):
        machine.update(distance, now)
    assert machine.state is State.BACKING_UP
    assert machine.update(CLEAR, 3.0)[0] is State.EXPLORING


def test_backup_speed_must_be_negative():
    with pytest.raises(SettingsError, match='~backup_speed'):
        check(BackUpSettings(backup_speed=0.0))


@pytest.mark.parametrize('field, value', [
    ('trigger_distance', 0.0), ('backup_duration', 0.0), ('explore_speed', -0.1),
    ('rate_hz', 0.0), ('scan_timeout', -1.0)])
def test_single_field_limits(field, value):
    with pytest.raises(SettingsError, match='~%s' % field):
        check(BackUpSettings(**{field: value}))


def test_react_now_only_for_a_trusted_obstacle_while_exploring():
    from closed_loop.control.scan import SectorReading
    from closed_loop.settings import check
    from closed_loop.control.state_machine import BackUpSettings, State, react_now
    settings = check(BackUpSettings())
    near, far, invalid = SectorReading(0.3, 5, 5), SectorReading(1.0, 5, 5), SectorReading(float('nan'), 0, 5)
    assert react_now(State.EXPLORING, near, settings)
    assert not react_now(State.EXPLORING, far, settings)
    assert not react_now(State.BACKING_UP, near, settings)
    assert not react_now(State.EXPLORING, invalid, settings)
    assert not react_now(State.EXPLORING, None, settings)
