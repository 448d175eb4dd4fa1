"""Validated node settings: one dataclass per node holds every ``~parameter``, its default and unit.

A settings class is a plain dataclass whose fields are made with :func:`param`. The ROS layer reads
each field from the private parameter of the same name (``~stop_distance`` for ``stop_distance``),
and :func:`from_params` converts and checks the values, raising :class:`SettingsError` with the
parameter's name and what was expected. Defaults live here only; launch files override them.
"""
import dataclasses
import functools
import math
import typing

from closed_loop.yaml_check import quote


#: The least rate (Hz) of any node's timer or sensor: slower would leave its timers, and the watchdogs
#: that ride on them, asleep for seconds.
MIN_RATE_HZ = 1.0


class SettingsError(ValueError):
    """A parameter value is unusable; the message names the parameter and what was expected."""


def param(default, unit='', doc='', minimum=None, maximum=None, exclusive_minimum=False,
          choices=None, live=False):
    """A settings field: its default, unit, one-line meaning and the values it accepts.

    ``live``: the node takes a new value while it runs (dynamic_reconfigure, ``closed_loop.reconfigure``);
    the others (rates, timeouts, frames) are read once at start-up.
    """
    return dataclasses.field(default=default, metadata={
        'unit': unit, 'doc': doc, 'minimum': minimum, 'maximum': maximum,
        'exclusive_minimum': exclusive_minimum, 'choices': choices, 'live': live})


def _coerce(name, kind, value):
    """Convert ``value`` to ``kind`` the way a YAML/launch parameter is expected to arrive."""
    if kind is bool:
        if isinstance(value, bool):
            return value
        if isinstance(value, str) and value.lower() in ('true', 'false'):
            return value.lower() == 'true'
        raise SettingsError('~%s: expected true or false, got %s' % (name, quote(value)))
    if kind is float:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise SettingsError('~%s: expected a number, got %s' % (name, quote(value)))
        value = float(value)
        if not math.isfinite(value):
            raise SettingsError('~%s: expected a finite number, got %s' % (name, quote(value)))
        return value
    if kind is int:
        if isinstance(value, bool) or not isinstance(value, int):
            if isinstance(value, float) and value.is_integer():
                return int(value)
            raise SettingsError('~%s: expected an integer, got %s' % (name, quote(value)))
        return value
    if kind is str:
        if not isinstance(value, str):
            raise SettingsError('~%s: expected a string, got %s' % (name, quote(value)))
        return value
    return value


@functools.lru_cache(maxsize=None)
def _hints(cls):
    return typing.get_type_hints(cls)


def check(settings):
    """Check every field of ``settings`` against its limits; raise SettingsError on the first bad one."""
    hints = _hints(type(settings))
    for f in dataclasses.fields(settings):
        meta = f.metadata
        value = _coerce(f.name, hints.get(f.name), getattr(settings, f.name))
        object.__setattr__(settings, f.name, value)
        unit = (' ' + meta.get('unit')) if meta.get('unit') else ''
        low, high = meta.get('minimum'), meta.get('maximum')
        if low is not None:
            if meta.get('exclusive_minimum') and not value > low:
                raise SettingsError('~%s: expected more than %g%s, got %s' % (f.name, low, unit, quote(value)))
            if not value >= low:
                raise SettingsError('~%s: expected at least %g%s, got %s' % (f.name, low, unit, quote(value)))
        if high is not None and not value <= high:
            raise SettingsError('~%s: expected at most %g%s, got %s' % (f.name, high, unit, quote(value)))
        choices = meta.get('choices')
        if choices is not None and value not in choices:
            raise SettingsError('~%s: expected one of %s, got %s'
                                % (f.name, ', '.join(map(str, choices)), quote(value)))
    extra = getattr(settings, 'check_together', None)
    if extra is not None:
        extra()
    return settings


def from_params(cls, get_param):
    """Build ``cls`` from ``get_param(name, default)`` (e.g. ``rospy.get_param`` with ``~`` names)."""
    values = {}
    for f in dataclasses.fields(cls):
        values[f.name] = get_param('~' + f.name, f.default)
    return check(cls(**values))


def live_fields(cls):
    """The fields of ``cls`` a running node takes new values of, in declaration order."""
    return [f for f in dataclasses.fields(cls) if f.metadata.get('live')]


def describe(cls):
    """Rows of (name, default, unit, doc) for documentation and ``--help`` output."""
    return [(f.name, f.default, f.metadata.get('unit', ''), f.metadata.get('doc', ''))
            for f in dataclasses.fields(cls)]
