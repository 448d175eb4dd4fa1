"""The difficulty metrics of the BARN benchmark (Perille et al., 2020), for a world of
``closed_loop.sim.barn``, computed along its shortest footprint-feasible way (``barn.way_length``) where that
way crosses the field, at points a cell apart:

- ``closest_m``, distance to the closest obstacle: the mean distance from the way's points to the nearest
  obstacle's footprint;
- ``visibility_m``, average visibility: the mean length of ``RAYS`` rays cast round each point, each to the
  first surface or ``VISIBILITY_CAP_M``;
- ``dispersion``, the mean number of changes round each point between rays that meet a surface within
  ``DISPERSION_RANGE_M`` and rays that do not (how many ways open out from it);
- ``characteristic_m``, characteristic dimension: at each point the narrowest axis (a ray and its
  opposite, their lengths summed), averaged along the way;
- ``tortuosity``: the way's length over the straight distance from the start to the goal.

Lower closest, visibility and characteristic dimension, and higher dispersion and tortuosity, make a world
harder. Free of ROS.
"""
import math
from dataclasses import asdict, dataclass

import numpy

from closed_loop.sim import barn, shapes
from closed_loop.sim.planar_rays import PlanarRays
from closed_loop.sim.world import parse_world

RAYS = 64
VISIBILITY_CAP_M = 5.0
DISPERSION_RANGE_M = 1.5
SCAN_HEIGHT_M = 0.3


@dataclass(frozen=True)
class Metrics:
    """One world's difficulty metrics (see the module's docstring), and its way's length (m)."""
    closest_m: float
    visibility_m: float
    dispersion: float
    characteristic_m: float
    tortuosity: float
    way_m: float

    def line(self):
        """The metrics as one line (a world file's comment)."""
        return ('closest %.3f m, visibility %.2f m, dispersion %.2f, characteristic dimension %.3f m, '
                'tortuosity %.3f, way %.2f m' % (self.closest_m, self.visibility_m, self.dispersion,
                                                   self.characteristic_m, self.tortuosity, self.way_m))

    def as_dict(self):
        return {k: round(v, 4) for k, v in asdict(self).items()}


def _resample(poses, spacing_m):
    """Points along the polyline through ``poses`` ((x, y, ...)), ``spacing_m`` apart."""
    points = numpy.array([(p[0], p[1]) for p in poses], float)
    if len(points) < 2:
        return points
    steps = numpy.hypot(*numpy.diff(points, axis=0).T)
    along = numpy.concatenate(([0.0], numpy.cumsum(steps)))
    at = numpy.arange(0.0, along[-1] + 1e-9, spacing_m)
    return numpy.column_stack((numpy.interp(at, along, points[:, 0]), numpy.interp(at, along, points[:, 1])))


def metrics(settings, world, profile):
    """The :class:`Metrics` of ``world`` (a dict made by ``barn.generate`` with ``settings``) for ``profile``."""
    field = barn.field_of_world(settings, world)
    way_m, poses = barn.way_length(settings, field, profile)
    if not poses:
        raise barn.BarnError('%s: no way for %s (not a world of these settings?)' % (world['name'], profile.name))
    layout = barn.Layout(settings)
    field_end = layout.field_start + settings.length_cells * settings.cell_m
    points = _resample(poses, settings.cell_m)
    points = points[(points[:, 0] >= layout.field_start) & (points[:, 0] <= field_end)]
    parsed = parse_world(world, world['name'], check_starts=False)
    caster = PlanarRays(parsed.obstacles)
    centres = numpy.array([o.position for o in parsed.obstacles], float)
    angles = numpy.arange(RAYS) * 2 * math.pi / RAYS
    dirs = numpy.column_stack((numpy.cos(angles), numpy.sin(angles), numpy.zeros(RAYS)))
    closest, visibility, dispersion, narrowest = [], [], [], []
    for x, y in points:
        ranges = caster.cast(centres, (x, y, SCAN_HEIGHT_M), dirs, VISIBILITY_CAP_M)
        ranges = numpy.minimum(ranges, VISIBILITY_CAP_M)
        closest.append(min(shapes.distance(o, x, y) for o in parsed.obstacles))
        visibility.append(float(ranges.mean()))
        near = ranges < DISPERSION_RANGE_M
        dispersion.append(int(numpy.count_nonzero(near != numpy.roll(near, 1))))
        narrowest.append(float((ranges[:RAYS // 2] + ranges[RAYS // 2:]).min()))
    straight = math.hypot(poses[-1][0] - poses[0][0], poses[-1][1] - poses[0][1])
    return Metrics(float(numpy.mean(closest)) if closest else math.inf,
                   float(numpy.mean(visibility)) if visibility else VISIBILITY_CAP_M,
                   float(numpy.mean(dispersion)) if dispersion else 0.0,
                   float(numpy.mean(narrowest)) if narrowest else 2 * VISIBILITY_CAP_M,
                   way_m / straight if straight > 0 else 1.0, way_m)
