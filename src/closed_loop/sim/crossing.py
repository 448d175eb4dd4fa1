"""Seeded worlds of a walker crossing the robot's way (generator method ``crossing``): the scenario a search
varies to find when a controller meets a person (``closed_loop.batch.search``), as ``person_crossing.yaml`` is
one of them by hand.

The robot starts at the origin facing +x, its goal ``goal_distance`` ahead, between two side walls
``width`` apart. A walker (a red cylinder, a person's size) walks across the robot's line at ``crossing_x``
(m ahead of the start), at ``walker_speed`` (m/s), from ``walker_start`` (m to the right of the line, or to the
left where negative: it crosses the line ``|walker_start| / walker_speed`` seconds in) to the far wall, once; a
``seed`` jitters where it crosses by up to ``jitter`` m, so that one setting gives many episodes. Free of ROS.
"""
import math
from dataclasses import dataclass

import numpy

WALKER_RADIUS_M, WALKER_HEIGHT_M = 0.25, 1.7
WALL_THICKNESS_M, WALL_HEIGHT_M = 0.1, 0.8


class CrossingError(ValueError):
    """Settings out of range; the message names the field."""


@dataclass(frozen=True)
class CrossingSettings:
    """A crossing world's settings (the module's docstring); every field checked by :meth:`check`."""
    seed: int = 0                  # jitters where the walker crosses
    walker_speed: float = 1.0      # m/s
    crossing_x: float = 3.0        # m ahead of the start where the walker crosses the robot's line
    walker_start: float = 3.0      # m to the right of the line where it starts (negative: to the left)
    jitter: float = 0.0            # m, the seed's shift of where it crosses, at most
    goal_distance: float = 7.0     # m, start to goal along +x
    width: float = 8.0             # m, between the side walls
    profile: str = 'closed_loop'   # the robot (its footprint keeps the start clear)

    def check(self):
        def bad(name, expected):
            raise CrossingError('%s: expected %s, got %r' % (name, expected, getattr(self, name)))
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            bad('seed', 'an integer >= 0')
        for name, low, high in (('walker_speed', 0.05, 5.0), ('crossing_x', 0.8, 50.0), ('walker_start', -20.0, 20.0),
                                ('jitter', 0.0, 5.0), ('goal_distance', 1.0, 60.0), ('width', 2.0, 50.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
                bad(name, 'a number from %g to %g' % (low, high))
        if abs(self.walker_start) < WALKER_RADIUS_M + 0.5 or abs(self.walker_start) > self.width / 2 - WALKER_RADIUS_M:
            bad('walker_start', 'at least %.2f m off the robot\'s line and inside the walls (%.2f m)'
                % (WALKER_RADIUS_M + 0.5, self.width / 2 - WALKER_RADIUS_M))
        return self


def generate(settings, profile=None):
    """The world dict of ``settings`` (checked)."""
    s = settings.check()
    shift = float(numpy.random.default_rng(s.seed).uniform(-s.jitter, s.jitter)) if s.jitter else 0.0
    x = s.crossing_x + shift
    side = math.copysign(1.0, s.walker_start)          # it walks to the other side (right: y < 0, to y > 0)
    y0, y1 = -s.walker_start, side * (s.width / 2 - WALKER_RADIUS_M - 0.05)
    half = s.width / 2 + WALL_THICKNESS_M / 2
    x0, x1 = -1.0, s.goal_distance + 1.0
    walls = [{'name': name, 'type': 'wall', 'start': [x0, y], 'end': [x1, y], 'thickness': WALL_THICKNESS_M,
              'height': WALL_HEIGHT_M, 'color': 'white'} for name, y in (('wall_left', half), ('wall_right', -half))]
    walker = {'name': 'walker', 'type': 'cylinder', 'position': [round(x, 4), round(y0, 4)],
              'radius': WALKER_RADIUS_M, 'height': WALKER_HEIGHT_M, 'color': 'red',
              'motion': {'waypoints': [[round(x, 4), round(y1, 4)]], 'speed': float(s.walker_speed), 'loop': False}}
    return {'name': 'crossing_v%03d_x%03d_s%d' % (round(100 * s.walker_speed), round(100 * s.crossing_x), s.seed),
            'description': 'a walker crosses the way at x %.2f m, %.2f m/s, from %.2f m to the side'
                           % (x, s.walker_speed, s.walker_start),
            'robot': {'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}},
            'goal': {'x': float(s.goal_distance), 'y': 0.0},
            'obstacles': walls + [walker]}
