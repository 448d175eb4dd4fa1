"""The silence watchdog of a node that drives the robot: a stop when input stops arriving, on the wall clock.

A dead simulator also stops ``/clock``, and timers on the ROS clock then never fire; this one runs on a
monotonic wall clock in a thread of its own. Free of ROS.
"""
import math
import numbers
import threading
import time
from typing import Callable, Optional


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
                raise ValueError('%s: expected a positive finite number of s, got %r'
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
