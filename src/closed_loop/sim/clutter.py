"""Seeded cluttered worlds: cylinders and boxes on a jittered grid between two side walls, a start at the
origin facing +x and a goal ``length`` ahead, with a path guaranteed wide enough for the chosen robot.

The rule (:func:`generate`), all drawn from one ``numpy`` generator seeded with ``seed``, so a seed and the
settings give the same world on any machine:

1. A corridor: a polyline from the start to the goal through ``CORRIDOR_BENDS`` points at random sideways
   offsets. Its half-width is the robot's circumscribed radius plus ``safety_margin`` plus
   ``CORRIDOR_SLACK_M``: the robot fits along it at any heading, turning in place included.
2. Sites on a grid (``pitch``) over the field; each holds an obstacle with probability ``fill_ratio``: a
   cylinder (radius 0.1 to 0.2 m) or a box (sides 0.2 to 0.4 m, any yaw), jittered about the site.
3. An obstacle is left out when its bounding circle comes within the corridor's half-width of the
   polyline, within ``gap_ratio`` robot widths of another obstacle's bounding circle or a wall, or near the
   start or the goal. So the narrowest gaps are ``gap_ratio`` times the robot's width (1.3 by default:
   narrower than the robot plus its margins, gaps it must see and not enter), and the corridor stays open.
4. A check that does not trust step 3: the obstacles are drawn on a 5 cm grid, grown by the robot's
   circumscribed radius plus the margin, and the goal must be reachable from the start through what is
   left. A world that fails it is a bug here, raised as :class:`ClutterError`.

The world is a dict in the world-file format; ``closed_loop.sim.generators`` writes it with the settings in a
comment (``generate_world``, the corridor method). Free of ROS.
"""
import math
from dataclasses import dataclass

import cv2
import numpy

from closed_loop.sim.profiles import load_profile
from closed_loop.sim.world import MAX_OBSTACLES, WorldError, parse_world

CORRIDOR_BENDS = 3
CORRIDOR_SLACK_M = 0.05
START_GOAL_CLEAR_M = 0.6          # no obstacle's bounding circle this close to the start or the goal (m)
CYLINDER_RADIUS_M = (0.1, 0.2)
BOX_SIDE_M = (0.2, 0.4)
RASTER_CELL_M = 0.05
WALL_THICKNESS_M = 0.1
OBSTACLE_HEIGHT_M = 0.6


class ClutterError(ValueError):
    """Bad generator settings, or a generated world without the promised path (a bug)."""


@dataclass(frozen=True)
class ClutterSettings:
    """What a cluttered world is made from; every field has a unit and limits (checked by :meth:`check`)."""
    seed: int = 0                  # the generator's seed
    fill_ratio: float = 0.3        # fraction of grid sites that get an obstacle before the corridor is cut, 0-1
    profile: str = 'jackal'        # the robot the path must fit (config/robots/NAME.yaml, urdf/NAME.urdf)
    length: float = 10.0           # m, start to goal along +x
    width: float = 8.0             # m, between the side walls' inner faces
    pitch: float = 1.1             # m, grid spacing of the sites
    jitter: float = 0.1            # m, each obstacle's random offset from its site, at most
    gap_ratio: float = 1.3         # narrowest gap between obstacles, in robot widths
    safety_margin: float = 0.1     # m, the navigator's margin, kept free along the corridor

    def check(self):
        def bad(name, expected):
            raise ClutterError('%s: expected %s, got %r' % (name, expected, getattr(self, name)))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            bad('seed', 'an integer >= 0')
        for name, low, high in (('fill_ratio', 0.0, 1.0), ('length', 3.0, 100.0), ('width', 2.0, 50.0),
                                ('pitch', 0.3, 5.0), ('jitter', 0.0, 2.0), ('gap_ratio', 1.0, 10.0),
                                ('safety_margin', 0.0, 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
                bad(name, 'a number from %g to %g' % (low, high))
        return self


def _bounding_radius(ob):
    return ob['radius'] if ob['type'] == 'cylinder' else 0.5 * math.hypot(*ob['size'][:2])


def _segment_distance(px, py, a, b):
    (ax, ay), (bx, by) = a, b
    ex, ey = bx - ax, by - ay
    t = min(max(((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey), 0.0), 1.0)
    return math.hypot(px - ax - t * ex, py - ay - t * ey)


def narrowest_gap(world):
    """The least gap (m) between the bounding circles of two obstacles of a generated world (not its walls):
    the true gap between them is at least this."""
    solids = [o for o in world['obstacles'] if o['type'] != 'wall']
    return min((math.hypot(a['position'][0] - b['position'][0], a['position'][1] - b['position'][1])
                - _bounding_radius(a) - _bounding_radius(b)
                for i, a in enumerate(solids) for b in solids[i + 1:]), default=math.inf)


def robot_extent(profile):
    """(width m, circumscribed radius m) of a profile's footprint rectangle, about base_footprint."""
    fp = profile.footprint
    return fp.y_max - fp.y_min, fp.radius_m


def generate(settings, profile=None):
    """The world (a dict in the world-file format) for ``settings``; ``profile``: a loaded
    :class:`closed_loop.sim.profiles.Profile` (default: ``settings.profile``)."""
    s = settings.check()
    profile = profile or load_profile(s.profile)
    robot_width, robot_radius = robot_extent(profile)
    rng = numpy.random.default_rng(s.seed)
    half_w = 0.5 * s.width
    corridor_half = robot_radius + s.safety_margin + CORRIDOR_SLACK_M
    swing = max(half_w - corridor_half - 0.2, 0.0)
    bends = [(s.length * (i + 1) / (CORRIDOR_BENDS + 1), float(rng.uniform(-swing, swing)))
             for i in range(CORRIDOR_BENDS)]
    corridor = [(0.0, 0.0)] + bends + [(s.length, 0.0)]
    min_gap = s.gap_ratio * robot_width

    placed = []
    xs = numpy.arange(1.0, s.length - 0.5 + 1e-9, s.pitch)
    ys = numpy.arange(-half_w + 0.5 * s.pitch, half_w - 0.5 * s.pitch + 1e-9, s.pitch)
    for x in xs:
        for y in ys:
            # Every site draws the same numbers whether or not it is used, so one site's fate does not
            # shift the others' (a world changes locally when fill_ratio changes).
            used, kind, a, b, yaw, jx, jy = rng.uniform(0.0, 1.0, 7)
            if used >= s.fill_ratio:
                continue
            cx, cy = float(x + (2 * jx - 1) * s.jitter), float(y + (2 * jy - 1) * s.jitter)
            if kind < 0.5:
                ob = {'type': 'cylinder', 'position': [round(cx, 3), round(cy, 3)],
                      'radius': round(float(numpy.interp(a, (0, 1), CYLINDER_RADIUS_M)), 3),
                      'height': OBSTACLE_HEIGHT_M}
            else:
                ob = {'type': 'box', 'position': [round(cx, 3), round(cy, 3)],
                      'size': [round(float(numpy.interp(a, (0, 1), BOX_SIDE_M)), 3),
                               round(float(numpy.interp(b, (0, 1), BOX_SIDE_M)), 3), OBSTACLE_HEIGHT_M],
                      'yaw': round(float(yaw * math.pi), 3)}
            r = _bounding_radius(ob)
            cx, cy = ob['position']
            if min(_segment_distance(cx, cy, corridor[i], corridor[i + 1]) for i in range(len(corridor) - 1)) \
                    < corridor_half + r:
                continue
            if math.hypot(cx, cy) < START_GOAL_CLEAR_M + robot_radius + r \
                    or math.hypot(cx - s.length, cy) < START_GOAL_CLEAR_M + robot_radius + r:
                continue
            if half_w - abs(cy) - r < min_gap:
                continue
            if any(math.hypot(cx - o['position'][0], cy - o['position'][1]) - r - _bounding_radius(o) < min_gap
                   for o in placed):
                continue
            placed.append(ob)
    if len(placed) + 2 > MAX_OBSTACLES:
        raise ClutterError('fill_ratio: %d obstacles is more than a world may hold (%d)'
                           % (len(placed), MAX_OBSTACLES))
    sites = len(xs) * len(ys)
    obstacles = []
    for i, ob in enumerate(placed):
        ob = dict(ob, name='%s_%d' % (ob['type'], i), color='red' if i % 9 == 4 else 'grey')
        obstacles.append(ob)
    x0, x1 = -1.0, s.length + 1.0
    for side, name in ((1, 'wall_left'), (-1, 'wall_right')):
        y = side * (half_w + 0.5 * WALL_THICKNESS_M)
        obstacles.append({'name': name, 'type': 'wall', 'start': [x0, y], 'end': [x1, y],
                          'thickness': WALL_THICKNESS_M, 'height': OBSTACLE_HEIGHT_M, 'color': 'white'})
    world = {
        'name': 'clutter_%s_f%03d_s%d' % (s.profile, int(round(s.fill_ratio * 100)), s.seed),
        'description': 'Generated clutter: %d obstacles on %d sites (fill_ratio %.2f), goal (%g, 0), for %s'
                       % (len(placed), sites, s.fill_ratio, s.length, s.profile),
        'robot': {'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}},
        'goal': {'x': float(s.length), 'y': 0.0},
        'obstacles': obstacles,
    }
    check_path(world, profile, s)
    return world


def _raster(world_obj, x0, y0, cols, rows):
    """Occupancy (rows, cols) uint8: 0 where an obstacle is, 255 elsewhere, cells of RASTER_CELL_M."""
    free = numpy.full((rows, cols), 255, numpy.uint8)

    def to_px(x, y):
        return (x - x0) / RASTER_CELL_M, (y - y0) / RASTER_CELL_M
    for ob in world_obj.obstacles:
        cx, cy = to_px(ob.position[0], ob.position[1])
        if ob.shape == 'cylinder':
            cv2.circle(free, (int(round(cx)), int(round(cy))), int(math.ceil(ob.radius / RASTER_CELL_M)), 0, -1)
        else:
            corners = cv2.boxPoints(((cx, cy), (ob.size[0] / RASTER_CELL_M, ob.size[1] / RASTER_CELL_M),
                                     math.degrees(ob.yaw)))
            cv2.fillPoly(free, [numpy.round(corners).astype(numpy.int32)], 0)
    return free


def check_path(world, profile, settings):
    """Raise :class:`ClutterError` unless the robot's circumscribed disc plus ``safety_margin`` can travel
    from the start to the goal (the world's own check, independent of how it was built)."""
    _, radius = robot_extent(profile)
    world_obj = parse_world(world, '<generated %s>' % world['name'], footprint=profile.footprint)
    x0, y0 = -1.0, -0.5 * settings.width - 0.5
    cols = int(math.ceil((settings.length + 2.0) / RASTER_CELL_M))
    rows = int(math.ceil((settings.width + 1.0) / RASTER_CELL_M))
    free = _raster(world_obj, x0, y0, cols, rows)
    room = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * RASTER_CELL_M \
        - RASTER_CELL_M * math.sqrt(2.0)
    passable = (room >= radius + settings.safety_margin).astype(numpy.uint8)
    _, labels = cv2.connectedComponents(passable, connectivity=4)

    def label(x, y):
        return labels[int((y - y0) / RASTER_CELL_M), int((x - x0) / RASTER_CELL_M)]
    start, goal = label(0.0, 0.0), label(settings.length, 0.0)
    if start == 0 or start != goal:
        raise ClutterError('%s: no path %.2f m wide from the start to the goal (a generator bug)'
                           % (world['name'], 2 * (radius + settings.safety_margin)))
