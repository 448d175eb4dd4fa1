"""The way through the scan's points: the compiled wave, gaps, the way kept, corridors."""
import math

import cv2
import numpy
import pytest

from closed_loop.control.navigation import wave_kernel, wavefront


def image_wave(passable, start, goal):
    """The wave as images (OpenCV's dilation by a 3x3 square in odd rounds, a cross in even ones, within the
    passable cells not yet reached): what the compiled wave must give, cell for cell."""
    steps = numpy.full(passable.shape, wave_kernel.UNREACHED, numpy.int32)
    steps[goal] = 0
    front = numpy.zeros(passable.shape, numpy.uint8)
    front[goal] = 1
    cross = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
    k = 0
    while steps[start] == wave_kernel.UNREACHED:
        k += 1
        front = cv2.dilate(front, numpy.ones((3, 3), numpy.uint8) if k % 2 else cross)
        front &= (passable & (steps == wave_kernel.UNREACHED)).astype(numpy.uint8)
        if not front.any():
            return -1, steps
        steps[front > 0] = k
    return k, steps


def test_the_compiled_wave_reaches_each_cell_in_the_round_the_images_do():
    rng = numpy.random.default_rng(11)
    reached = unreached = 0
    for _ in range(300):
        passable = rng.random((int(rng.integers(5, 60)), int(rng.integers(5, 60)))) < rng.uniform(0.45, 0.9)
        start = tuple(int(rng.integers(0, n)) for n in passable.shape)
        goal = tuple(int(rng.integers(0, n)) for n in passable.shape)
        passable[start] = passable[goal] = True
        k, steps = wave_kernel.wave(passable, start, goal, 254)
        want_k, want = image_wave(passable, start, goal)
        assert k == want_k
        if k >= 0:
            assert numpy.array_equal(steps, want)
            reached += 1
        else:
            unreached += 1
    assert reached >= 30 and unreached >= 30, (reached, unreached)


def test_a_wave_longer_than_its_rounds_finds_no_way():
    passable = numpy.ones((3, 40), bool)
    assert wave_kernel.wave(passable, (1, 0), (1, 39), 40)[0] == 39
    assert wave_kernel.wave(passable, (1, 0), (1, 39), 39)[0] == -1


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
    shortest = wavefront.way(wall, goal, 0.35, 1.0)
    assert shortest.aim[1] > 0.2 and shortest.route()[:, 1].max() > 0.5
    kept = wavefront.way(wall, goal, 0.35, 1.0, kept=followed)
    assert kept.aim[1] < -0.3 and kept.goal == goal and numpy.allclose(kept.route()[-1], goal)
    # The right gap closes: the way goes left.
    closed = numpy.concatenate((wall, [(2.0, y) for y in numpy.arange(-1.7, -0.7, 0.05)]))
    assert wavefront.way(closed, goal, 0.35, 1.0, kept=followed).aim[1] > 0.2
    # A way followed far longer than the new shortest is dropped.
    detour = wavefront.way(wall_with_gaps(-2.8), goal, 0.35, 1.0).route()
    assert wavefront.way(wall_with_gaps(1.0, -2.8), goal, 0.35, 1.0, kept=detour).aim[1] > 0.2


def test_a_cell_is_in_sight_only_where_every_cell_on_the_line_to_it_is_passable():
    passable = numpy.ones((7, 7), bool)
    passable[3, 3] = False
    assert not wave_kernel.in_sight(passable, (0, 0), (6, 6))          # the diagonal crosses (3, 3)
    assert not wave_kernel.in_sight(passable, (3, 0), (3, 6))
    assert wave_kernel.in_sight(passable, (2, 0), (2, 6)) and wave_kernel.in_sight(passable, (0, 6), (6, 6))
    assert wave_kernel.in_sight(passable, (1, 1), (1, 1))
    # A shallow line: sampled at twice the cells it crosses, each sample rounded to its cell.
    passable[:] = True
    passable[1, 4] = False
    assert not wave_kernel.in_sight(passable, (0, 0), (2, 6)) and wave_kernel.in_sight(passable, (0, 0), (0, 6))


def test_the_way_down_the_wave_stops_at_the_limit_and_where_sight_ends():
    passable = numpy.ones((5, 12), bool)
    k, steps = wave_kernel.wave(passable, (2, 0), (2, 11), 254)
    whole = wave_kernel.descend(steps, (2, 0), (2, 11), 0.2, math.inf, numpy.zeros((0, 0), bool))
    assert [tuple(c) for c in whole] == [(2, j) for j in range(12)]      # on the goal's line, to the goal
    assert len(wave_kernel.descend(steps, (2, 0), (2, 11), 0.2, 0.5, passable)) == 4   # 0.6 m >= 0.5 m
    passable[2, 5] = False                                                # out of sight beyond column 4
    assert [tuple(c) for c in wave_kernel.descend(steps, (2, 0), (2, 11), 0.2, math.inf, passable)][-1] == (2, 4)
