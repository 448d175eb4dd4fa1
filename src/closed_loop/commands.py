"""Velocity commands and the lesson's command patterns; free of ROS.

A differential-drive robot takes a forward speed ``linear_x`` (m/s) and a yaw rate ``angular_z``
(rad/s, REP 103: positive turns left). Every command is checked on construction, so a NaN or an
infinity cannot reach ``cmd_vel``.
"""
import dataclasses
import math
import numbers

from closed_loop.settings import MIN_RATE_HZ, param


class CommandError(ValueError):
    """A velocity command is unusable; the message names the field."""


def _check_component(name, value, unit):
    if type(value) is float and math.isfinite(value):
        return value        # the usual case, without the slower abstract check below (a command a physics step)
    if not isinstance(value, numbers.Real) or isinstance(value, bool):
        raise CommandError('%s: expected a number of %s, got %r' % (name, unit, value))
    if not math.isfinite(value):
        raise CommandError('%s: expected a finite number of %s, got %r' % (name, unit, value))
    return float(value)


@dataclasses.dataclass(frozen=True)
class VelocityCommand:
    """Forward speed ``linear_x`` (m/s) and yaw rate ``angular_z`` (rad/s), both finite."""
    linear_x: float
    angular_z: float

    def __post_init__(self):
        object.__setattr__(self, 'linear_x', _check_component('linear_x', self.linear_x, 'm/s'))
        object.__setattr__(self, 'angular_z',
                           _check_component('angular_z', self.angular_z, 'rad/s'))


def validate_command(linear_x, angular_z):
    """A :class:`VelocityCommand`; :class:`CommandError` naming the field on NaN, inf or non-numbers."""
    return VelocityCommand(linear_x, angular_z)


STOP = VelocityCommand(0.0, 0.0)

# The lesson's common patterns.
PATTERNS = {
    'forward': VelocityCommand(0.5, 0.0),
    'turn_left': VelocityCommand(0.0, 0.5),
    'curve': VelocityCommand(0.5, 0.2),
    'stop': STOP,
}


@dataclasses.dataclass
class PublisherSettings:
    """velocity_publisher's ``~parameters``; defaults are the lesson's."""
    rate_hz: float = param(10.0, 'Hz', 'publishing rate (ROS clock)', minimum=MIN_RATE_HZ)
    linear_x: float = param(0.5, 'm/s', 'forward speed, used when pattern is empty')
    angular_z: float = param(0.0, 'rad/s', 'yaw rate (positive: left), used when pattern is empty')
    pattern: str = param('', '', "a named pattern (%s) or '' for linear_x / angular_z"
                         % ', '.join(sorted(PATTERNS)), choices=('',) + tuple(sorted(PATTERNS)))


def command_for(settings):
    """The command ``settings`` ask for: the named pattern, or linear_x / angular_z if it is ''."""
    if settings.pattern:
        try:
            return PATTERNS[settings.pattern]
        except KeyError:
            raise CommandError('pattern: expected one of %s, got %r'
                               % (', '.join(sorted(PATTERNS)), settings.pattern))
    return validate_command(settings.linear_x, settings.angular_z)
