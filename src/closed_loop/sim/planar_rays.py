"""A planar ray caster for the LIDAR: exact, and several times cheaper than pybullet's in clutter.

The LIDAR's rays are horizontal and every obstacle is a vertical prism (``closed_loop.sim.shapes``), so a
ray's first hit is a 2D question: where the ray, in the scan's plane, first meets the footprint of an
obstacle whose height spans that plane. Each shape casts at its own obstacles
(``shapes.SHAPES[shape].ray_distances``); obstacles whose bounding circle lies beyond the range are left
out first, and each of the others is tested only against the rays whose bearings its bounding circle can
cover (an angular window seen from the LIDAR), so a scan costs in proportion to what each ray can meet.
Moving obstacles are cast where they are now.

What it does not see, pybullet's caster does: other robots, and the scan plane tilted off the horizontal.
:class:`closed_loop.sim.sensors.lidar.Lidar` uses it only where neither can be (``~ray_caster``). Free of ROS.
"""
import collections

import numpy

from closed_loop.sim import shapes


class PlanarRays:
    """Casts horizontal rays at the obstacles ``obstacles`` (``world.Obstacle``, vertical prisms)."""

    def __init__(self, obstacles):
        groups = collections.defaultdict(list)
        for index, obstacle in enumerate(obstacles):
            groups[obstacle.shape].append(index)
        self._groups = []
        for shape, indices in groups.items():
            cls = shapes.SHAPES[shape]
            chosen = [obstacles[i] for i in indices]
            half_height = numpy.array([0.5 * o.size[2] for o in chosen])
            # Each shape's parameter rows end with the radius of a circle round the footprint.
            self._groups.append((cls, numpy.array(indices), cls.ray_params(chosen), half_height))

    def cast(self, centres, origin, dirs, range_max, cull=True):
        """Distances (N,) from ``origin`` (x, y, z) along ``dirs`` ((N, 3) unit vectors, near the horizontal)
        to the first obstacle or the ground (z = 0) within ``range_max``, inf where there is none;
        ``centres``: (K, 3) every obstacle's centre now, in the order given at construction.

        A ray is cast in the plane along its horizontal part; a hit on a side counts where the ray is
        within the obstacle's height there (a ray that would enter through a top face is not followed).
        With ``cull`` (the default), each obstacle is tested only against the rays whose bearings its bounding
        circle covers, as seen from the origin; without, against every ray (the same distances: a test
        holds them equal)."""
        centres = numpy.asarray(centres, float)
        x, y, z = (float(v) for v in origin)
        rise = dirs[:, 2]
        best = numpy.full(len(dirs), numpy.inf)
        drift = range_max * float(numpy.abs(rise).max())     # how far a ray rises or falls over the range
        if drift:
            level = numpy.hypot(dirs[:, 0], dirs[:, 1])
            flat = dirs[:, :2] / level[:, None]
            down = rise < 0.0
            best[down] = -z / rise[down]
        else:                                   # a level scan (the usual one): its directions are already flat
            flat = dirs[:, :2]
        if cull:
            bearings = numpy.arctan2(flat[:, 1], flat[:, 0])
            order = numpy.argsort(bearings, kind='stable')
            sorted_bearings = bearings[order]
        for shape, indices, params, half_height in self._groups:
            at = centres[indices]
            gap = numpy.abs(at[:, 2] - z)
            near = (numpy.hypot(at[:, 0] - x, at[:, 1] - y) - params[:, -1] <= range_max) \
                & (gap <= half_height + drift)
            if not near.any():
                continue
            params_n, at_n, half_n = params[near], at[near], half_height[near]
            if cull:
                ray, obstacle = _pairs(sorted_bearings, order, at_n[:, :2] - (x, y), params_n[:, -1])
            else:
                ray, obstacle = numpy.arange(len(dirs))[:, None], numpy.arange(len(at_n))[None, :]
            along = shape.ray_distances(params_n[obstacle], at_n[obstacle, :2], (x, y), flat[ray])
            if drift:
                along = along / level[ray]
                if (gap[near] + drift > half_n).any():     # some ray may pass over or under one
                    with numpy.errstate(invalid='ignore'):      # inf x 0 on a level ray that misses
                        height = z + along * rise[ray] - at_n[obstacle, 2]
                    along[numpy.abs(height) > half_n[obstacle]] = numpy.inf
            if cull:
                numpy.minimum.at(best, ray, along)
            else:
                numpy.minimum(best, along.min(axis=1), out=best)
        best[best > range_max] = numpy.inf
        return best


#: A ray this close (rad) to the edge of an obstacle's angular window is still tested against it.
WINDOW_MARGIN_RAD = 1e-9


def _pairs(sorted_bearings, order, rel, radius):
    """(ray indices, obstacle indices) of the ray-obstacle pairs to test: each obstacle (``rel``: its centre
    from the origin, (M, 2); ``radius``: its bounding circle's) against the rays whose bearings
    (``sorted_bearings``, ascending in [-pi, pi]; ``order``: their ray indices) its circle covers; every ray
    when the origin is inside the circle."""
    distance = numpy.hypot(rel[:, 0], rel[:, 1])
    centre = numpy.arctan2(rel[:, 1], rel[:, 0])
    inside = distance <= radius
    half = numpy.arcsin(radius / numpy.where(inside, radius, distance))      # pi/2 inside: set to pi below
    half[inside] = numpy.pi
    half += WINDOW_MARGIN_RAD
    low, high = centre - half, centre + half
    count = len(sorted_bearings)
    start = numpy.searchsorted(sorted_bearings, low, 'left')
    end = numpy.searchsorted(sorted_bearings, high, 'right')
    obstacle = numpy.arange(len(rel))
    # Where a window wraps past -pi or pi, the part on the other side.
    under, over = numpy.flatnonzero(low < -numpy.pi), numpy.flatnonzero(high > numpy.pi)
    if len(under) or len(over):
        start = numpy.concatenate((start, numpy.searchsorted(sorted_bearings, low[under] + 2 * numpy.pi, 'left'),
                                   numpy.zeros(len(over), int)))
        end = numpy.concatenate((end, numpy.full(len(under), count),
                                 numpy.searchsorted(sorted_bearings, high[over] - 2 * numpy.pi, 'right')))
        obstacle = numpy.concatenate((obstacle, under, over))
    counts = numpy.maximum(end - start, 0)
    total = int(counts.sum())
    first = numpy.repeat(start - (numpy.cumsum(counts) - counts), counts)
    return order[first + numpy.arange(total)], numpy.repeat(obstacle, counts)
