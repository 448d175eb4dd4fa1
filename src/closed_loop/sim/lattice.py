"""Where a robot's footprint rectangle can go on a grid, heading first: the configuration space of a
differential-drive robot at 8 headings (every 45 degrees), for the world generator's guarantee
(``closed_loop.sim.barn``) and a world's shortest footprint-feasible path (the benchmark's optimal time).

The model, exact on its lattice:

- the grid's occupied cells hold obstacles reaching ``obstacle_radius_m`` round their centres (a post
  standing on the cell);
- the robot stands on a cell's centre at one of 8 headings; it is free there when no occupied cell's centre
  comes within ``obstacle_radius_m`` of its rectangle grown by ``margin_m``;
- it moves one cell along its heading, forward or back (a diagonal heading: one diagonal step), between two
  free states at that heading: the rectangle translated along its own axis by less than its length sweeps
  exactly the union of the two;
- it turns in place by 45 degrees where the rectangle is free at every angle between the two headings (the
  sweep is the union of the rectangle at sub-steps of ``SWEEP_STEP_RAD``).

So it passes a gap narrower than its turning circle, aligned first, and turns only where it has room. Free
of ROS; numpy and OpenCV.
"""
import collections
import functools
import heapq
import math

import cv2
import numpy

HEADINGS = 8
#: Lattice step (row, column) of heading k (k x 45 degrees from +x, counter-clockwise; rows are +y).
STEPS = ((0, 1), (1, 1), (1, 0), (1, -1), (0, -1), (-1, -1), (-1, 0), (-1, 1))
#: The turn between two neighbouring headings is checked at this angular spacing (rad).
SWEEP_STEP_RAD = math.radians(3.0)


@functools.lru_cache(maxsize=256)
def _kernel(cell_m, rect, radius_m, angles):
    """uint8 kernel and anchor (x, y) of the offsets whose cell centre comes within ``radius_m`` of the
    rectangle ``rect`` (x_min, x_max, y_min, y_max, m, in the robot's frame) at any of ``angles`` (a tuple);
    made once for given values (a world generator builds a lattice for each field it draws), read-only."""
    reach = math.hypot(max(-rect[0], rect[1]), max(-rect[2], rect[3])) + radius_m
    n = int(math.ceil(reach / cell_m)) + 1
    offsets = numpy.arange(-n, n + 1) * cell_m
    dx, dy = numpy.meshgrid(offsets, offsets)          # dy along rows
    inside = numpy.zeros(dx.shape, bool)
    for angle in angles:
        c, s = math.cos(angle), math.sin(angle)
        lx, ly = c * dx + s * dy, -s * dx + c * dy       # the offset in the robot's frame
        gx = numpy.maximum(numpy.maximum(rect[0] - lx, lx - rect[1]), 0.0)
        gy = numpy.maximum(numpy.maximum(rect[2] - ly, ly - rect[3]), 0.0)
        inside |= numpy.hypot(gx, gy) <= radius_m
    kernel = inside.astype(numpy.uint8)
    kernel.flags.writeable = False
    return kernel, (n, n)


def _shift(array, di, dj):
    """``array`` moved by (di, dj) cells (out[i + di, j + dj] = array[i, j]), False where nothing moved in."""
    out = numpy.zeros_like(array)
    h, w = array.shape
    out[max(di, 0):h + min(di, 0), max(dj, 0):w + min(dj, 0)] = \
        array[max(-di, 0):h + min(-di, 0), max(-dj, 0):w + min(-dj, 0)]
    return out


class FootprintLattice:
    """The free states of a footprint on an occupancy grid.

    ``occupied``: (rows, columns) bool, row i at y = y0 + (i + 0.5) cell, column j at x = x0 + (j + 0.5) cell;
    ``footprint``: the robot's rectangle (x_min, x_max, y_min, y_max attributes, m, about base_footprint);
    ``margin_m``: room kept beyond it; ``obstacle_radius_m``: how far round an occupied cell's centre its
    obstacle reaches. ``free[k]``: (rows, columns) bool, the robot free at heading k; ``turn[k]``: free to turn
    in place between headings k and k + 1."""

    def __init__(self, occupied, cell_m, footprint, margin_m, obstacle_radius_m):
        self.cell_m = cell_m
        rect = (footprint.x_min - margin_m, footprint.x_max + margin_m, footprint.y_min - margin_m,
                footprint.y_max + margin_m)
        grid = numpy.asarray(occupied, bool).astype(numpy.uint8)
        self.shape = grid.shape

        def blocked(angles):
            kernel, anchor = _kernel(cell_m, rect, obstacle_radius_m, tuple(float(a) for a in angles))
            # dilate: out(c) = max over the kernel's offsets o of grid(c + o), the grid read as if outside
            # were open; the world's own walls close what must be closed.
            return cv2.dilate(grid, kernel, anchor=anchor, borderType=cv2.BORDER_CONSTANT, borderValue=0) > 0
        quarter = math.pi / 4
        self.free = numpy.stack([~blocked([k * quarter]) for k in range(HEADINGS)])
        subs = max(2, int(math.ceil(quarter / SWEEP_STEP_RAD)))
        self.turn = numpy.stack([~blocked(numpy.linspace(k * quarter, (k + 1) * quarter, subs + 1))
                                 for k in range(HEADINGS)])

    def _moves(self, reached):
        """The states one move from ``reached`` ((HEADINGS, rows, columns) bool), free ones only."""
        out = numpy.zeros_like(reached)
        for k, (di, dj) in enumerate(STEPS):
            out[k] = (_shift(reached[k], di, dj) | _shift(reached[k], -di, -dj))
        left = numpy.roll(reached & self.turn, 1, axis=0)                       # k -> k + 1
        right = numpy.roll(reached, -1, axis=0) & self.turn                      # k + 1 -> k
        return (out | left | right) & self.free

    def reachable(self, start, goal):
        """True if the robot can go from ``start`` ((row, column, heading)) to any cell where ``goal`` ((rows,
        columns) bool) is True, at any heading."""
        i, j, k = start
        if not self.free[k, i, j]:
            return False
        goal = numpy.asarray(goal, bool)
        # Every move joins 8-neighbour cells free at some heading, so where no 8-connected chain of such cells joins
        # the start to a goal cell there is no way (one call; most fields a generator draws again end here).
        labels = cv2.connectedComponents(self.free.any(axis=0).astype(numpy.uint8), connectivity=8)[1]
        if not (labels[goal] == labels[i, j]).any():
            return False
        reached = numpy.zeros(self.free.shape, bool)
        reached[k, i, j] = True
        front = reached
        while front.any():
            if (reached & goal[None]).any():
                return True
            front = self._moves(front) & ~reached
            reached |= front
        return bool((reached & goal[None]).any())

    def shortest(self, start, goal):
        """(length m, [(row, column, heading), ...]) of the shortest way, by distance travelled (turning in place
        costs none), from ``start`` to a ``goal`` cell; (inf, []) when there is none.

        A* over the states, toward a lower bound on the way left (the straight line to the nearest goal cell), and
        on until every state no farther than the shortest way is settled: the costs the walk back reads are then
        those of a relaxation to convergence over every state, to the bit (each state's least sum of steps,
        added along its way), at a small part of the cost."""
        i, j, k = start
        inf = math.inf
        goal = numpy.asarray(goal, bool)
        if not self.free[k, i, j] or not goal.any():
            return inf, []
        lengths = [self.cell_m * math.hypot(di, dj) for di, dj in STEPS]
        # Shaded down a little, so that rounding never lifts the bound above a real way's length.
        left = (cv2.distanceTransform((~goal).astype(numpy.uint8), cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
                * (self.cell_m * 0.999)).astype(float).tolist()
        free, turn, at_goal = self.free.tolist(), self.turn.tolist(), goal.tolist()
        rows, cols = self.shape
        settled = {(k, i, j): 0.0}
        heap = [(left[i][j], 0.0, k, i, j)]
        best = inf
        while heap:
            bound, cost, k, i, j = heapq.heappop(heap)
            if bound > best:
                break
            if cost > settled[(k, i, j)]:
                continue
            if at_goal[i][j] and cost < best:
                best = cost
            di, dj = STEPS[k]
            up, down = (k + 1) % HEADINGS, (k - 1) % HEADINGS
            moves = [(cost + lengths[k], k, ni, nj) for ni, nj in ((i + di, j + dj), (i - di, j - dj))
                     if 0 <= ni < rows and 0 <= nj < cols and free[k][ni][nj]]
            if turn[k][i][j] and free[up][i][j]:
                moves.append((cost, up, i, j))
            if turn[down][i][j] and free[down][i][j]:
                moves.append((cost, down, i, j))
            for then, nk, ni, nj in moves:
                if then < settled.get((nk, ni, nj), inf):
                    settled[(nk, ni, nj)] = then
                    heapq.heappush(heap, (then + left[ni][nj], then, nk, ni, nj))
        costs = numpy.full(self.free.shape, inf)
        for state, cost in settled.items():
            costs[state] = cost
        ends = numpy.where(goal[None], costs, inf)
        end = numpy.unravel_index(int(numpy.argmin(ends)), costs.shape)
        if not numpy.isfinite(ends[end]):
            return inf, []
        return float(ends[end]), self._walk_back(costs, end, (start[2], start[0], start[1]), lengths)

    def _walk_back(self, cost, end, start, lengths):
        """The states from ``start`` to ``end`` ((heading, row, column)), down ``cost``: at each cell, the turns in
        place at no cost to a heading that came there by a step (or is the start), then that step back."""
        path = [end]
        k, i, j = end
        rows, cols = self.shape
        while (k, i, j) != start:
            here = cost[k, i, j]
            parent = {k: None}                     # the headings one turn after another at the same cost
            queue = collections.deque([k])
            while queue:
                h = queue.popleft()
                for nh, ok in (((h - 1) % HEADINGS, self.turn[(h - 1) % HEADINGS, i, j]),
                               ((h + 1) % HEADINGS, self.turn[h, i, j])):
                    if ok and nh not in parent and cost[nh, i, j] == here:
                        parent[nh] = h
                        queue.append(nh)
            found = None
            for h in parent:
                if (h, i, j) == start:
                    found = (h, None)
                    break
                di, dj = STEPS[h]
                for si, sj in ((-di, -dj), (di, dj)):
                    pi, pj = i + si, j + sj
                    if 0 <= pi < rows and 0 <= pj < cols and abs(cost[h, pi, pj] + lengths[h] - here) < 1e-9:
                        found = (h, (h, pi, pj))
                        break
                if found is not None:
                    break
            if found is None:
                break
            h, step = found
            turns = []
            while h != k:
                turns.append((h, i, j))
                h = parent[h]
            path.extend(reversed(turns))
            if step is None:
                break
            path.append(step)
            k, i, j = step
        return [(i, j, k) for k, i, j in reversed(path)]
