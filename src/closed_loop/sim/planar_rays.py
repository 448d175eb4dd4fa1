"""A planar ray caster for the LIDAR: exact, and many times cheaper than pybullet's in clutter.

The LIDAR's rays are horizontal and every obstacle is a vertical prism (``closed_loop.sim.shapes``), so a
ray's first hit is a 2D question: where the ray, in the scan's plane, first meets the footprint of an
obstacle whose height spans that plane. Obstacles whose bounding circle lies beyond the range are left out,
and each of the others is tested only against the rays whose bearings its bounding circle can cover (an
angular window seen from the LIDAR), so a scan costs in proportion to what each ray can meet. For a LIDAR's
fan of evenly spaced rays (``fan``) the window is a range of ray indices found by arithmetic; for any other set
of rays, by a search in their sorted bearings. Moving obstacles are cast where they are now. A world of
thousands of obstacles standing still (a building's map) is cast the other way round: each ray walks a grid of
cells from the LIDAR and stops at the first cell whose far side lies beyond its nearest hit, so that the walls
behind the nearest one cost nothing.

The loop over obstacles and their rays is compiled (``closed_loop.sim.planar_kernel``, numba): as numpy array
operations a scan was about 55 calls, each costing its fixed microsecond and a half whatever it held, and the
cast took several times longer for the same distances. A shape's ray test is its branch there, by its code
``shapes.SHAPES[shape].RAY_KIND``; its numbers come from ``ray_params``.

What it does not see, pybullet's caster does: other robots, and the scan plane tilted off the horizontal.
:class:`closed_loop.sim.sensors.lidar.Lidar` uses it only where neither can be (``~ray_caster``). Free of ROS.
"""
import importlib

import numpy

from closed_loop.sim import shapes


#: From how many obstacles on a scan standing still the rays walk a grid of cells (``planar_kernel.grid_cast``)
#: instead of each obstacle in range finding its rays: a map of a building holds thousands, most of them behind
#: the nearest wall.
GRID_MIN_OBSTACLES = 1000
#: A grid cell's side, in multiples of the side of the square each obstacle would have to itself; and the
#: most cells a grid may have.
GRID_CELL_SCALE, GRID_MAX_CELLS = 1.0, 1 << 22
#: How far (m) beyond its footprint's bounding box an obstacle is listed in a cell, so that a hit on a cell's
#: side is found from either cell whatever the rounding.
GRID_MARGIN_M = 1e-6


def prepare():
    """The compiled loop loaded, both ways of matching rays to obstacles (compiled on a machine's first use)."""
    from closed_loop.sim.world import Obstacle
    post = Obstacle('post', 'cylinder', (1.0, 0.0, 0.5), 0.0, (0.2, 0.2, 1.0), 0.1, (1.0, 1.0, 1.0, 1.0), None)
    PlanarRays([post])
    PlanarRays([post], grid=True)


class PlanarRays:
    """Casts horizontal rays at the obstacles ``obstacles`` (``world.Obstacle``, vertical prisms); ``grid``: walk
    a grid of cells when the obstacles stand still (None: when there are at least
    :data:`GRID_MIN_OBSTACLES`)."""

    def __init__(self, obstacles, grid=None):
        # numba is imported with the first caster, not with this module: it costs a process about 0.1 s and
        # 60 MB, which a sweep's own process (that imports the world generators) need not pay.
        self._kernel = importlib.import_module('closed_loop.sim.planar_kernel')
        count = len(obstacles)
        self._kind = numpy.array([shapes.SHAPES[o.shape].RAY_KIND for o in obstacles], dtype=numpy.int64)
        self._params = numpy.zeros((count, 4))
        for shape in {o.shape for o in obstacles}:
            mine = [i for i, o in enumerate(obstacles) if o.shape == shape]
            rows = shapes.SHAPES[shape].ray_params([obstacles[i] for i in mine])
            self._params[mine, :rows.shape[1]] = rows
        self._radius = numpy.array([shapes.bounding_radius(o) for o in obstacles], dtype=float)
        self._half_height = numpy.array([0.5 * o.size[2] for o in obstacles], dtype=float)
        at = numpy.array([o.position for o in obstacles], float).reshape(-1, 3)
        # Where the obstacles were given, each coordinate apart; and the heights every one of them spans.
        self._x, self._y, self._z = (numpy.ascontiguousarray(at[:, i]) for i in range(3))
        self._spans = (float((self._z - self._half_height).max(initial=-numpy.inf)),
                       float((self._z + self._half_height).min(initial=numpy.inf)))
        self._none = numpy.empty(0)
        self._grid = None
        if count and (grid or (grid is None and count >= GRID_MIN_OBSTACLES)):
            self._grid = self._make_grid()
        self._no_order = numpy.empty(0, dtype=numpy.int64)
        # The compiled loop loaded now (compiled, on a machine's first use: about half a second), not at the
        # first scan.
        self.cast(None, (0.0, 0.0, 1.0), numpy.array([[1.0, 0.0, 0.0]]), 1.0, fan=(0.0, 1.0))

    def _make_grid(self):
        """(x0, y0, cell, nx, ny, starts, items, seen) for ``planar_kernel.grid_cast``: a square of cells about every
        obstacle's footprint, each holding the obstacles that may be hit in it."""
        boxes = self._kernel.footprint_boxes(self._kind, self._params, self._x, self._y, self._radius)
        x0, y0 = boxes[:, 0].min() - GRID_MARGIN_M, boxes[:, 1].min() - GRID_MARGIN_M
        width, height = boxes[:, 2].max() + GRID_MARGIN_M - x0, boxes[:, 3].max() + GRID_MARGIN_M - y0
        cell = max(GRID_CELL_SCALE * (width * height / len(boxes)) ** 0.5,
                   (width * height / GRID_MAX_CELLS) ** 0.5, 1e-3)
        nx, ny = int(width // cell) + 1, int(height // cell) + 1
        starts, items = self._kernel.grid_cells(boxes, float(x0), float(y0), cell, nx, ny, GRID_MARGIN_M)
        seen = numpy.full(len(boxes) + 1, -1, dtype=numpy.int64)
        seen[-1] = 0
        return float(x0), float(y0), float(cell), nx, ny, starts, items, seen

    def cast(self, centres, origin, dirs, range_max, cull=True, fan=None):
        """Distances (N,) from ``origin`` (x, y, z) along ``dirs`` ((N, 3) unit vectors, near the horizontal)
        to the first obstacle or the ground (z = 0) within ``range_max``, inf where there is none;
        ``centres``: (K, 3) every obstacle's centre now, in the order given at construction (None: where
        they were given, the obstacles standing still).

        A ray is cast in the plane along its horizontal part; a hit on a side counts where the ray is
        within the obstacle's height there (a ray that would enter through a top face is not followed).
        With ``cull`` (the default), each obstacle is tested only against the rays whose bearings its bounding
        circle covers, as seen from the origin; without, against every ray (the same distances: a test holds
        them equal), or the grid (the same again). ``fan``: (bearing of the first ray, increment) in rad when ray i's bearing is
        first + i x increment (a LIDAR's, give or take its tilt), which finds the windows faster."""
        x, y, z = map(float, origin)
        dirs = numpy.asarray(dirs, float)
        rise = numpy.ascontiguousarray(dirs[:, 2])
        best = numpy.full(len(dirs), numpy.inf)
        top, bottom = float(rise.max(initial=0.0)), float(rise.min(initial=0.0))
        drift = range_max * max(top, -bottom)         # how far a ray rises or falls over the range
        if drift:
            level = numpy.hypot(dirs[:, 0], dirs[:, 1])
            fx, fy = dirs[:, 0] / level, dirs[:, 1] / level
            if bottom < 0.0 and -z / bottom <= range_max:       # some ray meets the ground within the range
                down = rise < 0.0
                best[down] = -z / rise[down]
        else:                                   # a level scan (the usual one): its directions are already flat
            level, fx, fy = self._none, numpy.ascontiguousarray(dirs[:, 0]), numpy.ascontiguousarray(dirs[:, 1])
        if centres is None:
            ax, ay, az = self._x, self._y, self._z
        else:
            at = numpy.asarray(centres, float).reshape(-1, 3)
            ax, ay, az = (numpy.ascontiguousarray(at[:, i]) for i in range(3))
        # Only obstacles whose height spans the scan's plane, give or take the drift, are tested for height
        # (all of them span it, usually).
        check_height = not (centres is None and self._spans[0] <= z - drift and z + drift <= self._spans[1])
        kernel = self._kernel
        if cull and centres is None and self._grid is not None:
            kernel.grid_cast(self._kind, self._params, ax, ay, az, self._half_height, x, y, z, fx, fy, level, rise,
                             drift, range_max, check_height, *self._grid, best)
            best[best > range_max] = numpy.inf
            return best
        mode, first, increment, bearings, order = kernel.EVERY, 0.0, 0.0, self._none, self._no_order
        if cull and fan is not None:
            mode, first, increment = kernel.FAN, float(fan[0]), float(fan[1])
        elif cull:
            unsorted = numpy.arctan2(fy, fx)
            order = numpy.argsort(unsorted, kind='stable')
            mode, bearings = kernel.SORTED, unsorted[order]
        kernel.cast(self._kind, self._params, ax, ay, az, self._half_height, self._radius, x, y, z, fx, fy, level, rise,
              drift, range_max, check_height, mode, first, increment, bearings, order, best)
        best[best > range_max] = numpy.inf
        return best
