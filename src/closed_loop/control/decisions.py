"""Stop / slow / cruise, the lesson's if-then rules made safe; free of ROS.

The lesson's rule (stop under 0.5 m, slow to 0.2 m/s under 1.0 m, else 0.5 m/s) is kept, with three
additions: a reading that is missing, stale or untrusted means stop; leaving a zone needs the distance
to clear its limit by a hysteresis margin, so sensor noise at a boundary cannot make the robot
stutter; and the controller host's silence watchdog (``closed_loop.watchdog``) stops the robot when
simulated time itself stops.
"""
import dataclasses
import enum
import math
import numbers
from typing import Optional

from closed_loop.control.loop import LoopSettings
from closed_loop.settings import SettingsError, param


class DecisionError(ValueError):
    """An argument of this module is unusable; the message names it and what was expected."""


class Zone(enum.IntEnum):
    """How close the nearest obstacle ahead is; a larger value is more dangerous."""
    CLEAR = 0
    SLOW = 1
    STOP = 2


@dataclasses.dataclass
class FrontControlSettings(LoopSettings):
    """The ``~parameters`` every front-scan controller shares (stop_on_obstacle, state_machine_controller)."""
    front_half_angle: float = param(math.pi / 2.0, 'rad', 'half-width of the front sector, centred '
                                    'on 0 (forward)', minimum=0.0, maximum=math.pi,
                                    exclusive_minimum=True, live=True)


@dataclasses.dataclass
class StopSettings(FrontControlSettings):
    """stop_on_obstacle's ``~parameters``; defaults are the lesson's."""
    stop_distance: float = param(0.5, 'm', 'stop when the nearest obstacle ahead is closer than this',
                                 minimum=0.0, exclusive_minimum=True, live=True)
    slow_distance: float = param(1.0, 'm', 'slow down when the nearest obstacle ahead is closer '
                                 'than this', minimum=0.0, exclusive_minimum=True, live=True)
    slow_speed: float = param(0.2, 'm/s', 'forward speed in the slow zone', minimum=0.0, live=True)
    cruise_speed: float = param(0.5, 'm/s', 'forward speed when the way ahead is clear', minimum=0.0, live=True)
    hysteresis: float = param(0.05, 'm', 'leave a zone only once the distance exceeds its limit by '
                              'this much', minimum=0.0, live=True)
    react_immediately: bool = param(True, '', 'act on a more dangerous scan at once from the scan '
                                    "callback; false gives the lesson's timer-only design", live=True)

    def check_together(self):
        if not self.stop_distance < self.slow_distance:
            raise SettingsError('~slow_distance: expected more than stop_distance (%g m), got %r'
                                % (self.stop_distance, self.slow_distance))
        if not self.slow_speed <= self.cruise_speed:
            raise SettingsError('~cruise_speed: expected at least slow_speed (%g m/s), got %r'
                                % (self.slow_speed, self.cruise_speed))


def _zone_limit_m(zone, settings):
    """The distance under which ``zone`` is entered (m)."""
    return settings.stop_distance if zone == Zone.STOP else settings.slow_distance


def _raw_zone(distance_m, settings):
    if distance_m < settings.stop_distance:
        return Zone.STOP
    if distance_m < settings.slow_distance:
        return Zone.SLOW
    return Zone.CLEAR


def classify_zone(distance_m, previous_zone, settings):
    # type: (float, Optional[Zone], StopSettings) -> Zone
    """The zone for an obstacle at ``distance_m`` (m), given the zone the robot was in.

    ``NaN`` gives STOP (unknown is dangerous); ``+inf`` is clear. Entering a more dangerous zone is
    immediate (``distance < limit``). Leaving one is stepwise: STOP is left only when
    ``distance >= stop_distance + hysteresis`` and SLOW only when
    ``distance >= slow_distance + hysteresis``; so from STOP a distance just past ``slow_distance``
    gives SLOW, not CLEAR. ``previous_zone`` None means no history (no hysteresis).
    """
    if not isinstance(distance_m, numbers.Real) or isinstance(distance_m, bool):
        raise DecisionError('distance_m: expected a number of m, got %r' % (distance_m,))
    if math.isnan(distance_m):
        return Zone.STOP
    zone = _raw_zone(distance_m, settings)
    if previous_zone is None or zone >= previous_zone:
        return zone
    held = Zone(previous_zone)
    while held > zone and distance_m >= _zone_limit_m(held, settings) + settings.hysteresis:
        held = Zone(held - 1)
    return held


def speed_for_zone(zone, settings):
    """Forward speed (m/s) for ``zone``: cruise_speed, slow_speed or 0."""
    if zone == Zone.CLEAR:
        return settings.cruise_speed
    if zone == Zone.SLOW:
        return settings.slow_speed
    return 0.0


@dataclasses.dataclass(frozen=True)
class Decision:
    """What to do: the zone, the forward speed (m/s) and a reason for the log. ``fault``: the stop is for
    want of usable input (no, stale or invalid scans), not for an obstacle."""
    zone: Zone
    linear_x: float
    reason: str
    fault: bool = dataclasses.field(default=False, compare=False)


def stop(reason):
    """A STOP decision with zero speed and ``reason``, for want of usable input (``fault``)."""
    return Decision(Zone.STOP, 0.0, reason, fault=True)


def input_problem(reading, reading_age_s, scan_timeout_s):
    """Why the reading cannot be acted on, or None when it can.

    ``reading`` is a :class:`closed_loop.control.scan.SectorReading` or None (no usable scan);
    ``reading_age_s`` is the time since its stamp (s), None when unknown. A reading is refused when
    it is missing, its age is unknown or NaN, it is older than ``scan_timeout_s``, it is stamped more
    than ``scan_timeout_s`` in the future (the clock jumped back: its age means nothing), or no ray
    in it was valid. A small negative age (clock skew between machines) is accepted.
    """
    if reading is None:
        return 'no usable scan'
    if reading_age_s is None or math.isnan(reading_age_s):
        return 'scan age unknown'
    if reading_age_s > scan_timeout_s:
        return 'scan is %.2f s old (scan_timeout %.2f s)' % (reading_age_s, scan_timeout_s)
    if reading_age_s < -scan_timeout_s:
        return ('scan is stamped %.2f s in the future (clock jumped back?)' % -reading_age_s)
    if not reading.trusted:
        return ('no valid reading ahead (%d of %d rays invalid)'
                % (reading.total - reading.valid, reading.total))
    return None


def decide(reading, reading_age_s, previous_zone, settings):
    # type: (object, Optional[float], Optional[Zone], StopSettings) -> Decision
    """The zone and forward speed for the front ``reading`` (a SectorReading or None).

    Missing, stale, future-stamped or untrusted readings (see :func:`input_problem`) give STOP with a
    reason naming why; otherwise :func:`classify_zone` with hysteresis from ``previous_zone``.
    """
    problem = input_problem(reading, reading_age_s, settings.scan_timeout)
    if problem is not None:
        return stop(problem)
    distance = reading.distance_m
    zone = classify_zone(distance, previous_zone, settings)
    raw = _raw_zone(distance, settings)
    if zone == raw:
        if zone == Zone.CLEAR:
            reason = 'clear ahead (%.2f m)' % distance
        else:
            reason = 'obstacle %.2f m ahead, under %s_distance %.2f m' % (
                distance, zone.name.lower(), _zone_limit_m(zone, settings))
    else:
        reason = 'obstacle %.2f m ahead, staying in %s until %.2f m' % (
            distance, zone.name, _zone_limit_m(zone, settings) + settings.hysteresis)
    return Decision(zone, speed_for_zone(zone, settings), reason)


def react_now(reading, reading_age_s, previous_zone, settings):
    # type: (object, Optional[float], Optional[Zone], StopSettings) -> bool
    """Whether a new ``reading`` must be acted on at once rather than at the next timer tick.

    Yes for the first decision (``previous_zone`` None: the end of start-up, before which nothing was
    sent); otherwise only with ``settings.react_immediately`` and when :func:`decide` would move to a
    more dangerous zone than ``previous_zone`` (a missing, stale or invalid reading counts: it is STOP).
    """
    if previous_zone is None:
        return True
    if not settings.react_immediately:
        return False
    return decide(reading, reading_age_s, previous_zone, settings).zone > previous_zone
