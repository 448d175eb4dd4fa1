"""cmd_vel_guard's core on synthetic scans: predicted paths, footprint clearance, verdicts."""
import math

import numpy
import pytest

from closed_loop.control import guard, safety
from closed_loop import robot_model
from closed_loop.control.scan import Scan, scan_points
from closed_loop.settings import SettingsError, check

URDF = open(robot_model.default_urdf_path()).read()
FOOTPRINT = robot_model.footprint(URDF)
LASER = robot_model.frame_pose_2d(URDF, robot_model.SCAN_FRAME)
SETTINGS = check(guard.GuardSettings())
SAMPLES = 360


def scan_of(points_xy, stamp_s=0.0):
    """A full-turn scan (angle_min -pi) of point obstacles given in the laser frame, range_max 3.5 m."""
    increment = 2 * math.pi / SAMPLES
    ranges = numpy.full(SAMPLES, numpy.inf)
    for x, y in points_xy:
        i = int(round((math.atan2(y, x) + math.pi) / increment)) % SAMPLES
        ranges[i] = min(ranges[i], math.hypot(x, y))
    return Scan(stamp_s=stamp_s, frame_id='base_scan', angle_min=-math.pi,
                angle_max=-math.pi + increment * (SAMPLES - 1), angle_increment=increment, time_increment=0.0,
                scan_time=0.1, range_min=0.12, range_max=3.5, ranges=ranges)


def wall_ahead(distance_m, half_width_m=1.5):
    return [(distance_m, y) for y in numpy.arange(-half_width_m, half_width_m, 0.01)]


def run(points, v0, w0, v, w, settings=SETTINGS):
    return guard.filter_command(scan_points(scan_of(points), LASER), FOOTPRINT, v0, w0, v, w, settings)


def test_footprint_and_laser_come_from_the_urdf():
    assert (FOOTPRINT.x_min, FOOTPRINT.x_max) == pytest.approx((-0.15, 0.15))
    # The wheels (radius 0.05 m, 0.03 m wide, centred 0.14 m out) stick out past the 0.24 m body.
    assert (FOOTPRINT.y_min, FOOTPRINT.y_max) == pytest.approx((-0.155, 0.155))
    assert (LASER.x, LASER.y, LASER.yaw) == pytest.approx((0.0, 0.0, 0.0))


def test_scan_points_follow_rep_117():
    scan = scan_of([(1.0, 0.0)])
    ranges = scan.ranges.copy()
    ranges[0], ranges[1], ranges[2] = -numpy.inf, numpy.nan, 99.0
    scan = Scan(**dict(scan.__dict__, ranges=ranges))
    points = scan_points(scan, LASER)
    # +inf, NaN and out-of-limits give nothing; -inf is an object at range_min (behind: angle -pi).
    assert len(points) == 2
    assert points[0] == pytest.approx([-0.12, 0.0], abs=1e-9)
    assert points[1] == pytest.approx([1.0, 0.0], abs=1e-9)


def test_braking_path_is_v_squared_over_2a():
    poses = guard.predicted_poses(1.0, 0.0, 0.0, 0.0, SETTINGS)
    assert poses[-1][0] == pytest.approx(1.0 ** 2 / (2 * SETTINGS.braking_decel), abs=0.03)
    following = guard.predicted_poses(1.0, 0.0, 1.0, 0.0, SETTINGS)
    assert following[-1][0] == pytest.approx(poses[-1][0] + SETTINGS.reaction_time, abs=0.03)


def test_clearance_of_the_rectangle():
    points = numpy.array([[0.25, 0.0], [0.0, 0.5], [0.16, 0.165]])
    assert safety.footprint_clearance(points, FOOTPRINT, 0, 0, 0) == pytest.approx(math.hypot(0.01, 0.01))
    assert safety.footprint_clearance(numpy.array([[0.0, 0.0]]), FOOTPRINT, 0, 0, 0) == 0.0
    assert safety.footprint_clearance(numpy.zeros((0, 2)), FOOTPRINT, 0, 0, 0) == math.inf
    # Turned a quarter, the long side faces +y.
    assert safety.footprint_clearance(numpy.array([[0.0, 0.25]]), FOOTPRINT, 0, 0, math.pi / 2) == \
        pytest.approx(0.10)


def test_open_space_passes_the_command_whole():
    result = run([], 1.0, 0.0, 1.0, 0.5)
    assert result.verdict == guard.GuardVerdict.PASS and (result.linear_x, result.angular_z) == (1.0, 0.5)


def test_a_far_wall_passes_a_near_one_slows_a_close_one_vetoes():
    far = run(wall_ahead(2.0), 1.0, 0.0, 1.0, 0.0)
    near = run(wall_ahead(0.7), 1.0, 0.0, 1.0, 0.0)
    close = run(wall_ahead(0.24), 0.0, 0.0, 1.0, 0.0)
    assert far.verdict == guard.GuardVerdict.PASS
    assert near.verdict == guard.GuardVerdict.SLOWED and 0 < near.linear_x < 1.0
    assert close.verdict == guard.GuardVerdict.VETOED and (close.linear_x, close.angular_z) == (0.0, 0.0)
    for result in (far, near):
        assert result.clearance_m >= SETTINGS.safety_margin


def test_a_slowed_command_keeps_its_curvature():
    result = run(wall_ahead(0.7), 1.0, 0.0, 1.0, 0.4)
    assert result.verdict == guard.GuardVerdict.SLOWED
    assert result.angular_z / result.linear_x == pytest.approx(0.4)


def test_an_obstacle_beside_the_path_does_not_stop_it():
    result = run([(x, 0.5) for x in numpy.arange(0.0, 2.0, 0.02)], 0.5, 0.0, 0.5, 0.0)
    assert result.verdict == guard.GuardVerdict.PASS


def test_backing_away_from_a_wall_already_too_close_is_allowed():
    points = wall_ahead(0.2)
    assert run(points, 0.0, 0.0, -0.3, 0.0).verdict == guard.GuardVerdict.PASS
    assert run(points, 0.0, 0.0, 0.3, 0.0).verdict == guard.GuardVerdict.VETOED


def test_inside_the_margin_no_point_comes_closer_not_only_the_nearest():
    # A post 0.04 m off the left side (the nearest point) and a wall 0.08 m ahead, both within the margin.
    # Creeping ahead keeps the least clearance (the post's) but brings the wall closer: vetoed.
    post = [(0.0, FOOTPRINT.y_max + 0.04)]
    wall = [(FOOTPRINT.x_max + 0.08, y) for y in numpy.arange(-0.5, 0.5, 0.01)]
    points = scan_points(scan_of(post + wall), LASER)
    now = safety.footprint_clearance(points, FOOTPRINT, 0.0, 0.0, 0.0)
    assert now == pytest.approx(0.04, abs=0.005)
    creep = guard.predicted_poses(0.0, 0.0, 0.06 * 0.3, 0.0, SETTINGS)
    assert safety.path_clearance(points, FOOTPRINT, creep) >= now - safety.CLEARANCE_EPS_M   # the old rule's pass
    assert run(post + wall, 0.0, 0.0, 0.3, 0.0).verdict == guard.GuardVerdict.VETOED
    # Backing away from both passes; so does the same creep with the wall beyond the margin's reach.
    assert run(post + wall, 0.0, 0.0, -0.3, 0.0).verdict == guard.GuardVerdict.PASS
    far_wall = [(FOOTPRINT.x_max + 0.6, y) for y in numpy.arange(-0.5, 0.5, 0.01)]
    assert run(post + far_wall, 0.0, 0.0, 0.1, 0.0).verdict == guard.GuardVerdict.PASS


def test_turning_in_place_that_swings_a_corner_into_a_box_is_vetoed():
    # A point just off the front-left corner: turning left swings the corner into it.
    points = [(0.16, 0.2)]
    assert run(points, 0.0, 0.0, 0.0, 1.0).verdict != guard.GuardVerdict.PASS


def test_zero_passes_and_the_margin_is_kept_while_moving_fast():
    assert run(wall_ahead(0.3), 0.0, 0.0, 0.0, 0.0).verdict == guard.GuardVerdict.PASS
    result = run(wall_ahead(1.0), 1.0, 0.0, 1.0, 0.0)
    poses = guard.predicted_poses(1.0, 0.0, result.linear_x, result.angular_z, SETTINGS)
    points = scan_points(scan_of(wall_ahead(1.0)), LASER)
    assert safety.path_clearance(points, FOOTPRINT, poses) >= SETTINGS.safety_margin


def test_scan_problems_mean_no_motion():
    assert 'no usable scan' in guard.scan_problem(None, None, 0.5)
    assert 'old' in guard.scan_problem(scan_of(wall_ahead(1.0)), 0.8, 0.5)
    scan = scan_of([])
    nan_scan = Scan(**dict(scan.__dict__, ranges=numpy.full(SAMPLES, numpy.nan)))
    assert 'no valid reading' in guard.scan_problem(nan_scan, 0.0, 0.5)
    assert guard.scan_problem(scan_of(wall_ahead(1.0)), 0.05, 0.5) is None


def test_settings_limits():
    with pytest.raises(SettingsError, match='~safety_margin'):
        check(guard.GuardSettings(safety_margin=0.0))
    with pytest.raises(SettingsError, match='~rate_hz'):
        check(guard.GuardSettings(rate_hz=0.01))
