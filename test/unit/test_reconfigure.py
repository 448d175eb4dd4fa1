"""Live settings: the dynamic_reconfigure description built from a settings class, and checked changes."""
import math

import pytest

from closed_loop.control.decisions import StopSettings
from closed_loop.control.guard import GuardSettings
from closed_loop.reconfigure import LEVEL, changed, config_type, differences, live_values
from closed_loop.control.scan import DetectorSettings
from closed_loop.settings import SettingsError, live_fields
from closed_loop.control.state_machine import BackUpSettings, BackUpStateMachine, State

# What must be tunable live, per node (the list: thresholds, speeds, sector width, margins).
EXPECTED_LIVE = {
    StopSettings: {'front_half_angle', 'stop_distance', 'slow_distance', 'slow_speed', 'cruise_speed',
                   'hysteresis', 'react_immediately'},
    BackUpSettings: {'front_half_angle', 'trigger_distance', 'explore_speed', 'backup_speed', 'backup_duration'},
    DetectorSettings: {'front_half_angle', 'side_half_angle', 'warn_distance'},
    GuardSettings: {'safety_margin', 'reaction_time', 'braking_decel', 'angular_decel'},
}


@pytest.mark.parametrize('cls', sorted(EXPECTED_LIVE, key=lambda c: c.__name__))
def test_live_fields_are_the_thresholds_not_rates_or_frames(cls):
    names = {f.name for f in live_fields(cls)}
    assert names == EXPECTED_LIVE[cls]
    assert not names & {'rate_hz', 'scan_timeout', 'scan_frame', 'cmd_timeout'}


def test_description_carries_type_default_limits_and_unit():
    t = config_type(StopSettings)
    params = {p['name']: p for p in t.config_description['parameters']}
    assert list(params) == [f.name for f in live_fields(StopSettings)]  # declaration order
    stop = params['stop_distance']
    assert stop['type'] == 'double' and stop['default'] == 0.5 and stop['level'] == LEVEL
    assert stop['min'] == 0.0 and stop['max'] == math.inf
    assert stop['description'].startswith('stop when the nearest obstacle ahead is closer')
    assert '(m)' in stop['description'] and 'more than the minimum' in stop['description']
    assert params['front_half_angle']['max'] == pytest.approx(math.pi)
    assert params['react_immediately']['type'] == 'bool'
    assert (params['react_immediately']['min'], params['react_immediately']['max']) == (False, True)
    assert t.defaults['slow_distance'] == 1.0 and t.type['cruise_speed'] == 'double'
    assert t.min['slow_speed'] == 0.0 and t.max['slow_speed'] == math.inf
    assert t.all_level == LEVEL
    assert set(t.defaults) == set(t.min) == set(t.max) == set(t.level) == set(t.type) == set(params)


def test_description_defaults_are_the_values_the_node_started_with():
    started = changed(StopSettings(), {'stop_distance': 0.3})
    assert config_type(StopSettings, started).defaults['stop_distance'] == 0.3


def test_change_is_checked_whole_and_leaves_the_original_alone():
    old = StopSettings()
    new = changed(old, {'stop_distance': 0.8, 'groups': {}, 'unknown': 1})
    assert new.stop_distance == 0.8 and old.stop_distance == 0.5
    assert new.rate_hz == old.rate_hz
    assert differences(old, new) == 'stop_distance 0.5 -> 0.8'
    assert live_values(new)['stop_distance'] == 0.8


@pytest.mark.parametrize('config, message', [
    ({'stop_distance': 1.5}, '~slow_distance: expected more than stop_distance (1.5 m), got 1.0'),
    ({'stop_distance': 0.0}, '~stop_distance: expected more than 0 m'),
    ({'front_half_angle': 4.0}, '~front_half_angle: expected at most'),
    ({'cruise_speed': 0.1}, '~cruise_speed: expected at least slow_speed'),
    ({'cruise_speed': math.nan}, '~cruise_speed: expected a finite number'),
    ({'react_immediately': 'maybe'}, '~react_immediately: expected true or false'),
])
def test_a_change_that_breaks_a_rule_is_refused_with_the_reason(config, message):
    with pytest.raises(SettingsError, match='^' + message.replace('(', r'\(').replace(')', r'\)')):
        changed(StopSettings(), config)


def test_rates_and_frames_are_not_changed_live():
    assert changed(StopSettings(), {'rate_hz': 99.0, 'scan_frame': 'x'}).rate_hz == StopSettings().rate_hz


def test_an_int_for_a_double_is_taken_as_a_float():
    assert type(changed(StopSettings(), {'slow_distance': 2}).slow_distance) is float


def test_state_machine_keeps_its_state_under_new_settings():
    machine = BackUpStateMachine(BackUpSettings())
    assert machine.update(0.4, 0.0) == (State.BACKING_UP, -0.3)
    machine.reconfigure(changed(BackUpSettings(), {'backup_duration': 0.5, 'backup_speed': -0.1}))
    assert machine.update(0.4, 0.2) == (State.BACKING_UP, -0.1)
    assert machine.update(2.0, 0.5) == (State.EXPLORING, 0.5)
