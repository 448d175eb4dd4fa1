"""Scan geometry and REP 117 handling, for every layout a LaserScan can take."""
import math

import numpy
import pytest

from closed_loop.control.scan import (DetectorSettings, Scan, ScanError, SectorReading, nearest,
                              sample_angles, sector_min, sector_readings, usable_ranges,
                              validate_scan)
from closed_loop.settings import SettingsError, check

RANGE_MIN = 0.12
RANGE_MAX = 3.5
DEG = math.pi / 180.0


def make_scan(ranges, angle_min=-math.pi, increment=2 * math.pi / 360, angle_max=None,
              range_min=RANGE_MIN, range_max=RANGE_MAX):
    ranges = numpy.asarray(ranges, dtype=float)
    if angle_max is None:
        angle_max = angle_min + (len(ranges) - 1) * increment
    return Scan(stamp_s=12.5, frame_id='base_scan', angle_min=angle_min, angle_max=angle_max,
                angle_increment=increment, time_increment=0.0, scan_time=0.1,
                range_min=range_min, range_max=range_max, ranges=ranges)


def clear_ranges(count=360):
    return numpy.full(count, numpy.inf)


# --- the simulator's default layout -------------------------------------------------------------

def test_default_layout_puts_the_front_at_index_180():
    angles = sample_angles(make_scan(clear_ranges()))
    assert len(angles) == 360
    assert angles[0] == pytest.approx(-math.pi)
    assert angles[180] == pytest.approx(0.0, abs=1e-12)
    assert angles[90] == pytest.approx(-math.pi / 2)
    assert angles[270] == pytest.approx(math.pi / 2)
    assert angles[359] == pytest.approx(math.pi - DEG)


def test_front_sector_sees_an_obstacle_straight_ahead():
    ranges = clear_ranges()
    ranges[180] = 0.8
    reading = sector_min(make_scan(ranges), 0.0, math.pi / 2)
    assert reading.distance_m == pytest.approx(0.8)
    assert reading.trusted


def test_front_sector_edges_are_inclusive_and_behind_is_excluded():
    ranges = clear_ranges()
    ranges[0] = 0.3     # straight behind
    ranges[89] = 0.4    # 91 degrees right
    ranges[271] = 0.5   # 91 degrees left
    scan = make_scan(ranges)
    reading = sector_min(scan, 0.0, math.pi / 2)
    assert reading.distance_m == math.inf
    assert reading.total == 181          # indices 90..270
    ranges[90] = 0.6                     # exactly -90 degrees
    ranges[270] = 0.7                    # exactly +90 degrees
    assert sector_min(make_scan(ranges), 0.0, math.pi / 2).distance_m == pytest.approx(0.6)
    ranges[90] = math.inf
    assert sector_min(make_scan(ranges), 0.0, math.pi / 2).distance_m == pytest.approx(0.7)


def test_float32_message_fields_keep_the_sector_edges():
    # LaserScan carries float32 angles: the rays at +-90 degrees land a few 1e-8 rad off the edge.
    def f32(value):
        return float(numpy.float32(value))

    increment = f32(2 * math.pi / 360)
    ranges = clear_ranges()
    ranges[90] = 0.6
    ranges[270] = 0.7
    scan = make_scan(ranges, angle_min=f32(-math.pi), increment=increment,
                     angle_max=f32(-math.pi + 359 * increment))
    reading = sector_min(scan, 0.0, math.pi / 2)
    assert reading.total == 181
    assert reading.distance_m == pytest.approx(0.6)


def test_left_and_right_follow_rep_103():
    ranges = clear_ranges()
    ranges[270] = 1.1   # +90 degrees: left
    ranges[90] = 2.2    # -90 degrees: right
    readings = sector_readings(make_scan(ranges), DetectorSettings())
    assert readings['left'].distance_m == pytest.approx(1.1)
    assert readings['right'].distance_m == pytest.approx(2.2)
    assert readings['front'].distance_m == pytest.approx(1.1)   # +-90 degrees includes both edges


# --- other layouts ------------------------------------------------------------------------------

def test_zero_based_layout_wraps_the_front_sector_across_index_zero():
    ranges = clear_ranges()
    ranges[355] = 0.9   # 355 degrees = 5 degrees right of forward
    ranges[180] = 0.2   # straight behind
    scan = make_scan(ranges, angle_min=0.0)
    reading = sector_min(scan, 0.0, 10 * DEG)
    assert reading.distance_m == pytest.approx(0.9)
    assert reading.total == 21           # -10..+10 degrees, across the index seam
    assert sector_min(scan, math.pi, 10 * DEG).distance_m == pytest.approx(0.2)


def test_negative_increment_layout():
    increment = -2 * math.pi / 360
    ranges = clear_ranges()
    ranges[90] = 1.5    # pi - 90 degrees = +90: left
    ranges[180] = 0.7   # forward
    scan = make_scan(ranges, angle_min=math.pi, increment=increment)
    validate_scan(scan)
    assert sample_angles(scan)[90] == pytest.approx(math.pi / 2)
    assert sector_min(scan, math.pi / 2, 5 * DEG).distance_m == pytest.approx(1.5)
    assert sector_min(scan, 0.0, 5 * DEG).distance_m == pytest.approx(0.7)
    assert sector_min(scan, -math.pi / 2, 5 * DEG).distance_m == math.inf


def test_half_circle_scan_has_no_rays_behind():
    ranges = clear_ranges(181)
    ranges[0] = 0.6     # -90 degrees: right
    ranges[-1] = 0.4    # +90 degrees: left
    scan = make_scan(ranges, angle_min=-math.pi / 2, increment=DEG)
    assert sector_min(scan, -math.pi / 2, 1 * DEG).distance_m == pytest.approx(0.6)
    assert sector_min(scan, math.pi / 2, 1 * DEG).distance_m == pytest.approx(0.4)
    behind = sector_min(scan, math.pi, 45 * DEG)
    assert behind.total == 0
    assert not behind.trusted
    assert math.isnan(behind.distance_m)


def test_scan_running_past_pi_is_wrapped():
    # 90 .. 270 degrees: the last rays are really -90 .. -pi.
    ranges = clear_ranges(181)
    ranges[180] = 0.5   # 270 degrees = -90 degrees
    scan = make_scan(ranges, angle_min=math.pi / 2, increment=DEG)
    assert sector_min(scan, -math.pi / 2, 2 * DEG).distance_m == pytest.approx(0.5)
    assert sector_min(scan, 0.0, 30 * DEG).total == 0


def test_whole_circle_half_width_takes_every_ray():
    ranges = clear_ranges()
    ranges[0] = 1.0
    reading = sector_min(make_scan(ranges), 0.0, math.pi)
    assert reading.total == 360
    assert reading.distance_m == pytest.approx(1.0)


def test_sector_rays_found_once_per_layout_read_each_scan():
    # The rays of a sector are worked out once for a layout; each scan's own ranges are still read.
    first, second = clear_ranges(), clear_ranges()
    first[180], second[181] = 0.8, 0.6
    assert sector_min(make_scan(first), 0.0, math.pi / 2).distance_m == pytest.approx(0.8)
    assert sector_min(make_scan(second), 0.0, math.pi / 2).distance_m == pytest.approx(0.6)
    assert sector_min(make_scan(second), math.pi, math.pi / 4).distance_m == math.inf


def test_sector_min_equals_the_sector_by_every_ray_on_random_layouts():
    rng = numpy.random.default_rng(7)
    for _ in range(200):
        count = int(rng.integers(1, 400))
        increment = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.001, 0.05))
        angle_min = float(rng.uniform(-4.0, 4.0))
        ranges = rng.uniform(0.0, 4.0, count)
        ranges[rng.random(count) < 0.1] = math.nan
        ranges[rng.random(count) < 0.1] = math.inf
        ranges[rng.random(count) < 0.05] = -math.inf
        centre, half = float(rng.uniform(-math.pi, math.pi)), float(rng.uniform(0.01, math.pi))
        scan = make_scan(ranges, angle_min=angle_min, increment=increment)
        angles = angle_min + numpy.arange(count) * increment
        wrapped = numpy.angle(numpy.exp(1j * (angles - centre)))
        inside = numpy.abs(wrapped) <= half + 1e-3 * abs(increment)
        usable = usable_ranges(scan)[inside]
        valid = usable[~numpy.isnan(usable)]
        reading = sector_min(scan, centre, half)
        assert (reading.total, reading.valid) == (int(inside.sum()), len(valid))
        if len(valid):
            assert reading.distance_m == valid.min()
        else:
            assert math.isnan(reading.distance_m)


# --- REP 117 ------------------------------------------------------------------------------------

def test_usable_ranges_follow_rep_117():
    raw = [-math.inf, math.inf, math.nan, 0.05, 4.0, RANGE_MIN, RANGE_MAX, 1.0]
    usable = usable_ranges(make_scan(raw, increment=DEG))
    assert usable[0] == RANGE_MIN            # too close to measure: an obstacle at range_min
    assert usable[1] == math.inf             # no return: clear
    assert math.isnan(usable[2])             # invalid
    assert math.isnan(usable[3])             # below range_min: invalid, not a close obstacle
    assert math.isnan(usable[4])             # beyond range_max: invalid, not clear
    assert usable[5] == RANGE_MIN            # limits are valid readings
    assert usable[6] == RANGE_MAX
    assert usable[7] == 1.0


def test_minus_inf_is_an_obstacle_at_range_min():
    ranges = clear_ranges()
    ranges[180] = -math.inf
    reading = sector_min(make_scan(ranges), 0.0, math.pi / 2)
    assert reading.distance_m == RANGE_MIN
    assert reading.trusted


def test_invalid_readings_are_ignored_not_taken_as_obstacles():
    ranges = clear_ranges()
    ranges[180] = 0.0        # below range_min: a raw min() would say "touching"
    ranges[181] = math.nan
    ranges[182] = 0.9
    reading = sector_min(make_scan(ranges), 0.0, math.pi / 2)
    assert reading.distance_m == pytest.approx(0.9)
    assert reading.valid == reading.total - 2


def test_all_clear_is_trusted_and_infinite():
    reading = nearest(make_scan(clear_ranges()))
    assert reading == SectorReading(distance_m=math.inf, valid=360, total=360)
    assert reading.trusted


def test_all_nan_sector_is_untrusted():
    ranges = clear_ranges()
    ranges[90:271] = math.nan
    reading = sector_min(make_scan(ranges), 0.0, math.pi / 2)
    assert reading.valid == 0
    assert reading.total == 181
    assert not reading.trusted
    assert math.isnan(reading.distance_m)
    # the rest of the scan is still fine
    assert nearest(make_scan(ranges)).trusted


def test_nearest_covers_the_whole_scan():
    ranges = clear_ranges()
    ranges[3] = 2.0
    ranges[300] = 1.25
    assert nearest(make_scan(ranges)).distance_m == pytest.approx(1.25)


def test_scan_keeps_its_own_read_only_copy_of_ranges():
    source = numpy.full(360, numpy.inf)
    scan = make_scan(source)
    source[180] = 0.2
    assert sector_min(scan, 0.0, 0.1).distance_m == math.inf
    with pytest.raises(ValueError):
        scan.ranges[0] = 1.0


# --- validation ---------------------------------------------------------------------------------

@pytest.mark.parametrize('field', ['angle_min', 'angle_max', 'angle_increment', 'range_min',
                                   'range_max'])
@pytest.mark.parametrize('bad', [math.nan, math.inf, -math.inf])
def test_non_finite_fields_are_rejected_by_name(field, bad):
    values = dict(stamp_s=0.0, frame_id='base_scan', angle_min=-math.pi, angle_max=math.pi - DEG,
                  angle_increment=DEG, time_increment=0.0, scan_time=0.1, range_min=RANGE_MIN,
                  range_max=RANGE_MAX, ranges=clear_ranges())
    values[field] = bad
    with pytest.raises(ScanError, match='^%s:' % field):
        validate_scan(Scan(**values))


def test_zero_increment_is_rejected():
    with pytest.raises(ScanError, match='^angle_increment:'):
        validate_scan(make_scan(clear_ranges(), increment=0.0, angle_max=-math.pi))


def test_empty_ranges_are_rejected():
    with pytest.raises(ScanError, match='^ranges:.*at least one'):
        validate_scan(make_scan([], angle_max=-math.pi))


def test_two_dimensional_ranges_are_rejected():
    scan = make_scan(numpy.ones((2, 3)), angle_max=-math.pi + 2 * DEG)
    with pytest.raises(ScanError, match='^ranges:.*one-dimensional'):
        validate_scan(scan)


def test_non_numeric_ranges_are_rejected_on_construction():
    with pytest.raises(ScanError, match='^ranges:'):
        Scan(stamp_s=0.0, frame_id='base_scan', angle_min=0.0, angle_max=2 * DEG,
             angle_increment=DEG, time_increment=0.0, scan_time=0.1, range_min=RANGE_MIN,
             range_max=RANGE_MAX, ranges=['far'] * 3)


@pytest.mark.parametrize('count', [359, 361])
def test_ranges_length_disagreeing_with_angles_is_rejected(count):
    scan = make_scan(clear_ranges(count), angle_max=-math.pi + 359 * DEG)
    with pytest.raises(ScanError, match='^ranges: %d readings.*describe 360' % count):
        validate_scan(scan)


def test_angle_max_one_increment_past_the_last_ray_is_rejected():
    # The off-by-one layout (angle_max = angle_min + len * increment) would shift every sector.
    scan = make_scan(clear_ranges(), angle_max=math.pi)
    with pytest.raises(ScanError, match='^ranges:'):
        validate_scan(scan)


def test_angle_max_within_half_an_increment_is_accepted():
    validate_scan(make_scan(clear_ranges(), angle_max=math.pi - DEG + 0.4 * DEG))
    with pytest.raises(ScanError, match='^ranges:'):
        validate_scan(make_scan(clear_ranges(), angle_max=math.pi - DEG + 0.6 * DEG))


def test_negative_range_min_is_rejected():
    with pytest.raises(ScanError, match='^range_min:'):
        validate_scan(make_scan(clear_ranges(), range_min=-0.1))


@pytest.mark.parametrize('range_max', [RANGE_MIN, RANGE_MIN - 0.01])
def test_range_max_not_above_range_min_is_rejected(range_max):
    with pytest.raises(ScanError, match='^range_max:'):
        validate_scan(make_scan(clear_ranges(), range_max=range_max))


def test_geometry_functions_refuse_a_bad_scan():
    scan = make_scan(clear_ranges(359), angle_max=math.pi - DEG)
    for call in (lambda: sample_angles(scan), lambda: usable_ranges(scan),
                 lambda: sector_min(scan, 0.0, 1.0), lambda: nearest(scan)):
        with pytest.raises(ScanError, match='^ranges:'):
            call()


@pytest.mark.parametrize('centre, half_width, field', [
    (math.nan, 1.0, 'center_rad'), (math.inf, 1.0, 'center_rad'),
    (0.0, math.nan, 'half_width_rad'), (0.0, -0.1, 'half_width_rad')])
def test_bad_sector_arguments_are_rejected(centre, half_width, field):
    with pytest.raises(ScanError, match='^%s:' % field):
        sector_min(make_scan(clear_ranges()), centre, half_width)


def test_detector_settings_limits():
    check(DetectorSettings())
    with pytest.raises(SettingsError, match='~side_half_angle'):
        check(DetectorSettings(side_half_angle=0.0))
    with pytest.raises(SettingsError, match='~front_half_angle'):
        check(DetectorSettings(front_half_angle=4.0))
