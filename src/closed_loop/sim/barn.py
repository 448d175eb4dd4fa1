"""Seeded worlds built the way the BARN benchmark builds its own (Perille, Truong, Xiao and Stone, 2020,
"Benchmarking Metric Ground Navigation"): a cellular automaton on an occupancy grid, its occupied cells as unit
posts, a start before the field and a goal beyond it, and a way guaranteed only for the chosen robot's footprint
plus a small margin.

The rule (:func:`generate`), all drawn from one ``numpy`` generator seeded with (``seed``, attempt):

1. A field of ``length_cells`` x ``width_cells`` cells of ``cell_m``, ``FIELD_START_CELLS`` cells ahead of the start
   (the origin, facing +x); each cell is filled with probability ``fill``.
2. ``smoothing`` rounds of the automaton: a cell is filled next round when at least ``BIRTH`` of its 8
   neighbours are, and stays filled when at least ``SURVIVAL`` are (cells beyond the field's sides count as
   filled, beyond its ends as empty). Few rounds leave scattered posts; more grow them into walls and pockets.
3. Four walls round the whole way, a metre behind the start to a metre past the goal (the field cannot be gone
   round), the goal ``goal_distance`` ahead.
4. The guarantee: the robot's footprint rectangle, grown by ``margin``, must get from the start to the goal
   on the footprint lattice (``closed_loop.sim.lattice``: 8 headings, moving along its heading, turning in place
   only where the turn's sweep is free). A field that fails it is drawn again (the next attempt), up to
   ``MAX_ATTEMPTS``.

Each filled cell is a post: a cylinder of radius ``cell_m`` / 2 on the cell's centre. The difficulty metrics
of the paper (``closed_loop.sim.barn_metrics``) are computed on request and written in a world file's
comment. ``python3 -m closed_loop.sim.clutter --method barn`` (``generate_world``) writes such worlds. Free of
ROS.
"""
import dataclasses
import math
from dataclasses import dataclass

import numpy

from closed_loop.sim.lattice import FootprintLattice
from closed_loop.sim.profiles import load_profile

BIRTH, SURVIVAL = 5, 4
FIELD_START_CELLS = 14            # from the start to the field's first row, in cells (2.1 m of 0.15 m)
WALL_THICKNESS_M = 0.1
POST_HEIGHT_M = 0.6
MAX_ATTEMPTS = 200
#: The lattice the guarantee is checked on: this many lattice cells per field cell (posts on cell centres).
LATTICE_PER_CELL = 2


class BarnError(ValueError):
    """Bad settings, or no field with a way for the robot within MAX_ATTEMPTS."""


@dataclass(frozen=True)
class BarnSettings:
    """What a BARN-method world is made from; every field has a unit and limits (checked by :meth:`check`)."""
    seed: int = 0                  # the generator's seed
    fill: float = 0.25             # chance each cell starts filled, 0-1
    smoothing: int = 2             # rounds of the cellular automaton
    profile: str = 'jackal'        # the robot the way must fit (config/robots/NAME.yaml, urdf/NAME.urdf)
    length_cells: int = 30         # the field's extent along the way (+x), cells
    width_cells: int = 30          # across it (between the side walls), cells
    cell_m: float = 0.15           # m, a cell's side (a post's diameter)
    goal_distance: float = 10.0    # m, start to goal along +x
    margin: float = 0.05           # m, kept round the footprint along the guaranteed way

    def check(self):
        def bad(name, expected):
            raise BarnError('%s: expected %s, got %r' % (name, expected, getattr(self, name)))
        for name, low, high in (('seed', 0, 2 ** 31), ('smoothing', 0, 10), ('length_cells', 5, 200),
                                ('width_cells', 5, 200)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                bad(name, 'a whole number from %d to %d' % (low, high))
        for name, low, high in (('fill', 0.0, 0.9), ('cell_m', 0.05, 1.0), ('goal_distance', 3.0, 100.0),
                                ('margin', 0.0, 0.5)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
                bad(name, 'a number from %g to %g' % (low, high))
        field_end = (FIELD_START_CELLS + self.length_cells) * self.cell_m
        if field_end + 1.0 > self.goal_distance:
            bad('goal_distance', 'at least 1 m beyond the field (which ends %.2f m from the start)' % field_end)
        return self


def automaton(settings, rng):
    """The field (length_cells, width_cells) bool, row along +x, column along +y: random fill, then smoothing."""
    s = settings
    field = rng.uniform(0.0, 1.0, (s.length_cells, s.width_cells)) < s.fill
    for _ in range(s.smoothing):
        padded = numpy.pad(field, ((1, 1), (0, 0)), constant_values=False)
        padded = numpy.pad(padded, ((0, 0), (1, 1)), constant_values=True)
        neighbours = sum(padded[1 + di:1 + di + s.length_cells, 1 + dj:1 + dj + s.width_cells].astype(int)
                         for di in (-1, 0, 1) for dj in (-1, 0, 1) if di or dj)
        field = numpy.where(field, neighbours >= SURVIVAL, neighbours >= BIRTH)
    return field


class Layout:
    """Where a field's cells stand in the world, and the lattice over the whole way (a metre behind the start
    to a metre past the goal, wall to wall), whose cell centres are the world's points (j - j0, i - i0) x
    ``step``: the start and every post's centre on one."""

    def __init__(self, settings):
        s = settings
        self.settings = s
        self.half_width = 0.5 * s.width_cells * s.cell_m
        self.step = s.cell_m / LATTICE_PER_CELL
        self.field_start = FIELD_START_CELLS * s.cell_m
        self.i0 = LATTICE_PER_CELL * s.width_cells // 2           # y = 0 (the start's row)
        self.j0 = int(math.ceil(1.0 / self.step))                   # x = 0
        self.rows = LATTICE_PER_CELL * s.width_cells + 1
        self.cols = self.j0 + int(math.ceil((s.goal_distance + 1.0) / self.step)) + 1

    def post_centre(self, row, column):
        """The world (x, y) of field cell (row along +x, column along +y)."""
        s = self.settings
        return self.field_start + (row + 0.5) * s.cell_m, -self.half_width + (column + 0.5) * s.cell_m

    def lattice_cell(self, x, y):
        """(row, column) of the lattice cell whose centre is nearest (x, y)."""
        return int(round(y / self.step)) + self.i0, int(round(x / self.step)) + self.j0

    def lattice_centre(self, row, column):
        return (column - self.j0) * self.step, (row - self.i0) * self.step

    def occupancy(self, field):
        """(rows, cols) bool: the lattice cells holding a post's centre."""
        grid = numpy.zeros((self.rows, self.cols), bool)
        rows, columns = numpy.nonzero(field)
        # post_centre and lattice_cell for every post at once (numpy rounds halves to even, as round does).
        x = self.field_start + (rows + 0.5) * self.settings.cell_m
        y = -self.half_width + (columns + 0.5) * self.settings.cell_m
        grid[numpy.round(y / self.step).astype(numpy.intp) + self.i0,
             numpy.round(x / self.step).astype(numpy.intp) + self.j0] = True
        return grid

    def lattice(self, field, profile):
        """(the :class:`closed_loop.sim.lattice.FootprintLattice` of ``field`` for ``profile``'s footprint, the row
        offset of this layout's rows in it): the side walls are a row of occupied cells beyond each side."""
        grid = numpy.pad(self.occupancy(field), ((1, 1), (0, 0)), constant_values=True)
        return FootprintLattice(grid, self.step, profile.footprint, self.settings.margin,
                                0.5 * self.settings.cell_m), 1

    def start_state(self, offset):
        row, col = self.lattice_cell(0.0, 0.0)
        return row + offset, col, 0

    def goal_mask(self, offset, radius_m=0.2):
        """The lattice cells within ``radius_m`` of the goal."""
        ys = (numpy.arange(self.rows + 2 * offset) - offset - self.i0) * self.step
        xs = (numpy.arange(self.cols) - self.j0) * self.step
        return numpy.hypot(xs[None, :] - self.settings.goal_distance, ys[:, None]) <= radius_m


def field_with_way(settings, profile):
    """(field, attempt): the first field drawn from (seed, attempt) the robot can cross."""
    layout = Layout(settings)
    for attempt in range(MAX_ATTEMPTS):
        field = automaton(settings, numpy.random.default_rng([settings.seed, attempt]))
        lattice, offset = layout.lattice(field, profile)
        if lattice.reachable(layout.start_state(offset), layout.goal_mask(offset)):
            return field, attempt
    raise BarnError('fill: no field of %d attempts (seed %d, fill %.2f, smoothing %d) leaves a way for %s; '
                    'expected a lower fill' % (MAX_ATTEMPTS, settings.seed, settings.fill, settings.smoothing,
                                               settings.profile))


def generate(settings, profile=None):
    """The world (a dict in the world-file format) for ``settings``; ``profile``: a loaded
    :class:`closed_loop.sim.profiles.Profile` (default: ``settings.profile``)."""
    s = settings.check()
    profile = profile or load_profile(s.profile)
    field, attempt = field_with_way(s, profile)
    return world_from_field(s, field, attempt)


def world_from_field(settings, field, attempt=0):
    """The world dict of a field of posts."""
    s = settings
    layout = Layout(s)
    obstacles = []
    for r, c in zip(*numpy.nonzero(field)):
        x, y = layout.post_centre(r, c)
        obstacles.append({'name': 'post_%d_%d' % (r, c), 'type': 'cylinder',
                          'position': [round(float(x), 4), round(float(y), 4)], 'radius': round(0.5 * s.cell_m, 4),
                          'height': POST_HEIGHT_M, 'color': 'grey'})
    # Four walls round the whole way (a metre behind the start to a metre past the goal): nothing to go round.
    x0, x1 = -1.0 - 0.5 * WALL_THICKNESS_M, s.goal_distance + 1.0 + 0.5 * WALL_THICKNESS_M
    y1 = layout.half_width + 0.5 * WALL_THICKNESS_M
    for name, start, end in (('wall_left', [x0, y1], [x1, y1]), ('wall_right', [x0, -y1], [x1, -y1]),
                             ('wall_back', [x0, -y1], [x0, y1]), ('wall_front', [x1, -y1], [x1, y1])):
        obstacles.append({'name': name, 'type': 'wall', 'start': start, 'end': end,
                          'thickness': WALL_THICKNESS_M, 'height': POST_HEIGHT_M, 'color': 'white'})
    return {
        'name': 'barn_%s_f%03d_m%d_s%d' % (s.profile, int(round(s.fill * 100)), s.smoothing, s.seed),
        'description': 'BARN-method field: %d posts on %d x %d cells of %g m (fill %.2f, %d smoothing rounds, '
                       'attempt %d), goal (%g, 0), a way for %s + %g m'
                       % (int(field.sum()), s.length_cells, s.width_cells, s.cell_m, s.fill, s.smoothing, attempt,
                          s.goal_distance, s.profile, s.margin),
        'robot': {'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}},
        'goal': {'x': float(s.goal_distance), 'y': 0.0},
        'obstacles': obstacles,
    }


def field_of_world(settings, world):
    """The field (bool) of a world this module made, read back from its posts' names."""
    field = numpy.zeros((settings.length_cells, settings.width_cells), bool)
    for ob in world['obstacles']:
        if ob['name'].startswith('post_'):
            _, r, c = ob['name'].split('_')
            field[int(r), int(c)] = True
    return field


def has_way(settings, field, profile, margin_m):
    """True if the footprint grown by ``margin_m`` (not the settings' margin) can get from the start to the
    goal of ``field`` on the lattice: whether a robot keeping that much room can cross this world at all."""
    layout = Layout(dataclasses.replace(settings, margin=margin_m))
    lattice, offset = layout.lattice(field, profile)
    return lattice.reachable(layout.start_state(offset), layout.goal_mask(offset))


def way_length(settings, field, profile):
    """(m, [(x, y, yaw), ...]): the shortest way for the footprint from the start to the goal on the lattice."""
    layout = Layout(settings)
    lattice, offset = layout.lattice(field, profile)
    length, states = lattice.shortest(layout.start_state(offset), layout.goal_mask(offset))
    poses = []
    for i, j, k in states:
        x, y = layout.lattice_centre(i - offset, j)
        poses.append((x, y, k * math.pi / 4))
    return length, poses
