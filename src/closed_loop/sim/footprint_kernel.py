"""The footprint rasteriser's compiled loop (``closed_loop.sim.mesh_footprint``): which cells of a grid the
triangles, seen from above, touch. Compiled by numba (``closed_loop.compiled``); free of ROS."""
import math

import numpy

from closed_loop.compiled import jit


@jit
def touch(corners, x0, y0, cell, solid):
    """Mark in ``solid`` ((ny, nx) uint8, cell (iy, ix) being the square from (``x0`` + ix ``cell``, ``y0`` + iy
    ``cell``)) every cell that a triangle of ``corners`` ((n, 3, 2): x, y) touches, edges and corners included:
    the triangle and the square have no separating axis (x, y, or an edge's normal). A triangle seen edge-on is
    the segment it covers."""
    ny, nx = solid.shape
    half = 0.5 * cell
    for t in range(corners.shape[0]):
        xs = (corners[t, 0, 0], corners[t, 1, 0], corners[t, 2, 0])
        ys = (corners[t, 0, 1], corners[t, 1, 1], corners[t, 2, 1])
        low_x = max(int(math.floor((min(xs) - x0) / cell)), 0)
        high_x = min(int(math.floor((max(xs) - x0) / cell)), nx - 1)
        low_y = max(int(math.floor((min(ys) - y0) / cell)), 0)
        high_y = min(int(math.floor((max(ys) - y0) / cell)), ny - 1)
        for iy in range(low_y, high_y + 1):
            mid_y = y0 + (iy + 0.5) * cell
            for ix in range(low_x, high_x + 1):
                if solid[iy, ix]:
                    continue
                mid_x = x0 + (ix + 0.5) * cell
                apart = False
                for k in range(3):
                    # The normal of edge k; the triangle's span along it against the square's.
                    n_x, n_y = ys[k] - ys[(k + 1) % 3], xs[(k + 1) % 3] - xs[k]
                    p0 = n_x * xs[0] + n_y * ys[0]
                    p1 = n_x * xs[1] + n_y * ys[1]
                    p2 = n_x * xs[2] + n_y * ys[2]
                    centre, reach = n_x * mid_x + n_y * mid_y, (abs(n_x) + abs(n_y)) * half
                    if centre + reach < min(p0, p1, p2) or centre - reach > max(p0, p1, p2):
                        apart = True
                        break
                if not apart:
                    solid[iy, ix] = 1


@jit
def fill_inside(segments, weights, x0, y0, cell, solid):
    """Mark in ``solid`` every cell whose centre is inside the cross-section whose edges are ``segments`` ((m, 2,
    2): the two ends' x, y), by the winding rule along each row of cell centres: crossing segment k adds
    ``weights[k]`` (+1 where the solid begins along +x, -1 where it ends), and a centre is inside where the sum
    so far is above 0. A row whose crossings do not sum to 0 (the section does not close there) is left as it
    is."""
    ny, nx = solid.shape
    counts = numpy.zeros(ny + 1, dtype=numpy.int64)
    for k in range(segments.shape[0]):
        low, high = _rows(segments, k, y0, cell, ny)
        for iy in range(low, high + 1):
            counts[iy + 1] += 1
    for iy in range(ny):
        counts[iy + 1] += counts[iy]
    xs = numpy.empty(counts[ny])
    ws = numpy.empty(counts[ny], dtype=numpy.int64)
    filled = counts[:-1].copy()
    for k in range(segments.shape[0]):
        low, high = _rows(segments, k, y0, cell, ny)
        ax, ay, bx, by = segments[k, 0, 0], segments[k, 0, 1], segments[k, 1, 0], segments[k, 1, 1]
        for iy in range(low, high + 1):
            centre = y0 + (iy + 0.5) * cell
            xs[filled[iy]] = ax + (centre - ay) * (bx - ax) / (by - ay)
            ws[filled[iy]] = weights[k]
            filled[iy] += 1
    for iy in range(ny):
        row_x, row_w = xs[counts[iy]:counts[iy + 1]], ws[counts[iy]:counts[iy + 1]]
        if row_w.sum() != 0:
            continue
        order = numpy.argsort(row_x)
        winding = 0
        for q in range(len(order) - 1):
            winding += row_w[order[q]]
            if winding > 0:
                first = max(int(math.ceil((row_x[order[q]] - x0) / cell - 0.5)), 0)
                last = min(int(math.ceil((row_x[order[q + 1]] - x0) / cell - 0.5)) - 1, nx - 1)
                for ix in range(first, last + 1):
                    solid[iy, ix] = 1


@jit
def _rows(segments, k, y0, cell, ny):
    """The rows whose centre line segment ``k`` crosses, the half-open way (its lower end in, its upper end out):
    (first, last), empty where last < first."""
    low_y, high_y = min(segments[k, 0, 1], segments[k, 1, 1]), max(segments[k, 0, 1], segments[k, 1, 1])
    first = max(int(math.ceil((low_y - y0) / cell - 0.5)), 0)
    last = min(int(math.ceil((high_y - y0) / cell - 0.5)) - 1, ny - 1)
    return first, last
