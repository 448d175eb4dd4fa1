"""A planar ray caster for the LIDAR: exact, and several times cheaper than pybullet's in clutter.

The LIDAR's rays are horizontal and every obstacle is a vertical prism (``closed_loop.sim.shapes``), so a
ray's first hit is a 2D question: where the ray, in the scan's plane, first meets the footprint of an
obstacle whose height spans that plane. Each shape casts at its own obstacles
(``shapes.SHAPES[shape].ray_pairs``); obstacles whose bounding circle lies beyond the range are left
out first, and each of the others is tested only against the rays whose bearings its bounding circle can
cover (an angular window seen from the LIDAR), so a scan costs in proportion to what each ray can meet.
For a LIDAR's fan of evenly spaced rays (``fan``) the window is a range of ray indices found by arithmetic;
for any other set of rays, by a search in their sorted bearings. Moving obstacles are cast where they are
now. (Testing the nearest obstacles first and the farther ones only on the rays the nearer left open was
tried: among 315 posts it saved no time, the cost being the number of array operations, not pairs.)

What it does not see, pybullet's caster does: other robots, and the scan plane tilted off the horizontal.
:class:`closed_loop.sim.sensors.lidar.Lidar` uses it only where neither can be (``~ray_caster``). Free of ROS.
"""
import collections
import math

import numpy

from closed_loop.sim import shapes

#: A ray this close (rad) to the edge of an obstacle's angular window is still tested against it.
WINDOW_MARGIN_RAD = 1e-9
TWO_PI = 2.0 * math.pi


class PlanarRays:
    """Casts horizontal rays at the obstacles ``obstacles`` (``world.Obstacle``, vertical prisms)."""

    def __init__(self, obstacles):
        groups = collections.defaultdict(list)
        for index, obstacle in enumerate(obstacles):
            groups[obstacle.shape].append(index)
        #: The obstacles by shape, one after another: the given order of each, the shape's class, where its
        #: obstacles start and end in the order, its parameter rows (ending with the bounding circle's radius).
        self._order = numpy.array([i for indices in groups.values() for i in indices], dtype=numpy.intp)
        self._groups = []
        start = 0
        for shape, indices in groups.items():
            cls = shapes.SHAPES[shape]
            self._groups.append((cls, start, start + len(indices), cls.ray_params([obstacles[i] for i in indices])))
            start += len(indices)
        chosen = [obstacles[i] for i in self._order]
        self._radius = numpy.array([shapes.bounding_radius(o) for o in chosen])
        self._half_height = numpy.array([0.5 * o.size[2] for o in chosen])
        self._at = numpy.array([o.position for o in chosen], float).reshape(-1, 3)
        # Where the obstacles were given, each coordinate apart; and the heights every one of them spans.
        self._x, self._y, self._z = (numpy.ascontiguousarray(self._at[:, i]) for i in range(3))
        self._spans = (float((self._z - self._half_height).max(initial=-numpy.inf)),
                       float((self._z + self._half_height).min(initial=numpy.inf)))
        #: Rows: each obstacle's centre from the origin (x, y), its distance, its circle's radius (filled in by
        #: each cast, the radius once), so the ones near are taken in one call.
        self._seen = numpy.empty((4, len(chosen)))
        self._seen[3] = self._radius

    def cast(self, centres, origin, dirs, range_max, cull=True, fan=None):
        """Distances (N,) from ``origin`` (x, y, z) along ``dirs`` ((N, 3) unit vectors, near the horizontal)
        to the first obstacle or the ground (z = 0) within ``range_max``, inf where there is none;
        ``centres``: (K, 3) every obstacle's centre now, in the order given at construction (None: where
        they were given, the obstacles standing still).

        A ray is cast in the plane along its horizontal part; a hit on a side counts where the ray is
        within the obstacle's height there (a ray that would enter through a top face is not followed).
        With ``cull`` (the default), each obstacle is tested only against the rays whose bearings its bounding
        circle covers, as seen from the origin; without, against every ray (the same distances: a test holds
        them equal). ``fan``: (bearing of the first ray, increment) in rad when ray i's bearing is
        first + i x increment (a LIDAR's, give or take its tilt), which finds the windows faster."""
        x, y, z = map(float, origin)
        rise = dirs[:, 2]
        count = len(dirs)
        best = numpy.full(count, numpy.inf)
        top, bottom = float(rise.max()), float(rise.min())
        drift = range_max * max(top, -bottom)         # how far a ray rises or falls over the range
        if drift:
            level = numpy.hypot(dirs[:, 0], dirs[:, 1])
            fx, fy = dirs[:, 0] / level, dirs[:, 1] / level
            if bottom < 0.0 and -z / bottom <= range_max:       # some ray meets the ground within the range
                down = rise < 0.0
                best[down] = -z / rise[down]
        else:                                   # a level scan (the usual one): its directions are already flat
            level, fx, fy = None, dirs[:, 0], dirs[:, 1]
        if centres is None:
            ax, ay, az = self._x, self._y, self._z
        else:
            at = numpy.asarray(centres, float).reshape(-1, 3)[self._order]
            ax, ay, az = at[:, 0], at[:, 1], at[:, 2]
        seen = self._seen
        rel_x, rel_y, distance = numpy.subtract(ax, x, out=seen[0]), numpy.subtract(ay, y, out=seen[1]), seen[2]
        numpy.hypot(rel_x, rel_y, out=distance)
        within = distance - self._radius <= range_max
        # Only obstacles whose height spans the scan's plane, give or take the drift (all of them, usually).
        spans_all = centres is None and self._spans[0] <= z - drift and z + drift <= self._spans[1]
        if not spans_all:
            gap = numpy.abs(az - z)
            within &= gap <= self._half_height + drift
        near = numpy.flatnonzero(within)
        if not len(near):
            best[best > range_max] = numpy.inf
            return best
        rel_x, rel_y, distance, radius = seen[:, near]
        if not cull:
            ray, obstacle = numpy.arange(count)[:, None], numpy.arange(len(near))[None, :]
        elif fan is not None:
            ray, obstacle = _fan_pairs(fan, count, rel_x, rel_y, distance, radius, drift / range_max)
        else:
            bearings = numpy.arctan2(fy, fx)
            order = numpy.argsort(bearings, kind='stable')
            ray, obstacle = _sorted_pairs((bearings[order], order), rel_x, rel_y, distance, radius)
        # ``obstacle`` counts in ``near``, whose shapes come one after another; the pairs come obstacle by obstacle.
        parts = numpy.searchsorted(near, [g[1] for g in self._groups] + [len(self._radius)])
        high = not spans_all and (gap[near] + drift > self._half_height[near]).any()   # a ray may pass over one
        for (shape, start, _end, params), a, b in zip(self._groups, parts[:-1], parts[1:]):
            if a == b:
                continue
            if len(self._groups) == 1:
                mine, rays = obstacle, ray
            else:
                first, last = numpy.searchsorted(obstacle if cull else obstacle[0], (a, b))
                mine, rays = obstacle[..., first:last], (ray[first:last] if cull else ray)
            prepared = shape.ray_prepare(params[near[a:b] - start], rel_x[a:b], rel_y[a:b])
            along = shape.ray_pairs(prepared, mine - a, fx[rays], fy[rays])
            if drift:
                along = along / level[rays]
                if high:
                    with numpy.errstate(invalid='ignore'):                  # inf x 0 on a level ray that misses
                        height = z + along * rise[rays] - az[near[a:b]][mine - a]
                    along[numpy.abs(height) > self._half_height[near[a:b]][mine - a]] = numpy.inf
            if along.ndim == 2:
                numpy.minimum(best, along.min(axis=1), out=best)
            else:
                numpy.minimum.at(best, rays, along)
        best[best > range_max] = numpy.inf
        return best


def _half_widths(distance, radius, margin=0.0):
    """Half the angle (rad) each bounding circle covers, seen from the origin, and ``margin``; pi from inside."""
    inside = distance <= radius
    if not inside.any():
        return numpy.arcsin(radius / distance) + (WINDOW_MARGIN_RAD + margin)
    half = numpy.arcsin(radius / numpy.where(inside, radius, distance))
    half[inside] = numpy.pi
    return half + (WINDOW_MARGIN_RAD + margin)


def _expand(start, counts):
    """(ray indices, obstacle positions) of the pairs: obstacle m with rays start[m] .. start[m] + counts[m] - 1."""
    total = int(counts.sum())
    first = numpy.repeat(start - (numpy.cumsum(counts) - counts), counts)
    return first + numpy.arange(total), numpy.repeat(numpy.arange(len(counts)), counts)


def _fan_pairs(fan, count, rel_x, rel_y, distance, radius, stray=0.0):
    """The ray-obstacle pairs to test for a fan of ``count`` rays (bearings first + i x increment, give or take
    ``stray`` rad): each obstacle (its centre from the origin, its circle's radius) against the rays in its
    window, found as index ranges. A full turn's window wraps round its ends; a partial fan's may reach past
    the first ray's bearing or a full turn beyond it, where the part on the other side is taken too. The pairs
    come obstacle by obstacle."""
    first, increment = fan
    centre = numpy.arctan2(rel_y, rel_x) - first                         # from the first ray
    half = _half_widths(distance, radius, stray)
    if abs(count * increment - TWO_PI) < 1e-9:
        # Ray indices: from ceil((centre - half) / increment) to floor((centre + half) / increment), at most a
        # turn of them, each taken modulo the count (so the centre need not be within a turn of the first ray).
        start = numpy.ceil((centre - half) / increment)
        counts = numpy.minimum(numpy.floor((centre + half) / increment) - start + 1.0, count).astype(numpy.intp)
        ray, obstacle = _expand(start.astype(numpy.intp), counts)
        return numpy.mod(ray, count), obstacle
    half = numpy.repeat(half, 3)
    centre = numpy.mod(centre, TWO_PI)                                    # [0, 2 pi) from the first ray
    centre = (centre[:, None] + _TURNS).ravel()                           # each window, a turn before and after
    # Ray indices: from ceil((centre - half) / increment), to floor((centre + half) / increment) inclusive.
    bounds = numpy.floor(numpy.stack((half - centre, centre + half)) / increment)
    # -start within [-count, 0], end - 1 within [-1, count - 1]
    numpy.maximum(bounds, ((-count,), (-1,)), out=bounds)
    numpy.minimum(bounds, ((0,), (count - 1,)), out=bounds)
    edges = bounds.astype(numpy.intp)
    ray, obstacle = _expand(-edges[0], numpy.maximum(edges[1] + 1 + edges[0], 0))
    return ray, obstacle // 3


_TURNS = numpy.array([-TWO_PI, 0.0, TWO_PI])


def _sorted_pairs(windows, rel_x, rel_y, distance, radius):
    """As :func:`_fan_pairs` for any rays: ``windows`` is (their bearings ascending in [-pi, pi], the ray index
    of each); each obstacle's window is found in them by search, and where it wraps past -pi or pi, the part on
    the other side too."""
    sorted_bearings, order = windows
    centre = numpy.arctan2(rel_y, rel_x)
    half = _half_widths(distance, radius)
    low = numpy.column_stack((centre - half - TWO_PI, centre - half, centre - half + TWO_PI)).ravel()
    high = numpy.column_stack((centre + half - TWO_PI, centre + half, centre + half + TWO_PI)).ravel()
    start = numpy.searchsorted(sorted_bearings, low, 'left')
    end = numpy.searchsorted(sorted_bearings, high, 'right')
    position, obstacle = _expand(start, numpy.maximum(end - start, 0))
    return order[position], obstacle // 3
