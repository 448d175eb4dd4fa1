"""Live settings: the dynamic_reconfigure description of a settings class, and applying a change to it.

The description is built at run time from the settings class's fields marked ``live``
(:func:`closed_loop.settings.param`): name, type, default, limits and a description that carries the
unit. There is no ``cfg/*.cfg`` file and no generated module, so nothing is built at catkin time and
ROS Noetic's dynamic_reconfigure (the same Python server) serves the same description. A change is
checked by the settings class itself (:func:`closed_loop.settings.check`, including rules between
fields such as stop below slow); a value that breaks one is refused with that message. Free of ROS.
"""
import dataclasses
import math
import types
import typing

from closed_loop.settings import SettingsError, check, live_fields

#: The reconfigure level of every live parameter (one group, one level: a change is applied whole).
LEVEL = 1
#: The description's only group (dynamic_reconfigure's default group has id 0).
_GROUP = {'name': 'Default', 'type': '', 'state': True, 'cstate': 'true', 'id': 0, 'parent': 0,
          'groups': [], 'srcline': 0, 'srcfile': 'closed_loop/reconfigure.py', 'class': 'DEFAULT',
          'parentclass': '', 'parentname': 'Default', 'field': 'default', 'upper': 'DEFAULT',
          'lower': 'groups'}
_TYPE_NAMES = {float: 'double', int: 'int', bool: 'bool', str: 'str'}
_INT_LIMITS = (-2 ** 31, 2 ** 31 - 1)


def _limits(kind, meta):
    if kind is bool:
        return False, True
    if kind is str:
        return '', ''
    low, high = meta.get('minimum'), meta.get('maximum')
    if kind is int:
        return (_INT_LIMITS[0] if low is None else int(low)), (_INT_LIMITS[1] if high is None else int(high))
    return (-math.inf if low is None else float(low)), (math.inf if high is None else float(high))


def _description(f):
    meta = f.metadata
    text = meta.get('doc', '')
    if meta.get('unit'):
        text += ' (%s)' % meta['unit']
    if meta.get('exclusive_minimum'):
        text += '; more than the minimum'
    return text


def config_type(cls, settings=None):
    """The dynamic_reconfigure config type for ``cls``'s live fields: an object with the attributes a
    module generated from a ``.cfg`` file has (``config_description``, ``defaults``, ``min``, ``max``,
    ``level``, ``type``, ``all_level``), for ``dynamic_reconfigure.server.Server``.

    ``settings``: an instance whose values become the defaults (the node's effective start values);
    the class defaults otherwise. Raises SettingsError for a live field of a type it cannot serve.
    """
    hints = typing.get_type_hints(cls)
    parameters = []
    for f in live_fields(cls):
        kind = hints.get(f.name)
        if kind not in _TYPE_NAMES:
            raise SettingsError('~%s: a live parameter must be a float, int, bool or str' % f.name)
        low, high = _limits(kind, f.metadata)
        default = getattr(settings, f.name) if settings is not None else f.default
        parameters.append({'name': f.name, 'type': _TYPE_NAMES[kind], 'default': kind(default),
                           'level': LEVEL, 'description': _description(f), 'min': low, 'max': high,
                           'srcline': 0, 'srcfile': 'closed_loop/reconfigure.py', 'edit_method': '',
                           'ctype': _TYPE_NAMES[kind], 'cconsttype': 'const ' + _TYPE_NAMES[kind]})
    description = dict(_GROUP, parameters=parameters)
    return types.SimpleNamespace(
        config_description=description,
        defaults={p['name']: p['default'] for p in parameters},
        min={p['name']: p['min'] for p in parameters},
        max={p['name']: p['max'] for p in parameters},
        level={p['name']: p['level'] for p in parameters},
        type={p['name']: p['type'] for p in parameters},
        all_level=LEVEL if parameters else 0)


def live_values(settings):
    """{name: value} of the live fields of ``settings``."""
    return {f.name: getattr(settings, f.name) for f in live_fields(type(settings))}


def changed(settings, config):
    """``settings`` with the live fields ``config`` ({name: value}, other keys ignored) gives, checked
    whole by the settings class. Raises SettingsError naming the field and what was expected; the
    original ``settings`` is never modified."""
    updates = {f.name: config[f.name] for f in live_fields(type(settings)) if f.name in config}
    return check(dataclasses.replace(settings, **updates))


def differences(old, new):
    """'name old -> new' for each live field that differs, for the log."""
    return ', '.join('%s %r -> %r' % (name, value, getattr(new, name))
                     for name, value in live_values(old).items() if getattr(new, name) != value)
