"""The lesson's EXPLORING / BACKING_UP state machine, with time handed in; free of ROS.

EXPLORING drives forward until an obstacle ahead is closer than ``trigger_distance``; BACKING_UP then
reverses for ``backup_duration`` and returns to EXPLORING. Time comes from the caller (the node passes
the ROS clock, so the machine runs on simulated time), which also makes it testable without sleeping.
"""
import dataclasses
import enum
import math
import numbers
from typing import Callable, Optional, Tuple

from closed_loop.control.decisions import FrontControlSettings
from closed_loop.control.loop import lasted
from closed_loop.settings import SettingsError, param


class StateMachineError(ValueError):
    """An argument to the state machine is unusable; the message names it."""


class State(enum.Enum):
    """What the robot is doing."""
    EXPLORING = 'EXPLORING'
    BACKING_UP = 'BACKING_UP'


@dataclasses.dataclass
class BackUpSettings(FrontControlSettings):
    """state_machine_controller's ``~parameters``; defaults are the lesson's."""
    trigger_distance: float = param(0.5, 'm', 'back up when the nearest obstacle ahead is closer than '
                                    'this', minimum=0.0, exclusive_minimum=True, live=True)
    explore_speed: float = param(0.5, 'm/s', 'forward speed while exploring', minimum=0.0, live=True)
    backup_speed: float = param(-0.3, 'm/s', 'speed while backing up (negative: reverse)', live=True)
    backup_duration: float = param(2.0, 's', 'how long to back up', minimum=0.0,
                                   exclusive_minimum=True, live=True)

    def check_together(self):
        if not self.backup_speed < 0.0:
            raise SettingsError('~backup_speed: expected less than 0 m/s (reverse), got %r'
                                % self.backup_speed)


def react_now(state, reading, settings):
    """Whether a new front ``reading`` (a SectorReading or None) must be acted on at once: a trusted
    reading closer than ``trigger_distance`` while EXPLORING (backing up starts now, not at the next
    tick). A stale or invalid reading is caught by the timer's own check."""
    return (state is State.EXPLORING and reading is not None and reading.trusted
            and reading.distance_m < settings.trigger_distance)


def _check_number(name, value, unit, allow_infinite):
    if not isinstance(value, numbers.Real) or isinstance(value, bool) or math.isnan(value):
        raise StateMachineError('%s: expected a number of %s, got %r' % (name, unit, value))
    if not allow_infinite and math.isinf(value):
        raise StateMachineError('%s: expected a finite number of %s, got %r' % (name, unit, value))


class BackUpStateMachine:
    """EXPLORING / BACKING_UP, advanced by :meth:`update` with a distance and the current time.

    ``on_transition(old, new, now_s)``, if given, is called after every state change (the node logs
    and publishes from it; the machine itself does not log).
    """

    def __init__(self, settings, on_transition=None):
        # type: (BackUpSettings, Optional[Callable[[State, State, float], None]]) -> None
        self._settings = settings
        self._on_transition = on_transition
        self._state = State.EXPLORING
        self._entered_s = None  # type: Optional[float]
        self._last_now_s = None  # type: Optional[float]

    @property
    def state(self):
        """The current :class:`State`."""
        return self._state

    def time_in_state(self, now_s):
        """Seconds spent in the current state at ``now_s``; 0 before the first update."""
        if self._entered_s is None:
            return 0.0
        return max(0.0, now_s - self._entered_s)

    def reconfigure(self, settings):
        # type: (BackUpSettings) -> None
        """Go on with new settings: the state and the time it was entered stay; the next update judges
        them by the new values (a shorter ``backup_duration`` may end BACKING_UP at once)."""
        self._settings = settings

    def speed(self):
        """Forward speed (m/s) for the current state."""
        if self._state is State.BACKING_UP:
            return self._settings.backup_speed
        return self._settings.explore_speed

    def update(self, distance_m, now_s):
        # type: (float, float) -> Tuple[State, float]
        """Advance with the nearest obstacle ahead (m) at time ``now_s`` (s); return (state, m/s).

        ``distance_m`` may be ``+inf`` (clear) but not NaN: an unknown distance is the caller's to
        handle (stop without advancing the machine), never a value to act on. BACKING_UP lasts
        exactly ``backup_duration``: it ends at the first update with ``now_s - entered >=
        backup_duration``. If the obstacle is still within ``trigger_distance`` then, backing up
        starts again in the same update rather than driving forward for a period. When ``now_s`` is
        earlier than the previous update's (a ``/clock`` reset, a looping bag) the current state's
        timer restarts from ``now_s`` instead of running negative.
        """
        _check_number('distance_m', distance_m, 'm', allow_infinite=True)
        _check_number('now_s', now_s, 's', allow_infinite=False)
        if self._entered_s is None or now_s < self._last_now_s:
            self._entered_s = now_s
        self._last_now_s = now_s
        if (self._state is State.BACKING_UP
                and lasted(now_s - self._entered_s, self._settings.backup_duration)):
            self._enter(State.EXPLORING, now_s)
        if self._state is State.EXPLORING and distance_m < self._settings.trigger_distance:
            self._enter(State.BACKING_UP, now_s)
        return self._state, self.speed()

    def _enter(self, state, now_s):
        old = self._state
        self._state = state
        self._entered_s = now_s
        if self._on_transition is not None:
            self._on_transition(old, state, now_s)
