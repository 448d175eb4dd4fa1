"""The simulator node's schedule: each sensor at its period and offset on simulated time, every-step tasks
every step, no slip through rounding."""
import pytest

from closed_loop.sim.scheduler import Schedule

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
