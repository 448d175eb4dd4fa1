"""The way through the scan's points: where no chain of passable cells joins the goal to the robot, the
answer (no way) comes without the wave, and is the wave's own answer."""
import numpy
import pytest

from closed_loop.control import wavefront


def clutter(rng, posts):
    """Posts as rings of points round random centres, some of them on a wall across the way."""
    centres = rng.uniform((-1.0, -4.0), (7.0, 4.0), (posts, 2))
    around = numpy.linspace(0.0, 2 * numpy.pi, 12, endpoint=False)
    ring = 0.1 * numpy.column_stack((numpy.cos(around), numpy.sin(around)))
    wall_y = rng.uniform(-4.0, 4.0, int(rng.integers(0, 40)))
    wall = numpy.column_stack((numpy.full(len(wall_y), 3.0), wall_y))
    return numpy.concatenate([(centres[:, None, :] + ring[None]).reshape(-1, 2), wall])


def test_no_chain_of_passable_cells_gives_no_way_as_the_wave_does(monkeypatch):
    rng = numpy.random.default_rng(11)
    cases = [(clutter(rng, int(rng.integers(5, 60))), (float(rng.uniform(4.0, 8.0)), float(rng.uniform(-2.0, 2.0))))
             for _ in range(300)]
    shortcut = [wavefront.way(points, goal, 0.35, 1.0) for points, goal in cases]
    # The same cases with every cell in one component: the wave alone decides.
    connected = wavefront.cv2.connectedComponents
    monkeypatch.setattr(wavefront.cv2, 'connectedComponents',
                        lambda image, **kw: (2, numpy.ones(image.shape, numpy.uint16)))
    waved = [wavefront.way(points, goal, 0.35, 1.0) for points, goal in cases]
    monkeypatch.setattr(wavefront.cv2, 'connectedComponents', connected)
    none = sum(w is None for w in waved)
    assert 30 <= none <= 270, 'the cases should mix ways and none: %d of 300 have none' % none
    for a, b in zip(shortcut, waved):
        assert (a is None) == (b is None)
        if a is not None:
            assert a.aim == b.aim and a.goal == b.goal
            assert numpy.array_equal(a.route(), b.route())


@pytest.mark.parametrize('gap', [0.5, 1.2])
def test_a_wall_with_one_gap_is_passed_only_where_the_gap_is_wide_enough(gap):
    ys = numpy.arange(-5.0, 5.0, 0.05)
    wall = numpy.column_stack((numpy.full(len(ys), 2.0), ys))
    wall = wall[numpy.abs(wall[:, 1] - 1.0) > gap / 2]
    found = wavefront.way(wall, (4.0, 0.0), 0.35, 1.0)
    assert (found is not None) == (gap > 0.7 + 0.1)


def wall_with_gaps(*gaps):
    """A wall across the way 2 m ahead, open 1 m wide round each of ``gaps`` (y, m)."""
    ys = numpy.arange(-5.0, 5.0, 0.05)
    keep = numpy.ones(len(ys), bool)
    for y in gaps:
        keep &= numpy.abs(ys - y) > 0.5
    return numpy.column_stack((numpy.full(keep.sum(), 2.0), ys[keep]))


def test_the_way_followed_is_kept_while_it_is_open_and_not_much_longer():
    goal = (4.0, 0.0)
    # Only the right gap open: the way goes through it; that is the way followed.
    followed = wavefront.way(wall_with_gaps(-1.2), goal, 0.35, 1.0).route()
    assert followed[:, 1].min() < -0.8
    # The left gap opens too, a little nearer: the way followed is kept, not swapped for the new shortest.
    wall = wall_with_gaps(1.0, -1.2)
    assert wavefront.way(wall, goal, 0.35, 1.0).aim[1] > 0.3
    kept = wavefront.way(wall, goal, 0.35, 1.0, kept=followed)
    assert kept.aim[1] < -0.3 and kept.goal == goal and numpy.allclose(kept.route()[-1], goal)
    # The right gap closes: the way goes left.
    closed = numpy.concatenate((wall, [(2.0, y) for y in numpy.arange(-1.7, -0.7, 0.05)]))
    assert wavefront.way(closed, goal, 0.35, 1.0, kept=followed).aim[1] > 0.3
    # A way followed far longer than the new shortest is dropped.
    detour = wavefront.way(wall_with_gaps(-2.8), goal, 0.35, 1.0).route()
    assert wavefront.way(wall_with_gaps(1.0, -2.8), goal, 0.35, 1.0, kept=detour).aim[1] > 0.3
