"""A planar ray caster for the LIDAR: exact, and several times cheaper than pybullet's in clutter.

The LIDAR's rays are horizontal and every obstacle is a vertical prism (``closed_loop.sim.shapes``), so a
ray's first hit is a 2D question: where the ray, in the scan's plane, first meets the footprint of an
obstacle whose height spans that plane. Each shape casts at its own obstacles
(``shapes.SHAPES[shape].ray_distances``); obstacles whose bounding circle lies beyond the range are left
out first, so a scan costs in proportion to what is near. Moving obstacles are cast where they are now.

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

    def cast(self, centres, origin, dirs, range_max):
        """Distances (N,) from ``origin`` (x, y, z) along ``dirs`` ((N, 3) unit vectors, near the horizontal)
        to the first obstacle or the ground (z = 0) within ``range_max``, inf where there is none;
        ``centres``: (K, 3) every obstacle's centre now, in the order given at construction.

        A ray is cast in the plane along its horizontal part; a hit on a side counts where the ray is
        within the obstacle's height there (a ray that would enter through a top face is not followed)."""
        centres = numpy.asarray(centres, float)
        x, y, z = (float(v) for v in origin)
        level = numpy.hypot(dirs[:, 0], dirs[:, 1])
        flat = dirs[:, :2] / level[:, None]
        rise = dirs[:, 2]
        best = numpy.full(len(dirs), numpy.inf)
        with numpy.errstate(divide='ignore'):
            down = rise < 0.0
            best[down] = -z / rise[down]
        drift = range_max * float(numpy.abs(rise).max())     # how far a ray rises or falls over the range
        for shape, indices, params, half_height in self._groups:
            at = centres[indices]
            gap = numpy.abs(at[:, 2] - z)
            near = (numpy.hypot(at[:, 0] - x, at[:, 1] - y) - params[:, -1] <= range_max) \
                & (gap <= half_height + drift)
            if not near.any():
                continue
            along = shape.ray_distances(params[near], at[near, :2], (x, y), flat)
            if drift:
                along /= level[:, None]
                if (gap[near] + drift > half_height[near]).any():     # some ray may pass over or under one
                    with numpy.errstate(invalid='ignore'):      # inf x 0 on a level ray that misses
                        height = z + along * rise[:, None] - at[near, 2]
                    along[numpy.abs(height) > half_height[near]] = numpy.inf
            numpy.minimum(best, along.min(axis=1), out=best)
        best[best > range_max] = numpy.inf
        return best
