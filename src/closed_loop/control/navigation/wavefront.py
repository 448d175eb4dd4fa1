"""Which way around: a navigation function over the newest scan, for the local planner's aim.

The dynamic window (``closed_loop.control.navigation.window``) judges commands over a couple of seconds; alone, it
steers toward the goal's bearing and can wander into a pocket that the goal's direction leads into. So the
aim it scores toward is not the goal itself but a point about ``aim_m`` along the shortest way to the goal
through the free space the scan shows (Brock and Khatib's global dynamic window, 1999, with the scan as
the map):

- a grid of ``CELL_M`` cells over the box around the robot and the goal (plus ``BOX_MARGIN_M``; a goal
  beyond ``MAX_BOX_M`` is brought in along its bearing, to the box's edge);
- a cell is passable when it is at least the robot's half-width plus the margin from every scan point (so
  a gap narrower than the robot plus its margins is closed; space the scan does not see counts as free);
- a breadth-first wave from the goal over passable cells, alternating 4- and 8-neighbour steps, which
  gives the octagonal distance (within 8% of the Euclidean), stopped once it has covered the robot;
- from the robot (or the passable cell nearest to it, within ``START_SEARCH_M``) down the wave, up to
  ``aim_m``, as far as the way stays in a straight line of sight of the robot through passable cells;
  where the straight line to the goal is passable all the way, that line is the way (no wave), and the
  aim is on it exactly. The grid is placed with the robot at a cell's centre.

The way followed at the last decision is kept while it stays open and not much longer than the shortest
(``kept``): where two ways are about as short, each new scan would otherwise swing the aim between them.

A ``corridor`` (a line through the goal, and a half-width) closes every cell farther from the line than
that, and where the goal cannot be reached within it, the goal moves back along the line to the farthest
point that can: the navigator with no goal goes round what stands on its line, and up to a wall across the
whole way, not round it.

No way through (the scan shows the goal closed off) leaves the goal as the aim; the state machine above
handles a robot that gets nowhere. Free of ROS.
"""
import collections
import importlib
import math

import cv2
import numpy

CELL_M = 0.1
FINE = 2
BOX_MARGIN_M = 3.0
MAX_BOX_M = 20.0
START_SEARCH_M = 0.8
#: A wave that has not reached the robot within this length of way (m, rounds of CELL_M) finds no way.
WAVE_REACH_M = 50.0
WAVE_ROUNDS = int(round(WAVE_REACH_M / CELL_M))
#: A way kept from the last decision stays the way while it is at most KEEP_LONGER x the shortest + KEEP_EXTRA_M.
KEEP_LONGER = 1.1
KEEP_EXTRA_M = 0.5
#: The wave's rounds to the start, times CELL_M and this, is at least the shortest way's length (alternating
#: 4- and 8-neighbour steps make the octagonal distance, at most 8% short of the Euclidean).
OCTAGONAL_M = 1.08
#: No sight asked of the way down the wave (``wave_kernel.descend``).
_ANY = numpy.zeros((0, 0), bool)

#: What :func:`way` found: the point to steer for, and the goal the way leads to (the goal given, or the
#: point a corridor's line is closed off at), both (x, y) in the robot's frame; ``route()``: the whole way
#: as (N, 2) points there, from the robot to that goal (worked out only when asked: a display's).
Way = collections.namedtuple('Way', 'aim goal route')


def _box(goal_xy):
    """(x0, y0, columns, rows) of the grid around the robot (the origin) and the goal, capped."""
    gx, gy = goal_xy
    distance = math.hypot(gx, gy)
    reach = MAX_BOX_M - 2 * BOX_MARGIN_M
    if distance > reach:
        gx, gy = gx * reach / distance, gy * reach / distance
    x0, x1 = min(0.0, gx) - BOX_MARGIN_M, max(0.0, gx) + BOX_MARGIN_M
    y0, y1 = min(0.0, gy) - BOX_MARGIN_M, max(0.0, gy) + BOX_MARGIN_M
    # Moved out to where the robot is at a cell's centre, so the way starts where the robot is.
    x0, y0 = -CELL_M * (math.ceil(-x0 / CELL_M) + 0.5), -CELL_M * (math.ceil(-y0 / CELL_M) + 0.5)
    return x0, y0, int(math.ceil((x1 - x0) / CELL_M)), int(math.ceil((y1 - y0) / CELL_M)), (gx, gy)


def aim(points, goal_xy, half_width_m, aim_m, sight_m=None, corridor=None):
    """The point (x, y) in the robot's frame to steer for, or None when the points show no way to the goal
    (:func:`way`'s ``aim``)."""
    found = way(points, goal_xy, half_width_m, aim_m, sight_m, corridor)
    return None if found is None else found.aim


def way(points, goal_xy, half_width_m, aim_m, sight_m=None, corridor=None, kept=None):
    """The :class:`Way` to the goal, or None when the points show none.

    ``points``: (N, 2) obstacle points in the robot's frame (the scan's, and those remembered of recent
    scans); ``goal_xy``: the goal there; ``half_width_m``: how far a passable cell must be from every
    point (the robot's half-width plus the margin); ``sight_m``: the room a straight line to the aim must
    keep (default ``half_width_m``; the robot's half-width alone lets the aim round a corner the way
    itself keeps the margin from); ``corridor``: ((x, y) a point of a line through the goal, (dx, dy) its
    unit direction, half-width m), all in the robot's frame: the way stays within the half-width of that
    line, to the goal or, if it is closed off, to the farthest point of the line before it that is not;
    ``kept``: (N, 2) the way followed until now (its ``route()`` at the last decision, in the robot's frame
    now, ending at the goal): it stays the way while all of it from the point nearest the robot on is still
    passable and it is at most KEEP_LONGER x the shortest way + KEEP_EXTRA_M (where two ways are about as
    short, a small change in the points would otherwise swing the robot from one to the other and back)."""
    x0, y0, cols, rows, (gx, gy) = _box(goal_xy)
    # The room at each cell's centre, read from a distance transform FINE times finer (accurate to a fine
    # cell's half-diagonal, where the coarse grid alone would be off by up to 0.14 m).
    fine = CELL_M / FINE
    occupied = numpy.full((rows * FINE, cols * FINE), 255, numpy.uint8)
    if len(points):
        j = ((points[:, 0] - x0) / fine).astype(numpy.intp)
        i = ((points[:, 1] - y0) / fine).astype(numpy.intp)
        inside = (i >= 0) & (i < rows * FINE) & (j >= 0) & (j < cols * FINE)
        occupied[i[inside], j[inside]] = 0
    # A 5x5 mask is within 2% of the exact distance, at a third of the cost; the aim is guidance, not safety.
    room = cv2.distanceTransform(occupied, cv2.DIST_L2, cv2.DIST_MASK_5)[FINE // 2::FINE, FINE // 2::FINE]
    passable = room * fine >= half_width_m
    if corridor is not None:
        (px, py), (dx, dy), half = corridor
        xs = x0 + (numpy.arange(cols) + 0.5) * CELL_M - px
        ys = y0 + (numpy.arange(rows) + 0.5) * CELL_M - py
        passable &= numpy.abs(dx * ys[:, None] - dy * xs[None, :]) <= half
    in_sight = passable if sight_m is None else room * fine >= sight_m
    goal_cell = (int((gy - y0) / CELL_M), int((gx - x0) / CELL_M))
    here = (int(-y0 / CELL_M), int(-x0 / CELL_M))
    start = _nearest_passable(passable, here)
    if start is None:
        return None
    if corridor is not None:
        cell, point = _farthest_on_line(passable, start, corridor, (x0, y0), (gx, gy))
        if cell is None:
            return None
        if cell != goal_cell:
            goal_cell, (gx, gy) = cell, point
            goal_xy = (gx, gy)
            if _in_sight(in_sight, start, cell):
                # Straight up to where the line is closed off.
                return Way(goal_xy, goal_xy, lambda: numpy.array([(0.0, 0.0), goal_xy]))
    if not passable[goal_cell]:
        return None
    goal = goal_xy if math.hypot(*goal_xy) <= MAX_BOX_M - 2 * BOX_MARGIN_M else (gx, gy)
    if start == here and _in_sight(passable, start, goal_cell):
        # The straight line is the way: the aim is on it, exactly (not at a cell's centre).
        scale = min(1.0, aim_m / max(math.hypot(*goal), 1e-9))
        return Way((goal[0] * scale, goal[1] * scale), tuple(goal), lambda: numpy.array([(0.0, 0.0), tuple(goal)]))
    # The wave (compiled: ``wave_kernel``), from the goal's cell until it reaches the start's.
    kernel = _kernel()
    k, steps = kernel.wave(passable, start, goal_cell, WAVE_ROUNDS)
    if k < 0:
        return None
    if kept is not None and corridor is None:
        followed = _follow(kept, goal, passable, in_sight, start, (x0, y0), aim_m,
                           KEEP_LONGER * OCTAGONAL_M * CELL_M * k + KEEP_EXTRA_M)
        if followed is not None:
            return followed
    # Down the wave from the start, aim_m of path. The aim is the farthest point of the way in sight of the
    # start through passable cells: steering for a point beyond a bend would cut the corner into what the
    # way goes round.
    last = kernel.descend(steps, start, goal_cell, CELL_M, aim_m, in_sight)[-1]
    centre = (lambda cell: (x0 + (int(cell[1]) + 0.5) * CELL_M, y0 + (int(cell[0]) + 0.5) * CELL_M))
    route = (lambda: _route([centre(cell) for cell in kernel.descend(steps, start, goal_cell, CELL_M, math.inf,
                                                                      _ANY)], goal))
    if steps[last[0], last[1]] == 0:
        return Way(tuple(goal), tuple(goal), route)
    return Way(centre(last), tuple(goal), route)


def _follow(kept, goal, passable, in_sight, start, origin, aim_m, longest_m):
    """The :class:`Way` along ``kept`` ((N, 2) points, the robot's frame) from its point nearest the robot, if
    it still ends at ``goal``, every cell it crosses from there is passable and it is at most ``longest_m``
    long; else None."""
    kept = numpy.asarray(kept, float)
    if len(kept) < 2 or math.hypot(kept[-1][0] - goal[0], kept[-1][1] - goal[1]) > 0.5 * CELL_M:
        return None
    segments = kept[1:] - kept[:-1]
    lengths = numpy.hypot(segments[:, 0], segments[:, 1])
    # The point of each segment nearest the robot (the origin); the way goes on from the nearest of them.
    t = numpy.clip(-(kept[:-1] * segments).sum(axis=1) / numpy.maximum(lengths ** 2, 1e-12), 0.0, 1.0)
    foot = kept[:-1] + t[:, None] * segments
    n = int(numpy.argmin(numpy.hypot(foot[:, 0], foot[:, 1])))
    ahead = numpy.concatenate(([foot[n]], kept[n + 1:]))
    along = numpy.concatenate(([0.0], numpy.cumsum(numpy.hypot(*numpy.diff(ahead, axis=0).T))))
    if along[-1] > longest_m:
        return None
    # Samples half a cell apart along it, each read in the grid.
    at = numpy.arange(0.0, along[-1], 0.5 * CELL_M)
    samples = numpy.column_stack((numpy.interp(at, along, ahead[:, 0]), numpy.interp(at, along, ahead[:, 1])))
    x0, y0 = origin
    rows, cols = passable.shape
    i = ((samples[:, 1] - y0) / CELL_M).astype(numpy.intp)
    j = ((samples[:, 0] - x0) / CELL_M).astype(numpy.intp)
    if (i < 0).any() or (i >= rows).any() or (j < 0).any() or (j >= cols).any() or not passable[i, j].all():
        return None
    aim_xy = tuple(ahead[-1])
    for index in numpy.nonzero(at <= aim_m)[0][::-1]:
        if _in_sight(in_sight, start, (int(i[index]), int(j[index]))):
            aim_xy = tuple(samples[index]) if at[index] < along[-1] else aim_xy
            break
    route = numpy.concatenate(([(0.0, 0.0)], ahead))
    return Way((float(aim_xy[0]), float(aim_xy[1])), tuple(kept[-1]), lambda: route)


def _route(points, goal):
    """(N, 2): the robot (the origin), the cells' centres down the wave and the goal exactly."""
    return numpy.array([(0.0, 0.0)] + points[1:-1] + [tuple(goal)])


def _farthest_on_line(passable, start, corridor, origin, goal_xy):
    """The cell and the point (x, y) of the goal, or of the farthest point before it on the corridor's line
    (from the robot's projection on it) that passable cells connect to ``start``; (None, None) if none
    does."""
    (px, py), (dx, dy), _ = corridor
    x0, y0 = origin
    rows, cols = passable.shape
    _, labels = cv2.connectedComponents(passable.astype(numpy.uint8), connectivity=8)
    region = labels[start]
    along = (goal_xy[0] - px) * dx + (goal_xy[1] - py) * dy
    nearest = -(px * dx + py * dy)        # the robot's projection on the line
    for t in numpy.arange(along, min(nearest, along) - 1e-9, -0.5 * CELL_M):
        i, j = int((py + t * dy - y0) / CELL_M), int((px + t * dx - x0) / CELL_M)
        if 0 <= i < rows and 0 <= j < cols and passable[i, j] and labels[i, j] == region:
            return (i, j), (float(px + t * dx), float(py + t * dy))
    return None, None


def _in_sight(passable, a, b):
    """True if every cell on the straight line from cell ``a`` to cell ``b`` is passable."""
    return _kernel().in_sight(passable, a, b)


def prepare():
    """The compiled wave loaded (and compiled, on a machine's first use: about a second) before the first way is
    asked for: a controller calls it as it is made, so its first decision is not the one that waits."""
    passable = numpy.ones((1, 2), bool)
    kernel = _kernel()
    k, steps = kernel.wave(passable, (0, 0), (0, 1), WAVE_ROUNDS)
    kernel.descend(steps, (0, 0), (0, 1), CELL_M, math.inf, passable)
    kernel.in_sight(passable, (0, 0), (0, 1))


def _kernel():
    """The compiled wave (``wave_kernel``), imported with the first way asked for: numba costs a process about
    0.1 s and 60 MB, which a sweep's own process (that imports the controllers) need not pay."""
    return importlib.import_module('closed_loop.control.navigation.wave_kernel')


def _nearest_passable(passable, cell):
    """The passable cell nearest to ``cell`` within START_SEARCH_M, or None."""
    i, j = cell
    if 0 <= i < passable.shape[0] and 0 <= j < passable.shape[1] and passable[i, j]:
        return cell
    reach = int(math.ceil(START_SEARCH_M / CELL_M))
    rows, cols = passable.shape
    best = None
    for di in range(-reach, reach + 1):
        for dj in range(-reach, reach + 1):
            ni, nj = i + di, j + dj
            if 0 <= ni < rows and 0 <= nj < cols and passable[ni, nj]:
                d = di * di + dj * dj
                if best is None or d < best[0]:
                    best = (d, (ni, nj))
    return None if best is None else best[1]
