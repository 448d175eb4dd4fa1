"""Stop / slow / cruise, the lesson's if-then rules made safe; free of ROS.

The lesson's rule (stop under 0.5 m, slow to 0.2 m/s under 1.0 m, else 0.5 m/s) is kept, with three
additions: a reading that is missing, stale or untrusted means stop; leaving a zone needs the distance
to clear its limit by a hysteresis margin, so sensor noise at a boundary cannot make the robot
stutter; and a silence watchdog on the wall clock, for when simulated time itself stops.
"""
import dataclasses
import enum
import math
import numbers
import threading
import time
from typing import Callable, Optional

from closed_loop import robot_model
from closed_loop.settings import MIN_RATE_HZ, SettingsError, param


class DecisionError(ValueError):
    """An argument of this module is unusable; the message names it and what was expected."""


class Zone(enum.IntEnum):
    """How close the nearest obstacle ahead is; a larger value is more dangerous."""
    CLEAR = 0
    SLOW = 1
    STOP = 2


#: Scans older than this are never acted on, whatever ``~scan_timeout`` says.
MAX_SCAN_TIMEOUT_S = 5.0


@dataclasses.dataclass
class FrontControlSettings:
    """The ``~parameters`` every front-scan controller shares (stop_on_obstacle, state_machine_controller)."""
    front_half_angle: float = param(math.pi / 2.0, 'rad', 'half-width of the front sector, centred '
                                    'on 0 (forward)', minimum=0.0, maximum=math.pi,
                                    exclusive_minimum=True, live=True)
    rate_hz: float = param(10.0, 'Hz', 'control timer rate (ROS clock)', minimum=MIN_RATE_HZ)
    scan_timeout: float = param(0.5, 's', 'stop when the newest scan is older than this (or none '
                                'has arrived)', minimum=0.0, maximum=MAX_SCAN_TIMEOUT_S,
                                exclusive_minimum=True)
    scan_frame: str = param(robot_model.SCAN_FRAME, '', "the laser's frame_id: scans in any other "
                            'frame are refused (stop)')

    @property
    def watchdog_period_s(self):
        """How often the silence watchdog looks: a control period, or half the timeout if that is shorter."""
        return min(1.0 / self.rate_hz, 0.5 * self.scan_timeout)


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


class SilenceWatchdog:
    """Calls ``on_silence(silent_s)`` every ``period_s`` while nothing has arrived for ``timeout_s``.

    It runs on a monotonic wall clock in a daemon thread, so it keeps working when simulated time
    stops (a dead simulator also stops ``/clock``, and timers on the ROS clock then never fire).
    :meth:`kick` records an arrival; the time before the first kick counts from construction. A stall
    of this process (the thread wakes more than a period late) is not silence: it is left out.
    ``clock`` (s) is injectable for tests.
    """

    def __init__(self, timeout_s, period_s, on_silence, clock=time.monotonic):
        # type: (float, float, Callable[[float], None], Callable[[], float]) -> None
        for name, value in (('timeout_s', timeout_s), ('period_s', period_s)):
            if not (isinstance(value, numbers.Real) and math.isfinite(value) and value > 0):
                raise DecisionError('%s: expected a positive finite number of s, got %r'
                                    % (name, value))
        self._timeout_s = timeout_s
        self._period_s = period_s
        self._on_silence = on_silence
        self._clock = clock
        self._lock = threading.Lock()
        self._last_arrival_s = clock()
        self._stopped = threading.Event()
        self._thread = None  # type: Optional[threading.Thread]

    def kick(self):
        """Record that input arrived now."""
        with self._lock:
            self._last_arrival_s = self._clock()

    def silent_for(self):
        """Seconds since the last arrival (or since construction)."""
        with self._lock:
            return self._clock() - self._last_arrival_s

    def check(self):
        """Call ``on_silence`` if the silence exceeds ``timeout_s``; return the silence (s) or None."""
        silent = self.silent_for()
        if silent > self._timeout_s:
            self._on_silence(silent)
            return silent
        return None

    def start(self):
        """Start checking every ``period_s`` in a daemon thread."""
        self._thread = threading.Thread(target=self._run, name='silence_watchdog', daemon=True)
        self._thread.start()

    def stop(self, join_timeout_s=0.0):
        """Stop the thread; wait up to ``join_timeout_s`` for it (it ends within one period)."""
        self._stopped.set()
        if self._thread is not None and join_timeout_s > 0.0:
            self._thread.join(join_timeout_s)

    @property
    def running(self):
        """True while the checking thread is alive."""
        return self._thread is not None and self._thread.is_alive()

    def discount(self, stalled_s):
        """Do not count ``stalled_s`` seconds, in which this process itself was not running, as silence."""
        with self._lock:
            self._last_arrival_s += max(0.0, stalled_s)

    def _run(self):
        woke = self._clock()
        while not self._stopped.wait(self._period_s):
            now = self._clock()
            slept, woke = now - woke, now
            # Woken a whole period late: the process (or the machine) was stalled, and the input that
            # came meanwhile still waits in the socket for its callbacks. Judging now would stop the
            # robot for silence that was ours; the stall is left out and the next period judges.
            if slept > 2.0 * self._period_s:
                self.discount(slept - self._period_s)
            self.check()
