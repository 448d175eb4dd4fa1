"""The velocity marker's geometry and colours (closed_loop.control.markers), without ROS."""
import math

import pytest

from closed_loop.control import markers


def test_straight_arrow_length_is_speed_times_horizon():
    assert markers.arrow_end(0.5, 0.0, 1.0) == (0.5, 0.0)
    assert markers.arrow_end(-0.3, 0.0, 2.0) == (-0.6, 0.0)


def test_turning_bends_the_arrow_to_the_left_for_positive_angular_z():
    x, y = markers.arrow_end(0.5, 0.5, 1.0)
    # On a circle of radius 1 m: after 0.5 rad, x = sin(0.5), y = 1 - cos(0.5).
    assert x == pytest.approx(math.sin(0.5))
    assert y == pytest.approx(1 - math.cos(0.5))
    assert markers.arrow_end(0.5, -0.5, 1.0)[1] == pytest.approx(-y)


def test_turning_in_place_has_no_arrow_length():
    assert markers.arrow_end(0.0, 1.0, 1.0) == pytest.approx((0.0, 0.0))


@pytest.mark.parametrize('speed, zone', [(0.0, 'STOP'), (0.2, 'SLOW'), (-0.1, 'SLOW'), (0.21, 'CLEAR'),
                                         (0.5, 'CLEAR')])
def test_zone_from_command(speed, zone):
    assert markers.zone_from_command(speed, 0.2) == zone


@pytest.mark.parametrize('name, zone', [('STOP', 'STOP'), ('slow', 'SLOW'), (' CLEAR ', 'CLEAR'),
                                        ('EXPLORING', None), ('BACKING_UP', None), ('dancing', None),
                                        ('', None)])
def test_controller_zone_names(name, zone):
    assert markers.normalise_zone(name) == zone


def test_zone_colours_are_distinct_traffic_lights():
    c = markers.ZONE_COLOURS
    assert c['STOP'][0] > 0.9 and c['STOP'][1] < 0.2
    assert c['CLEAR'][1] > 0.8 and c['CLEAR'][0] < 0.2
    assert len(set(c.values())) == 3


def test_distance_text_keeps_rep117_meanings():
    assert markers.distance_text(0.4821) == 'obstacle: 0.48 m'
    assert markers.distance_text(float('inf')) == 'obstacle: none in range'
    assert markers.distance_text(float('nan')) == 'obstacle: no valid reading'
    assert markers.distance_text(None) == 'obstacle: ?'
