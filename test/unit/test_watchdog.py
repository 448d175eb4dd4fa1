"""The silence watchdog: a stop when input stops arriving, on the wall clock, never for a stall of its own."""
import math
import threading
import time

import pytest

from closed_loop.watchdog import SilenceWatchdog


class FakeClock:
    def __init__(self):
        self.now_s = 100.0

    def __call__(self):
        return self.now_s


def test_watchdog_fires_only_after_the_timeout():
    clock = FakeClock()
    calls = []
    watchdog = SilenceWatchdog(0.5, 0.1, calls.append, clock=clock)
    clock.now_s += 0.5
    assert watchdog.check() is None
    clock.now_s += 0.01
    assert watchdog.check() == pytest.approx(0.51)
    assert calls == [pytest.approx(0.51)]
    watchdog.kick()
    clock.now_s += 0.3
    assert watchdog.check() is None
    assert len(calls) == 1


def test_watchdog_thread_calls_back_and_stops():
    fired = threading.Event()
    watchdog = SilenceWatchdog(0.01, 0.01, lambda silent_s: fired.set())
    watchdog.start()
    try:
        assert watchdog.running
        assert fired.wait(2.0)
    finally:
        watchdog.stop(join_timeout_s=2.0)
    assert not watchdog.running


def test_watchdog_discount_leaves_time_out():
    clock = FakeClock()
    calls = []
    watchdog = SilenceWatchdog(0.5, 0.1, calls.append, clock=clock)
    clock.now_s += 0.8
    watchdog.discount(0.6)
    assert watchdog.check() is None
    clock.now_s += 0.31
    assert watchdog.check() == pytest.approx(0.51)


def test_watchdog_thread_does_not_count_its_own_stall_as_silence():
    # The clock jumps 1 s between two wakes of the thread: the process was stalled, not the input.
    jump = {'s': 0.0}
    fired = threading.Event()
    watchdog = SilenceWatchdog(0.5, 0.02, lambda silent_s: fired.set(),
                               clock=lambda: time.monotonic() + jump['s'])
    watchdog.start()
    try:
        jump['s'] = 1.0
        assert not fired.wait(0.2), 'a stall of the checking thread was taken for silence'
        assert fired.wait(5.0), 'real silence after the stall went unnoticed'
    finally:
        watchdog.stop(join_timeout_s=2.0)


@pytest.mark.parametrize('timeout, period, field', [
    (0.0, 0.1, 'timeout_s'), (math.inf, 0.1, 'timeout_s'), (0.5, math.nan, 'period_s')])
def test_watchdog_rejects_bad_times(timeout, period, field):
    with pytest.raises(ValueError, match='^%s:' % field):
        SilenceWatchdog(timeout, period, lambda silent_s: None)
