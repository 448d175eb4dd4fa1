"""The way a robot came (closed_loop.control.navigation.trail): the trail it keeps, and backing out along it."""
import math

import pytest

from closed_loop.control.navigation.trail import (BACK_STRAIGHT_RAD, BACK_TURN_ONLY_RAD, TRAIL_LENGTH_M, TRAIL_STEP_M, Trail,
                                       back_toward)


def test_a_point_every_step_travelled_and_no_more_than_the_length():
    trail = Trail()
    for i in range(1000):
        trail.add(0.01 * i, 0.0)          # 10 m in 1 cm steps
    assert len(trail) == int(round(TRAIL_LENGTH_M / TRAIL_STEP_M))
    assert trail.back(0.0) == pytest.approx((9.9, 0.0))
    standing = Trail()
    for _ in range(50):
        standing.add(1.0, 2.0)
    assert len(standing) == 1


def test_back_walks_the_trail_and_interpolates_round_corners():
    trail = Trail()
    for point in ((0.0, 0.0), (0.5, 0.0), (0.5, 0.5)):
        trail.add(*point)
    assert trail.back(0.0) == (0.5, 0.5)
    assert trail.back(0.2) == pytest.approx((0.5, 0.3))
    assert trail.back(0.7) == pytest.approx((0.3, 0.0))
    assert trail.back(5.0) == (0.0, 0.0)                  # shorter than asked: its oldest point
    assert Trail().back(1.0) is None


def test_drop_behind_forgets_what_backing_out_went_back_over():
    trail = Trail()
    for i in range(10):
        trail.add(0.1 * i, 0.0)
    trail.drop_behind(0.52, 0.01)
    assert trail.back(0.0) == pytest.approx((0.5, 0.0))
    assert len(trail) == 6


@pytest.mark.parametrize('yaw', [0.0, 1.0, -2.5])
def test_backing_toward_a_point_straight_behind_is_straight_back(yaw):
    pose = (1.0, 2.0, yaw)
    behind = (1.0 - math.cos(yaw), 2.0 - math.sin(yaw))
    v, w = back_toward(pose, behind, 0.15, 1.5)
    assert v == pytest.approx(-0.15) and w == pytest.approx(0.0, abs=1e-12)


def test_the_rear_turns_toward_a_point_off_to_one_side_and_backs_slower_the_farther_off_it_is():
    # The point behind and to the left (+y) of a robot facing +x: the rear turns left, which is a clockwise
    # turn of the body (w < 0).
    speeds = []
    for off in (0.5 * BACK_STRAIGHT_RAD, 0.5 * (BACK_STRAIGHT_RAD + BACK_TURN_ONLY_RAD), 1.5 * BACK_TURN_ONLY_RAD):
        v, w = back_toward((0.0, 0.0, 0.0), (-math.cos(off), math.sin(off)), 0.15, 1.5)
        assert w < 0.0
        speeds.append(v)
    assert speeds[0] == pytest.approx(-0.15) and -0.15 < speeds[1] < 0.0 and speeds[2] == 0.0
    assert back_toward((0.0, 0.0, 0.0), (0.0, -1.0), 0.15, 0.2)[1] == pytest.approx(0.2)       # within the limit
