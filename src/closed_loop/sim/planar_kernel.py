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
