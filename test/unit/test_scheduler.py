"""The simulator node's schedule: each sensor at its period and offset on simulated time, every-step tasks
every step, no slip through rounding."""
import pytest

from closed_loop.sim.scheduler import ClockSchedule, Schedule, SchedulingSettings

STEP_S = 0.01


def run(schedule, seconds):
    hits = {}
    steps = int(round(seconds / STEP_S))
    for i in range(1, steps + 1):
        t = i * STEP_S
        for name in schedule.due(t):
            hits.setdefault(name, []).append(round(t, 6))
    return hits


def test_periods_offsets_and_every_step():
    schedule = Schedule(STEP_S)
    schedule.add('contacts')
    schedule.add('lidar', 0.1)
    schedule.add('camera', 0.1, 0.05)
    schedule.add('odom', 0.02)
    hits = run(schedule, 1.0)
    assert len(hits['contacts']) == 100
    assert hits['lidar'][:3] == [0.01, 0.1, 0.2] and len(hits['lidar']) == 11
    assert hits['camera'][:3] == [0.05, 0.15, 0.25] and len(hits['camera']) == 10
    assert len(hits['odom']) == 51


def test_order_is_the_order_added():
    schedule = Schedule(STEP_S)
    for name in ('a', 'b', 'c'):
        schedule.add(name, 0.1)
    assert schedule.due(0.01) == ['a', 'b', 'c']


@pytest.mark.parametrize('period', [0.07, 0.1, 0.2, 1.0 / 3])
def test_no_drift_over_a_long_run(period):
    schedule = Schedule(STEP_S)
    schedule.add('x', period)
    hits = run(schedule, 100.0)
    assert len(hits['x']) == pytest.approx(100.0 / period + 1, abs=1)


def clock_hits(rtf, seconds, wall_of_step, max_rate_hz=100.0):
    """The steps after which /clock goes out, steps at wall_of_step(i)."""
    settings = SchedulingSettings(real_time_factor=rtf, max_clock_rate_hz=max_rate_hz)
    clock = ClockSchedule(settings, STEP_S, wall_of_step(0))
    steps = int(round(seconds / STEP_S))
    return [i for i in range(1, steps + 1) if clock.due(i * STEP_S, wall_of_step(i))]


def test_clock_at_real_time_every_step_even_while_catching_up():
    # On time, and with steps 41 to 60 all at one wall instant (the loop catching up a 0.2 s stall): a
    # wall-clock rate (hztest's) counts every step either way. On the wall clock, 18 of them were lost.
    assert len(clock_hits(1.0, 1.0, lambda i: i * STEP_S)) == 100
    assert len(clock_hits(1.0, 1.0, lambda i: 0.6 if 40 < i <= 60 else i * STEP_S)) == 100


def test_clock_faster_than_real_time_is_throttled_on_simulated_time():
    # One in four steps (and the first): 25 per simulated second, 100 per wall second.
    hits = clock_hits(4.0, 1.0, lambda i: i * STEP_S / 4.0)
    assert len(hits) == 26 and hits[:3] == [1, 4, 8]
    # 2.5 steps per message: 40 per simulated second.
    assert len(clock_hits(2.5, 1.0, lambda i: i * STEP_S / 2.5)) == 41


def test_clock_as_fast_as_possible_is_throttled_on_the_wall_clock_without_a_burst():
    # Steps 1 ms of wall time apart: one in ten goes out (and the first).
    assert len(clock_hits(0.0, 10.0, lambda i: i * 0.001)) == 101
    # A 1 s stall after step 100, then 1900 steps at one instant: not a burst (the tolerance lets a second by).
    hits = clock_hits(0.0, 2.0, lambda i: i * 0.001 if i <= 100 else 1.1)
    assert len([i for i in hits if i > 100]) == 2
