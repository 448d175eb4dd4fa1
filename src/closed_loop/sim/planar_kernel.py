"""The planar ray caster's compiled loop (``closed_loop.sim.planar_rays``): every obstacle within range against
the rays of its angular window, each pair by its shape's ray test (:func:`_hit`, a branch per
``shapes.SHAPES[shape].RAY_KIND``), the nearest hit of each ray kept.

Compiled by numba (``closed_loop.compiled``): every way of matching rays to obstacles gives the same distances
to the bit. Free of ROS.
"""
import math

import numpy

from closed_loop.compiled import jit

#: A ray this close (rad) to the edge of an obstacle's angular window is still tested against it.
WINDOW_MARGIN_RAD = 1e-9
TWO_PI = 2.0 * math.pi
#: How the rays are matched to obstacles: every ray with every obstacle, a fan's windows by arithmetic, or
#: windows searched in the sorted bearings.
EVERY, FAN, SORTED = 0, 1, 2


@jit
def _hit(kind, params, m, rel_x, rel_y, fx, fy):
    """Distance along the ray (unit direction ``fx``, ``fy``) from the origin to obstacle ``m`` (its centre at
    ``rel_x``, ``rel_y`` from the origin; its shape's ``kind`` and ``params`` row), inf where it misses (or
    starts inside)."""
    if kind == 0:                               # a box: the slab test in its frame
        c, s, hx, hy = params[m, 0], params[m, 1], params[m, 2], params[m, 3]
        ox, oy = c * -rel_x + s * -rel_y, -s * -rel_x + c * -rel_y
        dx, dy = fx * c + fy * s, -fx * s + fy * c
        inv_x, inv_y = 1.0 / dx, 1.0 / dy
        ax, bx = (-hx - ox) * inv_x, (hx - ox) * inv_x
        ay, by = (-hy - oy) * inv_y, (hy - oy) * inv_y
        near = max(min(ax, bx), min(ay, by))
        far = min(max(ax, bx), max(ay, by))
        return near if near <= far and near >= 0.0 else numpy.inf
    radius = params[m, 0]                       # a cylinder: the nearer root along the ray
    b = fx * rel_x + fy * rel_y
    disc = b * b - (rel_x * rel_x + rel_y * rel_y - radius * radius)
    if disc < 0.0:
        return numpy.inf
    t = b - math.sqrt(disc)
    return t if t >= 0.0 else numpy.inf


@jit
def _take(kind, params, m, rel_x, rel_y, z, az, half_height, fx, fy, level, rise, drift, check_height, r, best):
    """Ray ``r`` tested against obstacle ``m``: its hit kept in ``best`` where nearer and within the height."""
    along = _hit(kind, params, m, rel_x, rel_y, fx[r], fy[r])
    if along == numpy.inf:
        return
    if drift != 0.0:
        along = along / level[r]
        if check_height and abs(z + along * rise[r] - az) > half_height:
            return
    if along < best[r]:
        best[r] = along


@jit
def cast(kinds, params, ax, ay, az, half_heights, radii, x, y, z, fx, fy, level, rise, drift, range_max,
          check_height, mode, first, increment, bearings, order, best):
    """Every obstacle in range against the rays of its window (``mode``), the nearest hit kept in ``best``."""
    count = len(fx)
    full_turn = abs(count * increment - TWO_PI) < 1e-9
    stray = drift / range_max
    for m in range(len(ax)):
        rel_x, rel_y = ax[m] - x, ay[m] - y
        distance = math.hypot(rel_x, rel_y)
        if distance - radii[m] > range_max:
            continue
        if check_height and abs(az[m] - z) > half_heights[m] + drift:
            continue
        kind, zm, hh = kinds[m], az[m], half_heights[m]
        if mode == EVERY:
            for r in range(count):
                _take(kind, params, m, rel_x, rel_y, z, zm, hh, fx, fy, level, rise, drift, check_height, r, best)
            continue
        # Half the angle the bounding circle covers, seen from the origin; a full turn from inside it.
        half = (math.pi if distance <= radii[m] else math.asin(radii[m] / distance)) + WINDOW_MARGIN_RAD
        centre = math.atan2(rel_y, rel_x)
        if mode == FAN and full_turn:
            half += stray
            start = math.ceil((centre - first - half) / increment)
            span = min(math.floor((centre - first + half) / increment) - start + 1.0, count)
            for q in range(int(span)):
                r = int(start + q) % count
                _take(kind, params, m, rel_x, rel_y, z, zm, hh, fx, fy, level, rise, drift, check_height, r, best)
            continue
        if mode == FAN:
            half += stray
            centre = (centre - first) % TWO_PI                  # [0, 2 pi) from the first ray
        for turn in (-TWO_PI, 0.0, TWO_PI):                      # the window, and a turn before and after
            low, high = centre + turn - half, centre + turn + half
            if mode == FAN:
                lo, hi = max(math.ceil(low / increment), 0.0), min(math.floor(high / increment), count - 1.0)
                for r in range(int(lo), int(hi) + 1):
                    _take(kind, params, m, rel_x, rel_y, z, zm, hh, fx, fy, level, rise, drift, check_height, r,
                          best)
            else:
                for p in range(numpy.searchsorted(bearings, low, side='left'),
                               numpy.searchsorted(bearings, high, side='right')):
                    _take(kind, params, m, rel_x, rel_y, z, zm, hh, fx, fy, level, rise, drift, check_height,
                          order[p], best)


@jit
def footprint_boxes(kinds, params, ax, ay, radii):
    """Each obstacle's footprint's bounding box, (M, 4): least x and y, greatest x and y."""
    boxes = numpy.empty((len(ax), 4))
    for m in range(len(ax)):
        if kinds[m] == 0:                       # a box: its turned half-sizes
            c, s, hx, hy = abs(params[m, 0]), abs(params[m, 1]), params[m, 2], params[m, 3]
            ex, ey = c * hx + s * hy, s * hx + c * hy
        else:
            ex = ey = radii[m]
        boxes[m, 0], boxes[m, 1], boxes[m, 2], boxes[m, 3] = ax[m] - ex, ay[m] - ey, ax[m] + ex, ay[m] + ey
    return boxes


@jit
def grid_cells(boxes, x0, y0, cell, nx, ny, margin):
    """The uniform grid of standing obstacles: ``(starts, items)``, cell ``i``'s obstacles being
    ``items[starts[i]:starts[i + 1]]``, every obstacle in each cell its footprint's bounding box ``boxes[m]``
    (grown by ``margin``) touches; cells numbered ``ix + nx * iy`` from the corner (``x0``, ``y0``), ``cell`` m
    square."""
    count = len(boxes)
    cells = numpy.empty((count, 4), dtype=numpy.int64)
    starts = numpy.zeros(nx * ny + 1, dtype=numpy.int64)
    for m in range(count):
        cells[m, 0] = min(max(int(math.floor((boxes[m, 0] - margin - x0) / cell)), 0), nx - 1)
        cells[m, 1] = min(max(int(math.floor((boxes[m, 1] - margin - y0) / cell)), 0), ny - 1)
        cells[m, 2] = min(max(int(math.floor((boxes[m, 2] + margin - x0) / cell)), 0), nx - 1)
        cells[m, 3] = min(max(int(math.floor((boxes[m, 3] + margin - y0) / cell)), 0), ny - 1)
        for iy in range(cells[m, 1], cells[m, 3] + 1):
            for ix in range(cells[m, 0], cells[m, 2] + 1):
                starts[ix + nx * iy + 1] += 1
    for i in range(nx * ny):
        starts[i + 1] += starts[i]
    items = numpy.empty(starts[nx * ny], dtype=numpy.int64)
    filled = starts[:-1].copy()
    for m in range(count):
        for iy in range(cells[m, 1], cells[m, 3] + 1):
            for ix in range(cells[m, 0], cells[m, 2] + 1):
                items[filled[ix + nx * iy]] = m
                filled[ix + nx * iy] += 1
    return starts, items


@jit
def grid_cast(kinds, params, ax, ay, az, half_heights, x, y, z, fx, fy, level, rise, drift, range_max, check_height,
              x0, y0, cell, nx, ny, starts, items, seen, best):
    """Each ray walked through the grid's cells from the origin (Amanatides and Woo's traversal), tested against
    the obstacles of each cell it crosses, until its nearest hit so far lies before the cell's far side or it
    leaves the range or the grid: the same nearest hits as :func:`cast`, at a cost that follows what each ray
    crosses rather than what the range holds. ``seen``: for each obstacle, the last ray tested against it (its
    number plus the stamp ``seen[-1]``, raised by the rays' count on return), so that one listed in several cells
    is tested once per ray."""
    stamp = seen[-1]
    x1, y1 = x0 + nx * cell, y0 + ny * cell
    for r in range(len(fx)):
        dx, dy = fx[r], fy[r]
        reach = range_max * level[r] if drift != 0.0 else range_max        # the range, in the plane
        inv_x, inv_y = 1.0 / dx, 1.0 / dy
        # Where the ray is within the grid's square (the slab test), from its origin on.
        ax_, bx_ = (x0 - x) * inv_x, (x1 - x) * inv_x
        ay_, by_ = (y0 - y) * inv_y, (y1 - y) * inv_y
        enter = max(max(min(ax_, bx_), min(ay_, by_)), 0.0)
        leave = min(min(max(ax_, bx_), max(ay_, by_)), reach)
        if not enter <= leave:
            continue
        px, py = x + enter * dx, y + enter * dy
        ix = min(max(int(math.floor((px - x0) / cell)), 0), nx - 1)
        iy = min(max(int(math.floor((py - y0) / cell)), 0), ny - 1)
        step_x, step_y = (1 if dx > 0.0 else -1), (1 if dy > 0.0 else -1)
        next_x = (x0 + (ix + (1 if dx > 0.0 else 0)) * cell - x) * inv_x if dx != 0.0 else numpy.inf
        next_y = (y0 + (iy + (1 if dy > 0.0 else 0)) * cell - y) * inv_y if dy != 0.0 else numpy.inf
        delta_x, delta_y = abs(cell * inv_x), abs(cell * inv_y)
        while True:
            k = ix + nx * iy
            for p in range(starts[k], starts[k + 1]):
                m = items[p]
                if seen[m] == stamp + r:
                    continue
                seen[m] = stamp + r
                if check_height and abs(az[m] - z) > half_heights[m] + drift:
                    continue
                _take(kinds[m], params, m, ax[m] - x, ay[m] - y, z, az[m], half_heights[m], fx, fy, level, rise,
                      drift, check_height, r, best)
            far = min(next_x, next_y)
            nearest = best[r] * level[r] if drift != 0.0 else best[r]
            if nearest <= far or far >= leave:
                break
            if next_x < next_y:
                ix += step_x
                next_x += delta_x
                if ix < 0 or ix >= nx:
                    break
            else:
                iy += step_y
                next_y += delta_y
                if iy < 0 or iy >= ny:
                    break
    seen[-1] = stamp + len(fx)
