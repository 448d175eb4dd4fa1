"""The BARN benchmark's score of a run (the challenge's harness, since February 2024), for a world made by
``closed_loop.sim.barn``:

    score = success x OT / clip(T, 2 OT, 8 OT), at most 0.5

- OT, the optimal time: the world's path (the start, then the path through the grid the world is made from,
  then the goal), its length at OPTIMAL_SPEED_MPS. The benchmark's path is the A* path its generator saved,
  through the grid of cells with the obstacles grown by the Jackal's half-width in whole cells, 8 neighbours,
  never between two occupied cells that share a corner; here the shortest such path (:func:`path_m`), from the
  start to a free cell of the field's first row, through the field, from a free cell of its last row to the
  goal (the generator's own A* also turns at most 45 degrees a step and keeps off the walls, so its paths run a
  little longer: an OT here is a little shorter, and a score a little lower, than the harness would give).
- T: from when the robot is 0.1 m from its start until it is within 1 m of the goal (the judge's
  ``benchmark_time_s``), at most TIME_LIMIT_S.
- success: within 1 m of the goal in time, with no contact.

Free of ROS.
"""
import functools
import heapq
import math

import numpy

from closed_loop.sim import barn
from closed_loop.sim.profiles import load_profile

OPTIMAL_SPEED_MPS = 2.0
TIME_LIMIT_S = 100.0
#: The most the score can be: OT / 2 OT.
BEST = 0.5


def path_m(settings, field, half_width_m):
    """The length (m) of the world's path (the module's docstring) for a robot ``half_width_m`` wide each side;
    with the obstacles grown by fewer cells where that leaves no path (none: inf)."""
    layout = barn.Layout(settings)
    cell = settings.cell_m
    for grow in range(int(math.ceil(half_width_m / cell - 1e-9)), -1, -1):
        length = _shortest(_grown(field, grow), cell, layout, settings.goal_distance)
        if math.isfinite(length):
            return length
    return math.inf


def _grown(field, cells):
    """``field`` (rows along +x, columns along +y) with each occupied cell grown by ``cells`` each way."""
    if cells <= 0:
        return field.copy()
    padded = numpy.pad(field, cells)
    grown = numpy.zeros_like(field)
    rows, cols = field.shape
    for dr in range(-cells, cells + 1):
        for dc in range(-cells, cells + 1):
            grown |= padded[cells + dr:cells + dr + rows, cells + dc:cells + dc + cols]
    return grown


def _shortest(blocked, cell, layout, goal_x):
    """Dijkstra over the free cells of ``blocked``: from the start (0, 0) straight to any free cell of the first
    row, 8 neighbours (a diagonal step not between two blocked cells), from any free cell of the last row
    straight to the goal (``goal_x``, 0)."""
    rows, cols = blocked.shape
    centre = [[layout.post_centre(r, c) for c in range(cols)] for r in range(rows)]
    best = numpy.full(blocked.shape, math.inf)
    queue = []
    for c in range(cols):
        if not blocked[0, c]:
            best[0, c] = math.hypot(*centre[0][c])
            heapq.heappush(queue, (best[0, c], 0, c))
    total = math.inf
    while queue:
        cost, r, c = heapq.heappop(queue)
        if cost > best[r, c] or cost >= total:
            continue
        if r == rows - 1:
            total = min(total, cost + math.hypot(goal_x - centre[r][c][0], centre[r][c][1]))
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                nr, nc = r + dr, c + dc
                if (dr or dc) and 0 <= nr < rows and 0 <= nc < cols and not blocked[nr, nc] \
                        and not (dr and dc and blocked[r + dr, c] and blocked[r, c + dc]):
                    step = cost + cell * (math.sqrt(2.0) if dr and dc else 1.0)
                    if step < best[nr, nc]:
                        best[nr, nc] = step
                        heapq.heappush(queue, (step, nr, nc))
    return total


@functools.lru_cache(maxsize=1024)
def optimal_s(settings):
    """OT (s) of the world ``settings`` (a ``barn.BarnSettings``) makes (its field drawn for the footprint of
    its ``profile``, as ``barn.generate`` draws it)."""
    profile = load_profile(settings.profile)
    field, _ = barn.field_with_way(settings, profile)
    footprint = profile.footprint
    return path_m(settings, field, 0.5 * (footprint.y_max - footprint.y_min)) / OPTIMAL_SPEED_MPS


def score(contacts, time_s, optimal):
    """The score of a run with ``contacts`` and the benchmark's time ``time_s`` (None: never within 1 m of the
    goal) in a world whose OT is ``optimal`` (s)."""
    if contacts or time_s is None or time_s > TIME_LIMIT_S or not math.isfinite(optimal):
        return 0.0
    return optimal / min(max(time_s, 2.0 * optimal), 8.0 * optimal)
