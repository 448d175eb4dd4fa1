"""The navigator's escape from a pocket (``closed_loop.control.navigation.navigator``): after ESCAPE_AFTER_S without
progress, a plan for the robot's footprint, heading first, over what it sees and remembers, to a point
ESCAPE_AIM_M along the way it was following (``closed_loop.control.navigation.hybrid_kernel``'s search: short moves
straight or on arcs, forward or back, and turns in place), followed one command at a time at SPEED_MPS (slower
on an arc that asks a faster turn than MAX_TURN_RADPS). Each command is checked exactly
(``closed_loop.control.navigation.move_check``) before it is sent, and slower where it is not safe (FALL_BACKS); a plan whose
next move is not safe for BLOCKED_S is dropped, and the next is asked for RETRY_S later.
Free of ROS.
"""
import importlib
import math

import cv2
import numpy

from closed_loop.control.navigation.clearance_field import outline
from closed_loop.control.loop import lasted, outlasted

#: Plan an escape once the robot has made no progress for this long (s), and again this long (s) after a plan
#: ends, is dropped or none was found.
ESCAPE_AFTER_S = 10.0
RETRY_S = 3.0
#: The plan's target: this far (m) along the way followed (or toward the goal), reached within GOAL_RADIUS_M.
ESCAPE_AIM_M = 2.0
GOAL_RADIUS_M = 0.3
#: The plan keeps the safety margin and this much more from what it knows; where the robot already stands
#: closer, it may start within START_RADIUS_M of where it stands no closer than it is, less this much.
PLAN_ROOM_M = 0.005
START_RADIUS_M = 0.15
#: Search limits: no move ends farther (m) than this from the start, and at most this many states are searched.
REACH_M = 2.5
MAX_EXPANDED = 20000
#: The distance field's cell (m), the search's position bins (m), the footprint outline's sample spacing (m);
#: the doubts on what is remembered where the scan cannot see are rounded up to DOUBT_STEP_M.
GRID_M = 0.01
DOUBT_STEP_M = 0.02
BIN_M = 0.05
OUTLINE_M = 0.03
#: Following: forward or back at this speed (m/s), turning in place at TURN_GAIN x the heading error between
#: these rates (rad/s); a move's heading held with HEADING_GAIN and its line with CROSS_GAIN (rad/s per m). A
#: move that asks a turn faster than MAX_TURN_RADPS (or the robot's limit, if lower) is driven slower on the
#: same arc (the plan's tightest arcs, ``hybrid_kernel``'s, ask less than that at SPEED_MPS).
SPEED_MPS = 0.4
MAX_TURN_RADPS = 1.0
TURN_GAIN = 1.5
TURN_RADPS = (0.25, 0.5)
HEADING_GAIN = 1.5
CROSS_GAIN = 3.0
#: A heading error this large (rad) on a move is turned away in place first; a turn in place is done within
#: TURN_DONE_RAD, or within NEAR_ENOUGH_RAD where the rest of it is not safe.
REALIGN_RAD = 0.5
TURN_DONE_RAD = 0.06
NEAR_ENOUGH_RAD = 0.2
#: A plan whose next move is not safe for this long (s) is dropped; one the robot has strayed from (its next
#: pose farther than a move and this, m) is dropped, and another asked for at once.
BLOCKED_S = 1.0
#: A move's command that is not safe is tried slower: (speed, turn rate) as fractions of it, in this order. A
#: turn slowed with the speed keeps the arc; slowed more, or none, keeps to the move's line rather than steer
#: back onto the plan (the check predicts the command's arc, which can swing a corner out where the plan's
#: poses keep the margin).
FALL_BACKS = ((1.0, 1.0), (0.5, 1.0), (0.25, 1.0), (0.5, 0.5), (0.25, 0.25), (0.25, 0.0))
OFF_PLAN_M = 0.1


def _kernel():
    return importlib.import_module('closed_loop.control.navigation.hybrid_kernel')


def _wrap(angle):
    return math.atan2(math.sin(angle), math.cos(angle))


def aim(route, goal_local):
    """Where to plan to, in the robot's frame: ESCAPE_AIM_M along ``route`` ((N, 2), the way followed, the
    robot's frame; None if none) from its point nearest the robot, or the goal if nearer, else toward the goal."""
    distance = math.hypot(*goal_local)
    if distance <= ESCAPE_AIM_M:
        return tuple(goal_local)
    if route is not None and len(route) >= 2:
        ahead = route[int(numpy.argmin(numpy.hypot(route[:, 0], route[:, 1]))):]
        along = numpy.concatenate(([0.0], numpy.cumsum(numpy.hypot(*numpy.diff(ahead, axis=0).T))))
        if along[-1] > 0:
            t = min(ESCAPE_AIM_M, along[-1])
            return float(numpy.interp(t, along, ahead[:, 0])), float(numpy.interp(t, along, ahead[:, 1]))
    return goal_local[0] * ESCAPE_AIM_M / distance, goal_local[1] * ESCAPE_AIM_M / distance


def _distances(points, start, n):
    """(2n + 1, 2n + 1): each GRID_M cell's distance (m) to the nearest of ``points`` (M, 2), read on the safe
    side (a point anywhere in its cell), cell (n, n) centred at ``start``."""
    size = 2 * n + 1
    free = numpy.full((size, size), 255, numpy.uint8)
    if len(points):
        j = numpy.floor((points[:, 0] - start[0]) / GRID_M + 0.5).astype(numpy.intp) + n
        i = numpy.floor((points[:, 1] - start[1]) / GRID_M + 0.5).astype(numpy.intp) + n
        inside = (i >= 0) & (i < size) & (j >= 0) & (j < size)
        free[i[inside], j[inside]] = 0
    return cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * GRID_M - GRID_M * math.sqrt(0.5)


def find_way(points, start, target, footprint, margin_m, doubtful=None, doubt=None):
    """Poses (N, 4) from ``start`` (x, y, yaw) to within GOAL_RADIUS_M of ``target`` (x, y), each with the index
    in ``hybrid_kernel.MOVES`` of the move that reached it, keeping ``margin_m`` of ``points`` (M, 2), and
    ``doubt`` (K,) m more of ``doubtful`` (K, 2) (what is remembered where the scan cannot see: the check of
    each command keeps it, ``move_check``), all in one frame; None if there is none within the search's
    limits."""
    kernel = _kernel()
    n = int(math.ceil((REACH_M + footprint.radius_m + margin_m) / GRID_M)) + 1
    field = _distances(points, start, n)
    if doubtful is not None and len(doubtful):
        # The doubts rounded up to DOUBT_STEP_M: one distance transform for each.
        levels = numpy.ceil(numpy.asarray(doubt) / DOUBT_STEP_M) * DOUBT_STEP_M
        for level in numpy.unique(levels):
            field = numpy.minimum(field, _distances(doubtful[levels == level], start, n) - level)
    shape = outline(footprint, OUTLINE_M)
    origin = start[0] - n * GRID_M, start[1] - n * GRID_M
    xs, ys = numpy.ascontiguousarray(shape[:, 0], float), numpy.ascontiguousarray(shape[:, 1], float)
    start = numpy.array(start, float)
    here = kernel.clearance_at(field, GRID_M, origin[0], origin[1], xs, ys, start[0], start[1], start[2])
    inner = min(-footprint.x_min, footprint.x_max, -footprint.y_min, footprint.y_max)
    poses = kernel.search(field, GRID_M, origin[0], origin[1], xs, ys, inner, footprint.radius_m,
                          GRID_M * math.sqrt(2.0), start, numpy.array(target, float),
                          GOAL_RADIUS_M, margin_m, min(margin_m, here - PLAN_ROOM_M), START_RADIUS_M, REACH_M, BIN_M,
                          MAX_EXPANDED)
    return poses if len(poses) >= 2 else None


def prepare():
    """The search loaded, and compiled on a machine's first use, before an escape asks for it
    (``window.prepare``)."""
    one = numpy.ones(1)
    _kernel().search(numpy.ones((3, 3)), 1.0, -1.0, -1.0, one, one, 0.5, 1.0, 0.0, numpy.zeros(3), numpy.ones(2),
                     0.1, 0.5, 0.5, 0.1, 1.0, 1.0, 10)


class Follower:
    """Follows a plan's poses (odom) one command at a time."""

    def __init__(self, poses):
        self.poses = poses[1:]
        self.index = 0
        self.strayed = False

    def turning(self):
        """The heading (rad, odom) the turn in place being followed ends at; None if the next move is not one."""
        if self.index >= len(self.poses) or self._move()[0] != 0:
            return None
        return self.poses[self.index][2]

    def _move(self):
        return _kernel().MOVES[int(self.poses[self.index][3])]

    def command(self, pose, limits=(SPEED_MPS, MAX_TURN_RADPS)):
        """(m/s, rad/s, why) toward the plan's next pose from ``pose`` (odom), within ``limits`` (the robot's top
        speed, m/s, and turn rate, rad/s); None once the plan is done, or the robot has strayed from it
        (``strayed``)."""
        x, y, yaw = pose
        while self.index < len(self.poses):
            tx, ty, tyaw = self.poses[self.index][:3]
            if math.hypot(tx - x, ty - y) > _kernel().MOVE_M + OFF_PLAN_M:
                self.strayed = True
                return None
            direction, turn = self._move()
            if direction == 0:
                error = _wrap(tyaw - yaw)
                if abs(error) < TURN_DONE_RAD:
                    self.index += 1
                    continue
                rate = math.copysign(min(TURN_RADPS[1], max(TURN_RADPS[0], TURN_GAIN * abs(error))), error)
                return 0.0, rate, 'escape: turning in place to the plan\'s heading'
            c, s = math.cos(tyaw), math.sin(tyaw)
            if ((tx - x) * c + (ty - y) * s) * direction < 0.01:
                self.index += 1
                continue
            cross, error = -(tx - x) * s + (ty - y) * c, _wrap(tyaw - yaw)
            if abs(error) > REALIGN_RAD:
                return 0.0, math.copysign(0.4, error), 'escape: turning back onto the plan'
            v = direction * min(SPEED_MPS, limits[0])
            curvature = turn * 2.0 * math.pi / _kernel().HEADINGS / _kernel().MOVE_M
            w = curvature * v + HEADING_GAIN * error + direction * CROSS_GAIN * cross
            top = min(MAX_TURN_RADPS, limits[1])
            if abs(w) > top:     # slower, on the same arc: where the robot goes is what counts
                v, w = v * top / abs(w), math.copysign(top, w)
            return v, w, 'escape: %s along the plan' % ('forward' if direction > 0 else 'back')
        return None


class Escape:
    """The escape's state: the plan followed, when its next move became unsafe, when to plan again."""

    def __init__(self):
        self.follower = None
        self.blocked_s = None
        self.next_try_s = None

    @property
    def active(self):
        return self.follower is not None

    def route(self):
        """The plan's way ahead, (N, 2) odom; None while none is followed."""
        return None if self.follower is None else self.follower.poses[self.follower.index:, :2]

    def due(self, now_s, stalled_s):
        """True while a plan is followed, or once one is to be asked for."""
        return self.active or (lasted(stalled_s, ESCAPE_AFTER_S) and (self.next_try_s is None or
                                                                      lasted(now_s - self.next_try_s, 0.0)))

    def command(self, now_s, pose, points, target, footprint, margin_m, check, horizon_s,
                limits=(SPEED_MPS, MAX_TURN_RADPS)):
        """(m/s, rad/s, why) for now, or None (the window decides), once :meth:`due`. ``points()``: (M, 2) what
        is seen and remembered, and (K, 2) what is remembered where the scan cannot see and (K,) its doubt (m)
        (odom); ``target``: (x, y) odom; ``check``: a ``move_check.MoveCheck`` for now; ``limits``: the robot's
        top speed (m/s) and turn rate (rad/s)."""
        if self.follower is None:
            self.next_try_s = now_s + RETRY_S
            seen, doubtful, doubt = points()
            poses = find_way(seen, pose, target, footprint, margin_m, doubtful, doubt)
            if poses is None:
                return None
            self.follower, self.blocked_s = Follower(poses), None
        while True:
            cmd = self.follower.command(pose, limits)
            if cmd is None:
                self.follower, self.next_try_s = None, now_s if self.follower.strayed else now_s + RETRY_S
                return None
            v, w, why = cmd
            for f, g in FALL_BACKS:
                if check.safe(v * f, w * g, horizon_s, max(abs(v * f), abs(check.v0))):
                    self.blocked_s = None
                    return v * f, w * g, why
                if v == 0.0:
                    break
            heading = self.follower.turning()
            if heading is None or abs(_wrap(heading - pose[2])) >= NEAR_ENOUGH_RAD:
                break
            self.follower.index += 1      # near enough the turn's heading: go on with the next move
        self.blocked_s = now_s if self.blocked_s is None else self.blocked_s
        if outlasted(now_s - self.blocked_s, BLOCKED_S):
            self.follower, self.next_try_s = None, now_s + RETRY_S
            return None
        return 0.0, 0.0, 'escape: the plan\'s next move does not keep the margin: waiting'
