"""What the navigator remembers of its scans: one point a cell (the newest), forgotten when a newer ray passes
through it or when it is older than the memory's time."""
import math

import numpy

from closed_loop.control.scan import scan_points
from closed_loop.control.scan import Scan
from closed_loop.control.navigation.memory import CELL_M, ScanMemory
from closed_loop.geometry import Pose2D

LASER = Pose2D(0.0, 0.0, 0.0)
RAYS = 360


def scan_of(ranges, stamp_s=0.0):
    increment = 2 * math.pi / RAYS
    return Scan(stamp_s, 'laser', -math.pi, -math.pi + (RAYS - 1) * increment, increment, 0.0, 0.1, 0.1, 10.0,
                ranges)


def wall_ahead(distance, stamp_s=0.0):
    """A scan that sees only a short wall straight ahead (rays within 10 degrees of it), nothing elsewhere."""
    angles = -math.pi + 2 * math.pi / RAYS * numpy.arange(RAYS)
    ranges = numpy.full(RAYS, numpy.inf)
    ahead = numpy.abs(angles) < math.radians(10)
    ranges[ahead] = distance / numpy.cos(angles[ahead])
    return scan_of(ranges, stamp_s)


def remember(memory, now_s, pose, scan):
    memory.add(now_s, pose, scan_points(scan, LASER), scan, LASER)


def test_one_point_a_cell_and_the_newest_one():
    memory = ScanMemory(60.0)
    remember(memory, 0.0, (0.0, 0.0, 0.0), wall_ahead(2.0))
    cells = numpy.floor(memory.xy / CELL_M).astype(int)
    assert len(memory.xy) > 3 and len({tuple(c) for c in cells}) == len(cells)
    # The same wall seen again: each cell keeps the newer sighting, and no cell holds two.
    before = len(memory.xy)
    remember(memory, 1.0, (0.0, 0.0, 0.0), wall_ahead(2.0, 1.0))
    assert len(memory.xy) == before and (memory.t == 1.0).all()


def test_a_point_a_newer_ray_passes_through_is_forgotten_and_one_behind_what_it_sees_is_kept():
    memory = ScanMemory(60.0)
    remember(memory, 0.0, (0.0, 0.0, 0.0), wall_ahead(2.0))
    seen = len(memory.xy)
    # Turned round: the wall is behind, where this scan's rays see nothing at all (they pass through it).
    clear_everywhere = scan_of(numpy.full(RAYS, numpy.inf), 1.0)
    remember(memory, 1.0, (0.0, 0.0, 0.0), clear_everywhere)
    assert len(memory.xy) == 0
    # Something nearer in front hides the remembered wall: it is kept, beside the nearer points.
    memory = ScanMemory(60.0)
    remember(memory, 0.0, (0.0, 0.0, 0.0), wall_ahead(2.0))
    remember(memory, 1.0, (0.0, 0.0, 0.0), wall_ahead(1.0, 1.0))
    assert (memory.t == 0.0).sum() == seen and (memory.t == 1.0).sum() > 3


def test_points_older_than_the_memory_are_forgotten():
    memory = ScanMemory(5.0)
    remember(memory, 0.0, (0.0, 0.0, 0.0), wall_ahead(2.0))
    remember(memory, 4.0, (0.0, 0.0, 0.0), scan_of(numpy.full(RAYS, -numpy.inf), 4.0))   # all too close
    assert (memory.t == 0.0).any()
    remember(memory, 6.0, (0.0, 0.0, 0.0), scan_of(numpy.full(RAYS, numpy.nan), 6.0))    # no reading at all
    assert not (memory.t == 0.0).any()


def test_a_point_where_the_robot_stands_is_forgotten():
    # Seen 2 m ahead, then the robot (by odometry) stands on it: odometry misplaced it, since the robot is
    # there. A point beside the footprint stays.
    from closed_loop.robot_model import Footprint
    footprint = Footprint(-0.25, 0.25, -0.2, 0.2)
    memory = ScanMemory(60.0)
    remember(memory, 0.0, (0.0, 0.0, 0.0), wall_ahead(2.0))
    blind = scan_of(numpy.full(RAYS, numpy.nan), 1.0)            # no reading: nothing seen, nothing seen through
    memory.add(1.0, (1.9, 0.0, 0.0), scan_points(blind, LASER), blind, LASER, footprint)
    assert len(memory.xy) and (numpy.abs(memory.xy[:, 1]) > 0.2).all()
    memory.add(2.0, (1.9, 0.0, 0.0), scan_points(blind, LASER), blind, LASER)   # no footprint given: kept
    assert (numpy.abs(memory.xy[:, 1]) > 0.2).all()
