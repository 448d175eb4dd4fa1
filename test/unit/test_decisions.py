"""Stop / slow / cruise: lesson boundaries, hysteresis, and stop on bad input."""
import math

import pytest

from closed_loop.control.decisions import (Decision, DecisionError, StopSettings, Zone, classify_zone, decide,
                                           input_problem, speed_for_zone, stop)
from closed_loop.control.scan import SectorReading
from closed_loop.settings import SettingsError, check, from_params

SETTINGS = check(StopSettings())


def reading(distance_m, valid=181, total=181):
    return SectorReading(distance_m=distance_m, valid=valid, total=total)


def test_defaults_are_the_lessons():
    assert (SETTINGS.stop_distance, SETTINGS.slow_distance) == (0.5, 1.0)
    assert (SETTINGS.slow_speed, SETTINGS.cruise_speed) == (0.2, 0.5)
    assert SETTINGS.front_half_angle == pytest.approx(math.pi / 2)
    assert SETTINGS.rate_hz == 10.0


# --- boundaries without history (the lesson's strict "<") -------------------------------------

@pytest.mark.parametrize('distance, zone', [
    (0.0, Zone.STOP), (0.499, Zone.STOP), (0.5, Zone.SLOW), (0.999, Zone.SLOW), (1.0, Zone.CLEAR),
    (math.inf, Zone.CLEAR), (-math.inf, Zone.STOP), (math.nan, Zone.STOP)])
def test_zone_boundaries(distance, zone):
    assert classify_zone(distance, None, SETTINGS) is zone


def test_speeds_per_zone():
    assert speed_for_zone(Zone.CLEAR, SETTINGS) == 0.5
    assert speed_for_zone(Zone.SLOW, SETTINGS) == 0.2
    assert speed_for_zone(Zone.STOP, SETTINGS) == 0.0


# --- hysteresis ---------------------------------------------------------------------------------

def test_entering_a_more_dangerous_zone_is_immediate():
    assert classify_zone(0.999, Zone.CLEAR, SETTINGS) is Zone.SLOW
    assert classify_zone(0.499, Zone.SLOW, SETTINGS) is Zone.STOP
    assert classify_zone(0.499, Zone.CLEAR, SETTINGS) is Zone.STOP


@pytest.mark.parametrize('zone, limit_m, next_zone', [(Zone.STOP, 0.5, Zone.SLOW), (Zone.SLOW, 1.0, Zone.CLEAR)])
def test_leaving_a_zone_needs_the_hysteresis_margin(zone, limit_m, next_zone):
    # hysteresis 0.05 m: at the limit and just short of limit + margin the robot stays in the zone
    assert classify_zone(limit_m, zone, SETTINGS) is zone
    assert classify_zone(limit_m + 0.049, zone, SETTINGS) is zone
    assert classify_zone(limit_m + 0.05, zone, SETTINGS) is next_zone


def test_leaving_stop_steps_through_slow():
    assert classify_zone(1.02, Zone.STOP, SETTINGS) is Zone.SLOW
    assert classify_zone(1.05, Zone.STOP, SETTINGS) is Zone.CLEAR
    assert classify_zone(math.inf, Zone.STOP, SETTINGS) is Zone.CLEAR


def test_noise_at_a_boundary_does_not_chatter():
    zone = Zone.CLEAR
    zones = []
    for distance in (0.99, 1.01, 0.99, 1.03, 1.01):
        zone = classify_zone(distance, zone, SETTINGS)
        zones.append(zone)
    assert zones == [Zone.SLOW] * 5


def test_zero_hysteresis_is_the_plain_rule():
    settings = check(StopSettings(hysteresis=0.0))
    assert classify_zone(0.5, Zone.STOP, settings) is Zone.SLOW
    assert classify_zone(1.0, Zone.STOP, settings) is Zone.CLEAR


def test_non_number_distance_is_an_error():
    with pytest.raises(DecisionError, match='^distance_m:'):
        classify_zone('0.3', Zone.CLEAR, SETTINGS)


# --- decide -------------------------------------------------------------------------------------

def test_decide_follows_the_zone():
    assert decide(reading(2.0), 0.1, Zone.CLEAR, SETTINGS) == Decision(
        Zone.CLEAR, 0.5, 'clear ahead (2.00 m)')
    slow = decide(reading(0.7), 0.1, Zone.CLEAR, SETTINGS)
    assert (slow.zone, slow.linear_x) == (Zone.SLOW, 0.2)
    assert 'slow_distance' in slow.reason
    halt = decide(reading(0.3), 0.1, Zone.SLOW, SETTINGS)
    assert (halt.zone, halt.linear_x) == (Zone.STOP, 0.0)
    held = decide(reading(0.52), 0.1, Zone.STOP, SETTINGS)
    assert (held.zone, held.linear_x) == (Zone.STOP, 0.0)
    assert '0.55' in held.reason


def test_all_clear_reading_cruises():
    assert decide(reading(math.inf), 0.0, Zone.STOP, SETTINGS).linear_x == 0.5


def test_missing_reading_stops():
    decision = decide(None, None, Zone.CLEAR, SETTINGS)
    assert (decision.zone, decision.linear_x) == (Zone.STOP, 0.0)
    assert 'no usable scan' in decision.reason


@pytest.mark.parametrize('age', [None, math.nan])
def test_unknown_age_stops(age):
    decision = decide(reading(3.0), age, Zone.CLEAR, SETTINGS)
    assert (decision.zone, decision.linear_x) == (Zone.STOP, 0.0)
    assert 'age unknown' in decision.reason


def test_stale_reading_stops_at_the_timeout():
    assert decide(reading(3.0), 0.5, Zone.CLEAR, SETTINGS).zone is Zone.CLEAR
    stale = decide(reading(3.0), 0.51, Zone.CLEAR, SETTINGS)
    assert (stale.zone, stale.linear_x) == (Zone.STOP, 0.0)
    assert '0.51 s old' in stale.reason


def test_future_stamped_reading_stops_but_small_skew_is_accepted():
    assert decide(reading(3.0), -0.1, Zone.CLEAR, SETTINGS).zone is Zone.CLEAR
    future = decide(reading(3.0), -5.0, Zone.CLEAR, SETTINGS)
    assert future.zone is Zone.STOP
    assert 'future' in future.reason


def test_untrusted_reading_stops():
    decision = decide(reading(math.nan, valid=0), 0.0, Zone.CLEAR, SETTINGS)
    assert (decision.zone, decision.linear_x) == (Zone.STOP, 0.0)
    assert '181 of 181 rays invalid' in decision.reason
    empty = decide(reading(math.nan, valid=0, total=0), 0.0, Zone.CLEAR, SETTINGS)
    assert empty.zone is Zone.STOP


def test_input_problem_is_none_for_a_good_reading():
    assert input_problem(reading(0.2), 0.0, 0.5) is None


def test_stop_helper():
    assert stop('why') == Decision(Zone.STOP, 0.0, 'why')


# --- settings -----------------------------------------------------------------------------------

def test_stop_distance_must_be_under_slow_distance():
    with pytest.raises(SettingsError, match='~slow_distance'):
        check(StopSettings(stop_distance=1.0, slow_distance=1.0))


def test_slow_speed_must_not_exceed_cruise_speed():
    with pytest.raises(SettingsError, match='~cruise_speed'):
        check(StopSettings(slow_speed=0.6, cruise_speed=0.5))


def load_stop_settings(params):
    """StopSettings read from ``params`` ({'~name': value}) the way the nodes read the server."""
    return from_params(StopSettings, lambda name, default: params.get(name, default))


def test_react_immediately_defaults_to_true_and_parses_from_params():
    assert SETTINGS.react_immediately is True
    assert load_stop_settings({}).react_immediately is True
    # A launch file's <param value="false"/> arrives as a bool, a string in YAML quotes as a string.
    assert load_stop_settings({'~react_immediately': False}).react_immediately is False
    assert load_stop_settings({'~react_immediately': 'false'}).react_immediately is False
    assert load_stop_settings({'~react_immediately': 'True'}).react_immediately is True


def test_react_immediately_rejects_a_non_bool():
    with pytest.raises(SettingsError, match='~react_immediately'):
        load_stop_settings({'~react_immediately': 0})


@pytest.mark.parametrize('field, value', [
    ('stop_distance', 0.0), ('slow_speed', -0.1), ('hysteresis', -0.01), ('rate_hz', 0.0),
    ('scan_timeout', 0.0), ('front_half_angle', 0.0), ('front_half_angle', 3.5),
    ('cruise_speed', math.nan)])
def test_single_field_limits(field, value):
    with pytest.raises(SettingsError, match='~%s' % field):
        check(StopSettings(**{field: value}))


# --- silence watchdog ---------------------------------------------------------------------------

def test_react_now_first_decision_and_new_danger_only():
    from closed_loop.control.decisions import react_now
    from closed_loop.control.scan import SectorReading
    from closed_loop.settings import check
    settings = check(StopSettings())
    near, far = SectorReading(0.3, 10, 10), SectorReading(2.0, 10, 10)
    assert react_now(far, 0.0, None, settings)            # the first decision, whatever it says
    assert react_now(near, 0.0, Zone.CLEAR, settings)     # new danger
    assert not react_now(far, 0.0, Zone.CLEAR, settings)  # nothing new
    assert not react_now(far, 0.0, Zone.STOP, settings)   # safer: wait for the tick
    assert react_now(None, None, Zone.SLOW, settings)     # no usable scan is STOP
    assert react_now(near, 9.0, Zone.CLEAR, settings)     # stale is STOP
    timer_only = check(StopSettings(react_immediately=False))
    assert not react_now(near, 0.0, Zone.CLEAR, timer_only)
    assert react_now(near, 0.0, None, timer_only)
