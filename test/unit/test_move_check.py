"""The exact check of a slow move off the dynamic window (``closed_loop.control.navigation.move_check``): the margin from
what the scan shows, the margin and a doubt from what is remembered where it cannot see, and, where the robot
already stands closer than that, only moves that bring nothing closer."""
import math

import numpy
import pytest

from closed_loop.control.navigation.move_check import BLIND_DRIFT_MPS, BLIND_EXTRA_M, MoveCheck
from closed_loop.control.navigation.navigator import NavigatorSettings
from closed_loop.control.scan import Scan
from closed_loop.geometry import Pose2D
from closed_loop.robot_model import Footprint

JACKAL = Footprint(-0.254, 0.254, -0.2155, 0.2155)
LASER = Pose2D(0.0, 0.0, 0.0)
SETTINGS = NavigatorSettings()


def open_front_scan():
    """A 270-degree scan that sees nothing: behind the robot is the blind sector."""
    rays = 541
    return Scan(0.0, 'laser', -3 * math.pi / 4, 3 * math.pi / 4, 1.5 * math.pi / (rays - 1), 0.0, 0.1, 0.1, 8.0,
                numpy.full(rays, numpy.inf))


def check_with_post_behind(gap_m, seen_ago_s):
    """A MoveCheck at rest with one point remembered ``gap_m`` behind the Jackal's rear edge, seen
    ``seen_ago_s`` ago, where the LIDAR cannot see."""
    remembered = numpy.array([[JACKAL.x_min - gap_m, 0.0]])
    return MoveCheck(SETTINGS, JACKAL, 0.0, 0.0, open_front_scan(), LASER, numpy.zeros((0, 2)), remembered,
                     numpy.array([0.0]), seen_ago_s)


def test_a_point_behind_with_room_allows_every_move_that_keeps_the_margin_and_its_doubt():
    check = check_with_post_behind(0.5, 0.0)
    assert check.safe(0.2, 0.0, 1.0) and check.safe(0.0, 0.5, 1.0) and check.safe(-0.15, 0.0, 1.0)


def test_a_move_into_the_margin_and_doubt_of_a_point_behind_is_refused():
    # 0.2 m behind, seen just now: backing up 0.15 m (then braking) would come within the margin and the doubt.
    gap = 0.2
    check = check_with_post_behind(gap, 0.0)
    assert gap > SETTINGS.safety_margin + BLIND_EXTRA_M
    assert not check.safe(-0.15, 0.0, 1.0)
    assert check.safe(0.2, 0.0, 1.0)


@pytest.mark.parametrize('seen_ago_s', [0.0, 30.0])
def test_already_within_the_margin_and_doubt_a_move_away_is_allowed_and_one_closer_is_not(seen_ago_s):
    # 0.09 m behind: inside the margin and the doubt (BLIND_EXTRA_M, and after 30 s the drift's 0.15 m more).
    # Driving straight ahead brings it no closer, and must stay allowed however the doubt grows while the robot
    # stands there; backing up, or a turn in place that swings a rear corner round toward it, is not.
    gap = 0.09
    check = check_with_post_behind(gap, seen_ago_s)
    assert gap < SETTINGS.safety_margin + BLIND_EXTRA_M + BLIND_DRIFT_MPS * seen_ago_s
    assert check.safe(0.2, 0.0, 1.0)
    assert not check.safe(-0.15, 0.0, 1.0)
    assert not check.safe(0.0, 0.8, 1.0)


def test_within_the_margin_of_one_point_a_creep_toward_another_into_its_margin_is_refused():
    """The hole of a rule on the least clearance alone: 1 cm from a post beside it (within the margin), the
    robot creeps toward another ahead, 0.14 m off, which would come to about 0.035 m, inside the margin, while the
    least clearance (to the one beside) never shrinks. Point by point (``safety.keeps_room``) it is refused; the
    same creep with the post ahead out of its way passes (the one beside comes no closer)."""
    beside = numpy.array([[0.0, JACKAL.y_max + 0.01]])
    post = numpy.array([[JACKAL.x_max + 0.14, 0.0]])
    none = numpy.zeros((0, 2))

    def check(points):
        return MoveCheck(SETTINGS, JACKAL, 0.0, 0.0, open_front_scan(), LASER, points, none, numpy.zeros(0), 0.0)

    assert check(numpy.concatenate((beside, post))).safe(0.1, 0.0, 1.0) is False
    assert check(beside).safe(0.1, 0.0, 1.0) is True
