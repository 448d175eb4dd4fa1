"""Settings: ``~parameter`` reading, type coercion, limits, choices and cross-field checks."""
import math
from dataclasses import dataclass

import pytest

from closed_loop.settings import SettingsError, check, describe, from_params, param


@dataclass
class Example:
    """One field of every kind and limit the settings machinery supports."""
    rate: float = param(10.0, 'Hz', 'how often', minimum=0.0, exclusive_minimum=True)
    distance: float = param(0.5, 'm', 'how far', minimum=0.0, maximum=5.0)
    offset: float = param(-1.0, 'm', 'no limits at all')
    count: int = param(3, '', 'how many', minimum=1, maximum=10)
    enabled: bool = param(True, '', 'on or off')
    mode: str = param('fast', '', 'which way', choices=('fast', 'safe'))
    low: float = param(1.0, 'm', 'lower bound')
    high: float = param(2.0, 'm', 'upper bound')

    def check_together(self):
        if not self.high > self.low:
            raise SettingsError('~high: expected more than ~low (%g m), got %r' % (self.low, self.high))


def load(**given):
    """``Example`` read through a fake parameter server holding ``given`` (names without ``~``)."""
    def get_param(name, default):
        assert name.startswith('~')
        return given.get(name[1:], default)
    return from_params(Example, get_param)


def error_for(**given):
    with pytest.raises(SettingsError) as caught:
        load(**given)
    return str(caught.value)


# --- defaults and reading -----------------------------------------------------------------------

def test_defaults_are_used_when_no_parameter_is_set():
    settings = load()
    assert settings == Example()
    assert (settings.rate, settings.count, settings.enabled, settings.mode) == (10.0, 3, True, 'fast')


def test_every_field_is_read_from_its_private_parameter_with_its_default():
    asked = {}

    def get_param(name, default):
        asked[name] = default
        return default
    from_params(Example, get_param)
    assert asked == {'~rate': 10.0, '~distance': 0.5, '~offset': -1.0, '~count': 3,
                     '~enabled': True, '~mode': 'fast', '~low': 1.0, '~high': 2.0}


def test_parameter_values_override_defaults():
    settings = load(rate=20.0, count=7, enabled=False, mode='safe', offset=-3.5)
    assert (settings.rate, settings.count, settings.enabled, settings.mode, settings.offset) == \
        (20.0, 7, False, 'safe', -3.5)


def test_describe_lists_name_default_unit_and_doc():
    rows = describe(Example)
    assert rows[0] == ('rate', 10.0, 'Hz', 'how often')
    assert [row[0] for row in rows] == ['rate', 'distance', 'offset', 'count', 'enabled', 'mode',
                                        'low', 'high']


# --- type coercion ------------------------------------------------------------------------------

def test_an_integer_is_accepted_for_a_float_and_becomes_a_float():
    settings = load(rate=20)
    assert settings.rate == 20.0
    assert type(settings.rate) is float


def test_a_whole_float_is_accepted_for_an_integer_and_becomes_an_int():
    settings = load(count=4.0)
    assert settings.count == 4
    assert type(settings.count) is int


@pytest.mark.parametrize('value', [2.5, '4', True, None])
def test_an_integer_field_refuses_other_values(value):
    message = error_for(count=value)
    assert message.startswith('~count: expected an integer')


@pytest.mark.parametrize('value', ['1.5', True, False, None, [1.0]])
def test_a_float_field_refuses_strings_booleans_and_others(value):
    # True would otherwise count as 1.0: a typo must not become a rate.
    message = error_for(rate=value)
    assert message.startswith('~rate: expected a number')


@pytest.mark.parametrize('value,expected', [('true', True), ('false', False), ('True', True),
                                            ('FALSE', False), (True, True), (False, False)])
def test_a_bool_field_accepts_booleans_and_their_names(value, expected):
    settings = load(enabled=value)
    assert settings.enabled is expected


@pytest.mark.parametrize('value', [1, 0, 1.0, 'yes', 'no', '1', '', None])
def test_a_bool_field_is_strict(value):
    message = error_for(enabled=value)
    assert message.startswith('~enabled: expected true or false')


@pytest.mark.parametrize('value', [3, None, b'fast'])
def test_a_string_field_refuses_non_strings(value):
    message = error_for(mode=value)
    assert message.startswith('~mode: expected a string')


@pytest.mark.parametrize('value', [float('nan'), float('inf'), float('-inf')],
                         ids=['nan', 'inf', '-inf'])
@pytest.mark.parametrize('name', ['rate', 'offset'])
def test_non_finite_floats_are_refused_even_without_limits(name, value):
    message = error_for(**{name: value})
    assert message.startswith('~%s: expected a finite number' % name)


@pytest.mark.parametrize('value', [float('nan'), float('inf')], ids=['nan', 'inf'])
def test_non_finite_floats_are_refused_for_integers(value):
    assert error_for(count=value).startswith('~count: expected an integer')


# --- limits and choices -------------------------------------------------------------------------

def test_an_inclusive_minimum_accepts_the_bound_itself():
    assert load(distance=0.0).distance == 0.0
    assert load(count=1).count == 1


def test_an_inclusive_minimum_refuses_values_below():
    message = error_for(distance=-0.01)
    assert message.startswith('~distance: expected at least 0 m')
    assert error_for(count=0).startswith('~count: expected at least 1')


def test_an_exclusive_minimum_refuses_the_bound_itself():
    message = error_for(rate=0.0)
    assert message.startswith('~rate: expected more than 0 Hz')
    assert error_for(rate=-1.0).startswith('~rate: expected more than 0 Hz')
    assert load(rate=1e-6).rate == 1e-6


def test_a_maximum_accepts_the_bound_and_refuses_values_above():
    assert load(distance=5.0).distance == 5.0
    assert error_for(distance=5.001).startswith('~distance: expected at most 5 m')
    assert error_for(count=11).startswith('~count: expected at most 10')


def test_the_message_shows_the_value_that_was_given():
    assert error_for(distance=7.25).endswith('got 7.25')


def test_choices():
    assert load(mode='safe').mode == 'safe'
    message = error_for(mode='reckless')
    assert message.startswith('~mode: expected one of fast, safe')
    assert "'reckless'" in message


# --- check and check_together -------------------------------------------------------------------

def test_check_together_runs_after_the_fields_are_checked():
    message = error_for(low=3.0, high=3.0)
    assert message.startswith('~high: expected more than ~low (3 m)')


def test_check_together_sees_coerced_values():
    seen = []

    @dataclass
    class Recorder:
        count: int = param(2, '', 'how many', minimum=1)

        def check_together(self):
            seen.append(type(self.count))

    from_params(Recorder, lambda name, default: 5.0)
    assert seen == [int]


def test_check_validates_a_settings_object_built_in_code():
    assert check(Example(rate=5)).rate == 5.0
    with pytest.raises(SettingsError, match=r'^~count: '):
        check(Example(count=-2))


def test_settings_error_is_a_value_error():
    assert issubclass(SettingsError, ValueError)


def test_the_first_bad_field_in_declaration_order_is_named():
    message = error_for(rate=math.nan, count=0)
    assert message.startswith('~rate: ')
