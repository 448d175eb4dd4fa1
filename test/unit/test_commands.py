"""Velocity commands: the lesson's patterns and refusal of NaN / inf."""
import math

import pytest

from closed_loop.commands import (PATTERNS, STOP, CommandError, PublisherSettings, VelocityCommand,
                                  command_for, validate_command)
from closed_loop.settings import SettingsError, check


def test_patterns_are_the_lessons():
    assert {name: (c.linear_x, c.angular_z) for name, c in PATTERNS.items()} == {
        'forward': (0.5, 0.0), 'turn_left': (0.0, 0.5), 'curve': (0.5, 0.2), 'stop': (0.0, 0.0)}
    assert all(isinstance(c, VelocityCommand) for c in PATTERNS.values())


def test_validate_command_returns_floats():
    command = validate_command(1, -2)
    assert command == VelocityCommand(1.0, -2.0)
    assert type(command.linear_x) is float and type(command.angular_z) is float


@pytest.mark.parametrize('linear_x, angular_z, field', [
    (math.nan, 0.0, 'linear_x'), (math.inf, 0.0, 'linear_x'), (-math.inf, 0.0, 'linear_x'),
    (0.0, math.nan, 'angular_z'), (0.0, math.inf, 'angular_z'), ('0.5', 0.0, 'linear_x'),
    (0.0, None, 'angular_z'), (True, 0.0, 'linear_x')])
def test_bad_components_are_rejected_by_name(linear_x, angular_z, field):
    with pytest.raises(CommandError, match='^%s:' % field):
        validate_command(linear_x, angular_z)


def test_commands_cannot_be_built_around_the_check():
    with pytest.raises(CommandError, match='^linear_x:'):
        VelocityCommand(math.nan, 0.0)


def test_commands_are_immutable():
    with pytest.raises(AttributeError):
        STOP.linear_x = 1.0


def test_publisher_defaults_drive_forward_like_the_lesson():
    settings = check(PublisherSettings())
    assert settings.rate_hz == 10.0
    assert command_for(settings) == VelocityCommand(0.5, 0.0)


def test_pattern_overrides_linear_and_angular():
    settings = check(PublisherSettings(linear_x=0.1, angular_z=0.1, pattern='curve'))
    assert command_for(settings) == VelocityCommand(0.5, 0.2)
    assert command_for(check(PublisherSettings(linear_x=-0.2, angular_z=0.3))) == \
        VelocityCommand(-0.2, 0.3)


def test_unknown_pattern_is_rejected():
    with pytest.raises(SettingsError, match='~pattern: expected one of .*forward'):
        check(PublisherSettings(pattern='spin'))
    with pytest.raises(CommandError, match='^pattern:'):
        command_for(PublisherSettings(pattern='spin'))


@pytest.mark.parametrize('field', ['linear_x', 'angular_z'])
def test_non_finite_parameters_are_rejected(field):
    with pytest.raises(SettingsError, match='~%s' % field):
        check(PublisherSettings(**{field: math.nan}))
