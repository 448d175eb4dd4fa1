"""The planner's clearance of the footprint along many poses, read from a distance field: never above the
exact clearance, and close to it."""
import numpy

from closed_loop.control.navigation.clearance_field import (CHAMFER_ERROR, FIELD_ERROR_M, GRID_CELL_M, DistanceField,
                                                 clearances, outline32)
from closed_loop.control.safety import footprint_clearances
from closed_loop.robot_model import Footprint

JACKAL = Footprint(-0.254, 0.254, -0.2155, 0.2155)


def test_the_field_never_overstates_and_stays_close_to_the_exact_clearance():
    rng = numpy.random.default_rng(7)
    points = rng.uniform(-3.0, 3.0, (300, 2))
    field = DistanceField(points, 3.0)
    step_m = 0.1
    shape = outline32(JACKAL, step_m)
    poses = numpy.stack((rng.uniform(-1.5, 1.5, (40, 9)), rng.uniform(-1.5, 1.5, (40, 9)),
                         rng.uniform(-3.2, 3.2, (40, 9))), axis=2).astype(numpy.float32)
    got = clearances(field, shape, poses, step_m)
    assert got.shape == (40, 9)
    exact = footprint_clearances(points, JACKAL, poses.reshape(-1, 3).astype(float)).reshape(40, 9)
    outside = exact > 0
    assert (got[outside] <= exact[outside] + 1e-6).all()
    # Low by at most the grid's allowances (a cell's diagonal and half the outline's sample gap) and the
    # chamfer's fraction, plus a cell for rounding points onto the grid.
    allowance = FIELD_ERROR_M + CHAMFER_ERROR * exact[outside] + GRID_CELL_M * 1.5
    assert (exact[outside] - got[outside] <= allowance).all()
    # Each pose on its own gives the same as in the batch.
    for c, k in [(0, 0), (13, 4), (39, 8)]:
        assert clearances(field, shape, poses[c:c + 1, k:k + 1], step_m)[0, 0] == got[c, k]


def test_no_points_no_limit():
    field = DistanceField(numpy.zeros((0, 2)), 2.0)
    poses = numpy.zeros((3, 4, 3), numpy.float32)
    assert numpy.isinf(clearances(field, outline32(JACKAL, 0.1), poses, 0.1)).all()
