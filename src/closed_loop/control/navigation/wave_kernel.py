"""The way's wave, compiled (numba), for ``closed_loop.control.navigation.wavefront``: a breadth-first wave from the goal's
cell over passable cells, alternating 8- and 4-neighbour steps (the octagonal distance), stopped once it has
reached the start's cell. As OpenCV calls it was four calls a round, about 30 rounds a wave, each call's fixed
cost far above its few hundred cells' work; here it is one call, and the same rounds to the cell.

Compiled by numba (``closed_loop.compiled``). Free of ROS.
"""
import numpy

from closed_loop.compiled import jit

#: A cell the wave has not reached.
UNREACHED = numpy.iinfo(numpy.int32).max


@jit
def wave(passable, start, goal, rounds):
    """(k, steps): ``steps`` (rows, columns) int32, the round each passable cell was reached in (the goal's cell
    in round 0; UNREACHED where it was not), and ``k`` the round the ``start`` cell was reached in; k = -1 when
    the wave stops growing first or would need ``rounds`` rounds or more. Round k steps to the 8 neighbours
    where k is odd and to the 4 where it is even. ``passable``: (rows, columns) bool, the goal's cell among
    them; ``start``, ``goal``: (row, column)."""
    rows, cols = passable.shape
    steps = numpy.full((rows, cols), UNREACHED, numpy.int32)
    front = numpy.empty((rows * cols, 2), numpy.int64)
    grown = numpy.empty((rows * cols, 2), numpy.int64)
    steps[goal[0], goal[1]] = 0
    front[0, 0], front[0, 1] = goal[0], goal[1]
    size = 1
    k = 0
    while steps[start[0], start[1]] == UNREACHED:
        k += 1
        if k >= rounds:
            return -1, steps
        diagonal = k % 2 == 1
        count = 0
        for f in range(size):
            i, j = front[f, 0], front[f, 1]
            for di in range(-1, 2):
                for dj in range(-1, 2):
                    if (di == 0 and dj == 0) or (not diagonal and di != 0 and dj != 0):
                        continue
                    ni, nj = i + di, j + dj
                    if 0 <= ni < rows and 0 <= nj < cols and passable[ni, nj] and steps[ni, nj] == UNREACHED:
                        steps[ni, nj] = k
                        grown[count, 0], grown[count, 1] = ni, nj
                        count += 1
        if count == 0:
            return -1, steps
        front, grown, size = grown, front, count
    return k, steps


@jit
def in_sight(passable, a, b):
    """True if every cell on the straight line from cell ``a`` to cell ``b`` ((row, column)) is passable: the
    line sampled at twice the cells it crosses, each sample rounded to its cell (half to even)."""
    n = max(abs(b[0] - a[0]), abs(b[1] - a[1])) * 2
    if n == 0:
        return True
    for q in range(n + 1):
        t = q / n
        if not passable[int(numpy.rint(a[0] + (b[0] - a[0]) * t)), int(numpy.rint(a[1] + (b[1] - a[1]) * t))]:
            return False
    return True


@jit
def descend(steps, start, goal, cell_m, limit_m, sight):
    """The cells ((N, 2) row, column) down the wave ``steps`` from ``start``: to the ``goal`` cell, or until
    ``limit_m`` of way (cells ``cell_m`` wide) or the first cell not in sight of the start through the cells
    ``sight`` holds true (that cell left out; a sight of no rows: any). Many ways are equally short on a grid;
    of the steps down, the one nearest to the goal in a straight line is taken (the first of the neighbours in
    row then column order, on a tie), so in the open the way is on the goal's line."""
    rows, cols = steps.shape
    cells = numpy.empty((rows * cols + 1, 2), numpy.int64)
    i, j = start[0], start[1]
    cells[0, 0], cells[0, 1] = i, j
    size = 1
    travelled = 0.0
    here = steps[i, j]
    while here > 0 and travelled < limit_m:
        best_i, best_j, best_step, best_gap = -1, -1, 0, 0
        for di in range(-1, 2):
            for dj in range(-1, 2):
                ni, nj = i + di, j + dj
                if (di or dj) and 0 <= ni < rows and 0 <= nj < cols and steps[ni, nj] < here:
                    gap = (goal[0] - ni) ** 2 + (goal[1] - nj) ** 2
                    if best_i < 0 or steps[ni, nj] < best_step or (steps[ni, nj] == best_step and gap < best_gap):
                        best_i, best_j, best_step, best_gap = ni, nj, steps[ni, nj], gap
        if best_i < 0:
            break
        travelled += cell_m * numpy.hypot(best_i - i, best_j - j)
        i, j = best_i, best_j
        if sight.shape[0] and not in_sight(sight, start, (i, j)):
            break
        cells[size, 0], cells[size, 1] = i, j
        size += 1
        here = steps[i, j]
    return cells[:size]
