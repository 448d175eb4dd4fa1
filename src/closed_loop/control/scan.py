"""Laser scan geometry with REP 117 range semantics, free of ROS.

A :class:`Scan` is a plain copy of a ``sensor_msgs/LaserScan``. Ray ``i`` points at
``angle_min + i * angle_increment`` (rad, REP 103: counter-clockwise, 0 = forward), whatever the
layout: ``angle_min = -pi`` with the front in the middle, ``angle_min = 0`` sweeping to ``2 pi``,
180-degree scans, negative increments. Sectors are therefore always picked by angle, never by a
fraction of the index range.

REP 117 meaning of ``ranges``: ``+inf`` no return within ``range_max`` (clear), ``-inf`` an object
closer than ``range_min`` (an obstacle too close to measure), ``NaN`` an invalid measurement. Finite
values outside ``[range_min, range_max]`` are invalid too. A raw ``min()`` over ``ranges`` gets all of
this wrong, so use :func:`sector_min` or :func:`nearest`.
"""
import dataclasses
import functools
import math
import numbers
from typing import Optional

import numpy

from closed_loop.settings import param

# Rays whose angle lies within this fraction of an increment outside a sector's edge still count.
# LaserScan angle fields are float32 and sample angles are sums of them, so a ray meant to sit
# exactly on an edge (-pi/2 in the default scan) can miss it by ~1e-7 rad; a thousandth of an
# increment absorbs that without ever taking in the neighbouring ray.
EDGE_TOLERANCE_INCREMENTS = 1e-3

# Sector centres published by obstacle_detector (REP 103: +y, i.e. left, is +pi/2).
SECTOR_CENTRES_RAD = {'front': 0.0, 'left': math.pi / 2.0, 'right': -math.pi / 2.0}


class ScanError(ValueError):
    """A scan (or a sector request) is unusable; the message starts with the offending field."""


@dataclasses.dataclass(frozen=True, eq=False)
class Scan:
    """A plain copy of a ``sensor_msgs/LaserScan``; angles in rad, ranges in m, times in s.

    ``ranges`` is stored as a read-only float64 copy. ``eq=False`` because comparing numpy arrays
    with ``==`` has no single truth value.
    """
    stamp_s: float
    frame_id: str
    angle_min: float
    angle_max: float
    angle_increment: float
    time_increment: float
    scan_time: float
    range_min: float
    range_max: float
    ranges: numpy.ndarray

    def __post_init__(self):
        try:
            ranges = numpy.array(self.ranges, dtype=numpy.float64)
        except (TypeError, ValueError) as error:
            raise ScanError('ranges: expected a sequence of numbers (m), got %r (%s)'
                            % (type(self.ranges).__name__, error))
        ranges.flags.writeable = False
        object.__setattr__(self, 'ranges', ranges)


def _is_finite_number(value):
    if type(value) is float:            # the usual case, without the abstract class's slower check
        return math.isfinite(value)
    return (isinstance(value, numbers.Real) and not isinstance(value, bool)
            and math.isfinite(value))


_FINITE_FIELDS = ('angle_min', 'angle_max', 'angle_increment', 'range_min', 'range_max')


def validate_scan(scan):
    """Raise :class:`ScanError` unless ``scan``'s geometry is usable.

    Checks: angle and range fields finite; ``angle_increment != 0``; ``ranges`` one-dimensional and
    not empty; ``len(ranges)`` agreeing with the angle fields, i.e. ``angle_max`` within half an
    increment of ``angle_min + (len - 1) * angle_increment`` (the ROS convention: ``angle_max`` is
    the angle of the last ray); ``range_min >= 0``; ``range_max > range_min``. The values inside
    ``ranges`` are not checked here: NaN and out-of-limit readings are data (see
    :func:`usable_ranges`), not a malformed scan.
    """
    for name in _FINITE_FIELDS:
        value = getattr(scan, name)
        if not _is_finite_number(value):
            raise ScanError('%s: expected a finite number, got %r' % (name, value))
    if scan.angle_increment == 0.0:
        raise ScanError('angle_increment: expected a non-zero angle step (rad), got 0')
    ranges = scan.ranges
    if ranges.ndim != 1:
        raise ScanError('ranges: expected a one-dimensional sequence, got shape %s' % (ranges.shape,))
    count = len(ranges)
    if count == 0:
        raise ScanError('ranges: expected at least one reading, got none')
    expected_max = scan.angle_min + (count - 1) * scan.angle_increment
    if abs(scan.angle_max - expected_max) > abs(scan.angle_increment) / 2.0:
        described = int(round((scan.angle_max - scan.angle_min) / scan.angle_increment)) + 1
        raise ScanError(
            'ranges: %d readings, but angle_min %.6f, angle_max %.6f and angle_increment %.6f rad '
            'describe %d (angle_max is the angle of the last ray, expected %.6f)'
            % (count, scan.angle_min, scan.angle_max, scan.angle_increment, described, expected_max))
    if scan.range_min < 0.0:
        raise ScanError('range_min: expected at least 0 m, got %r' % scan.range_min)
    if not scan.range_max > scan.range_min:
        raise ScanError('range_max: expected more than range_min (%r m), got %r'
                        % (scan.range_min, scan.range_max))


def sample_angles(scan):
    """The angle of every ray, ``angle_min + i * angle_increment`` (rad, not wrapped)."""
    validate_scan(scan)
    return _angles(scan.angle_min, scan.angle_increment, len(scan.ranges))


def _angles(angle_min, angle_increment, count):
    return angle_min + numpy.arange(count) * angle_increment


def usable_ranges(scan):
    """``ranges`` with REP 117 applied, in m, one entry per ray.

    ``-inf`` becomes ``range_min`` (an obstacle too close to measure is at least that close);
    ``+inf`` stays ``+inf`` (clear); ``NaN`` and finite values outside ``[range_min, range_max]``
    (limits included) become ``NaN`` (invalid, to be ignored, never treated as clear).
    """
    validate_scan(scan)
    return _usable(scan.ranges, scan.range_min, scan.range_max)


def _usable(ranges, range_min, range_max):
    """:func:`usable_ranges` of some of a scan's ``ranges`` (comparisons with NaN are False, silently)."""
    usable = numpy.array(ranges, dtype=float)
    usable[~((ranges >= range_min) & (ranges <= range_max))] = numpy.nan
    usable[ranges == numpy.inf] = numpy.inf
    usable[ranges == -numpy.inf] = range_min
    return usable


@dataclasses.dataclass(frozen=True)
class SectorReading:
    """The nearest obstacle within a group of rays.

    ``distance_m`` is the smallest usable range (m); ``+inf`` when every valid reading is clear;
    ``NaN`` when no reading is valid (nothing can be said about the sector). ``valid`` counts the
    rays that are not NaN after :func:`usable_ranges`; ``total`` counts the rays in the sector.
    """
    distance_m: float
    valid: int
    total: int

    @property
    def trusted(self):
        """True when at least one ray in the sector gave a valid reading."""
        return self.total > 0 and self.valid > 0


def _reading(ranges):
    valid = ranges[~numpy.isnan(ranges)]
    distance = float(valid.min()) if len(valid) else math.nan
    return SectorReading(distance_m=distance, valid=int(len(valid)), total=int(len(ranges)))


def _check_angle(name, value, minimum=None):
    if not _is_finite_number(value):
        raise ScanError('%s: expected a finite angle (rad), got %r' % (name, value))
    if minimum is not None and value < minimum:
        raise ScanError('%s: expected at least %g rad, got %r' % (name, minimum, value))


def sector_min(scan, center_rad, half_width_rad):
    """The nearest obstacle among rays within ``half_width_rad`` of ``center_rad`` (both rad).

    A ray belongs to the sector when its angle relative to ``center_rad``, wrapped into
    ``(-pi, pi]``, lies within ``+-half_width_rad`` (edges included). This works for any
    ``angle_min``, negative increments and scans that run past ``+-pi``. A ``half_width_rad`` of
    ``pi`` or more takes the whole scan. A sector that contains no ray gives an untrusted reading
    (``total == 0``). Raises :class:`ScanError` for a malformed scan or a non-finite or negative
    angle argument.
    """
    _check_angle('center_rad', center_rad)
    _check_angle('half_width_rad', half_width_rad, minimum=0.0)
    validate_scan(scan)
    inside = _sector(float(scan.angle_min), float(scan.angle_increment), len(scan.ranges), float(center_rad),
                     float(half_width_rad))
    return _reading(_usable(scan.ranges[inside], scan.range_min, scan.range_max))


@functools.lru_cache(maxsize=64)
def _sector(angle_min, angle_increment, count, center_rad, half_width_rad):
    """The indices of the rays in a sector (see :func:`sector_min`); a scan's layout and a controller's sector
    rarely change, so each is worked out once."""
    relative = _angles(angle_min, angle_increment, count) - center_rad
    wrapped = math.pi - numpy.mod(math.pi - relative, 2.0 * math.pi)
    tolerance = EDGE_TOLERANCE_INCREMENTS * abs(angle_increment)
    inside = numpy.flatnonzero(numpy.abs(wrapped) <= half_width_rad + tolerance)
    inside.setflags(write=False)
    return inside


def nearest(scan):
    """The nearest obstacle over the whole scan (see :class:`SectorReading`)."""
    return _reading(usable_ranges(scan))


@dataclasses.dataclass
class DetectorSettings:
    """obstacle_detector's ``~parameters``."""
    front_half_angle: float = param(math.pi / 2.0, 'rad',
                                    'half-width of the front sector, centred on 0 (forward)',
                                    minimum=0.0, maximum=math.pi, exclusive_minimum=True, live=True)
    side_half_angle: float = param(math.pi / 4.0, 'rad',
                                   'half-width of the left (+pi/2) and right (-pi/2) sectors',
                                   minimum=0.0, maximum=math.pi, exclusive_minimum=True, live=True)
    warn_distance: float = param(0.5, 'm', 'warn when the nearest obstacle is closer than this',
                                 minimum=0.0, exclusive_minimum=True, live=True)


def sector_readings(scan, settings, forward_rad=0.0):
    """The front, left and right :class:`SectorReading` of ``scan``, keyed by sector name.

    ``forward_rad``: the robot's forward direction in the scan's frame (0 for a laser mounted facing
    forward; minus the laser's yaw on the robot otherwise); the sectors turn with it.
    """
    half_widths = {'front': settings.front_half_angle, 'left': settings.side_half_angle,
                   'right': settings.side_half_angle}
    return {name: sector_min(scan, forward_rad + centre, half_widths[name])
            for name, centre in SECTOR_CENTRES_RAD.items()}


def describe_reading(reading):
    # type: (Optional[SectorReading]) -> str
    """A short human description of a reading for log lines."""
    if reading is None:
        return 'no reading'
    if not reading.trusted:
        return 'no valid reading (%d of %d rays invalid)' % (reading.total - reading.valid,
                                                            reading.total)
    return '%.2f m' % reading.distance_m


def scan_points(scan, laser_pose):
    """The scan's returns as an (N, 2) array of points in base_footprint (m).

    ``laser_pose``: the laser frame's :class:`closed_loop.geometry.Pose2D`. REP 117: ``-inf``
    (closer than range_min) is a point at range_min; ``+inf`` and invalid rays give no point.
    """
    ranges = usable_ranges(scan)
    angles = sample_angles(scan) + laser_pose.yaw
    keep = numpy.isfinite(ranges)
    r, a = ranges[keep], angles[keep]
    return numpy.column_stack((laser_pose.x + r * numpy.cos(a), laser_pose.y + r * numpy.sin(a)))
