"""The escape's search, compiled (numba), for ``closed_loop.control.navigation.escape``: a hybrid A* for a rectangular
footprint over a distance field, with moves the robot can follow one at a time (a short run straight or on an
arc, forward or back, or a turn in place), each checked at several poses along it.

States are binned by position (``bin_m``) and heading (``HEADINGS`` a turn), so a state reached again at a
higher cost is not searched again; each keeps the exact pose the moves reached it at. The cost is the length
driven (an arc a little more than straight, backing more than forward, a turn in place its own cost), the
estimate the straight-line distance to the target. In Python a search took up to seconds; here it takes
milliseconds.

Compiled by numba (``closed_loop.compiled``). Free of ROS.
"""
import heapq
import math

import numpy

from closed_loop.compiled import jit

#: Headings a turn: a turn in place, or an arc over one move, changes the heading by one of them.
HEADINGS = 32
#: Length of a move straight or on an arc (m).
MOVE_M = 0.1
#: Poses checked along each move, its end included.
SAMPLES = 4
#: Costs: an arc's length counts this much more than a straight run's, a move back this much more than the
#: same move forward; a turn in place by one heading costs as much as this length (m).
ARC_COST = 1.1
BACK_COST = 1.5
TURN_COST_M = 0.06

#: The moves: (direction +1 forward, -1 back, 0 a turn in place; heading change in headings over the move).
MOVES = numpy.array([(1, 0), (-1, 0), (1, 1), (1, -1), (-1, 1), (-1, -1), (0, 1), (0, -1)], numpy.int64)


@jit
def pose_along(x, y, yaw, direction, turn, fraction):
    """The pose ``fraction`` of the way along a move from (x, y, yaw)."""
    step = 2.0 * math.pi / HEADINGS
    if direction == 0:
        return x, y, yaw + turn * step * fraction
    s = direction * MOVE_M * fraction
    if turn == 0:
        return x + s * math.cos(yaw), y + s * math.sin(yaw), yaw
    k = turn * step / MOVE_M
    end = yaw + k * s
    return x + (math.sin(end) - math.sin(yaw)) / k, y - (math.cos(end) - math.cos(yaw)) / k, end


@jit
def _at(field, cell_m, origin_x, origin_y, x, y):
    rows, cols = field.shape
    j = int(math.floor((x - origin_x) / cell_m + 0.5))
    i = int(math.floor((y - origin_y) / cell_m + 0.5))
    return field[i, j] if 0 <= i < rows and 0 <= j < cols else 1.0


@jit
def keeps(field, cell_m, origin_x, origin_y, outline_x, outline_y, inner_m, outer_m, spread_m, x, y, yaw, need):
    """True if the footprint at (x, y, yaw) keeps ``need`` (m) of ``field``'s obstacles: at once where the field
    at its centre reads at least ``outer_m`` (its farthest corner) more, or (reads off by up to ``spread_m``)
    less than ``inner_m`` (the nearest edge) more; else read under its outline."""
    centre = _at(field, cell_m, origin_x, origin_y, x, y)
    if centre >= outer_m + need:
        return True
    if centre + spread_m < inner_m + need:
        return False
    return clearance_at(field, cell_m, origin_x, origin_y, outline_x, outline_y, x, y, yaw) >= need


@jit
def clearance_at(field, cell_m, origin_x, origin_y, outline_x, outline_y, x, y, yaw):
    """The least of ``field`` (m) under the footprint's outline at pose (x, y, yaw); 1.0 off the field."""
    rows, cols = field.shape
    c, s = math.cos(yaw), math.sin(yaw)
    least = 1.0
    for n in range(outline_x.shape[0]):
        px = x + c * outline_x[n] - s * outline_y[n]
        py = y + s * outline_x[n] + c * outline_y[n]
        j = int(math.floor((px - origin_x) / cell_m + 0.5))
        i = int(math.floor((py - origin_y) / cell_m + 0.5))
        if 0 <= i < rows and 0 <= j < cols and field[i, j] < least:
            least = field[i, j]
    return least


@jit
def _key(x, y, yaw, sx, sy, bin_m, half, width):
    """The state's index: its position's bin about the start (sx, sy), and its heading's."""
    i = int(math.floor((y - sy) / bin_m + 0.5)) + half
    j = int(math.floor((x - sx) / bin_m + 0.5)) + half
    k = int(math.floor(yaw / (2.0 * math.pi / HEADINGS) + 0.5)) % HEADINGS
    return (i * width + j) * HEADINGS + k


@jit
def _keep(poses, k, x, y, yaw, move):
    poses[k, 0], poses[k, 1], poses[k, 2], poses[k, 3] = x, y, yaw, move


@jit
def search(field, cell_m, origin_x, origin_y, outline_x, outline_y, inner_m, outer_m, spread_m, start, target,
           goal_radius_m, margin_m, start_margin_m, start_radius_m, reach_m, bin_m, max_expanded):
    """Poses (N, 4) from ``start`` (x, y, yaw) to within ``goal_radius_m`` of ``target`` (x, y): x, y, yaw and
    the index in ``MOVES`` of the move that reached each (-1 for the start); (0, 4) when no way is found within
    ``max_expanded`` states. ``field``: (rows, columns) clearance (m) from the nearest obstacle, cell (0, 0)
    centred at (``origin_x``, ``origin_y``). Every pose checked along a move keeps ``margin_m`` of it, or
    ``start_margin_m`` within ``start_radius_m`` of the start (where the robot may already be closer); no
    move ends farther than ``reach_m`` from the start. ``inner_m``, ``outer_m``, ``spread_m``: as
    :func:`keeps`'s."""
    half = int(math.ceil(reach_m / bin_m)) + 1
    width = 2 * half + 1
    total = width * width * HEADINGS
    cost = numpy.full(total, numpy.inf)
    parent = numpy.full(total, -1, numpy.int64)
    poses = numpy.zeros((total, 4))
    sx, sy, syaw = start[0], start[1], start[2]

    first = _key(sx, sy, syaw, sx, sy, bin_m, half, width)
    cost[first] = 0.0
    _keep(poses, first, sx, sy, syaw, -1.0)
    heap = [(math.hypot(target[0] - sx, target[1] - sy), 0.0, first)]
    expanded = 0
    found = -1
    while len(heap) and expanded < max_expanded:
        _, g, k = heapq.heappop(heap)
        if g > cost[k]:
            continue
        x, y, yaw = poses[k, 0], poses[k, 1], poses[k, 2]
        if math.hypot(target[0] - x, target[1] - y) <= goal_radius_m:
            found = k
            break
        expanded += 1
        for m in range(MOVES.shape[0]):
            direction, turn = MOVES[m, 0], MOVES[m, 1]
            ok = True
            ex, ey, eyaw = x, y, yaw
            for n in range(1, SAMPLES + 1):
                ex, ey, eyaw = pose_along(x, y, yaw, direction, turn, n / SAMPLES)
                need = start_margin_m if math.hypot(ex - sx, ey - sy) <= start_radius_m else margin_m
                if not keeps(field, cell_m, origin_x, origin_y, outline_x, outline_y, inner_m, outer_m, spread_m,
                             ex, ey, eyaw, need):
                    ok = False
                    break
            if not ok or math.hypot(ex - sx, ey - sy) > reach_m:
                continue
            if direction == 0:
                added = TURN_COST_M
            else:
                added = MOVE_M * (ARC_COST if turn != 0 else 1.0) * (BACK_COST if direction < 0 else 1.0)
            e = _key(ex, ey, eyaw, sx, sy, bin_m, half, width)
            if g + added < cost[e]:
                cost[e] = g + added
                parent[e] = k
                _keep(poses, e, ex, ey, math.atan2(math.sin(eyaw), math.cos(eyaw)), m)
                heapq.heappush(heap, (g + added + math.hypot(target[0] - ex, target[1] - ey), g + added, e))
    if found < 0:
        return numpy.zeros((0, 4))
    count = 0
    k = found
    while k >= 0:
        count += 1
        k = parent[k]
    out = numpy.zeros((count, 4))
    k = found
    for n in range(count - 1, -1, -1):
        out[n, :] = poses[k, :]
        k = parent[k]
    return out
