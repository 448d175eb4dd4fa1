"""The reactive navigator's local planner: a dynamic window over (v, w), each candidate's path predicted and
checked against the scan with the robot's footprint rectangle, the safe ones scored toward the goal. Its
settings and the states on top are in ``closed_loop.control.navigation.navigator``.

Why a dynamic window (Fox, Burgard and Thrun 1997; ROS's dwa_local_planner): it plans in the robot's own
command space, so speed and acceleration limits hold by construction; it judges a command by the path the
robot would sweep, with its real rectangle, not a point or a disc, so it neither enters a gap narrower
than the robot nor cuts a corner; and it needs no map, only the newest scan. A gap-following or VFH+
histogram picks a direction and leaves the footprint to a margin; the window checks the footprint itself.

Safety: each candidate is followed for ``horizon`` seconds (a control period and the scan's delay, with room
to spare) and then braked to rest at the robot's deceleration; its clearance is the least distance between
the footprint, at every predicted pose, and any scan point. A command whose clearance comes under its
margin (``required_margin``: ``safety_margin``, and ``margin_per_speed`` more per m/s of its speed) is never
chosen (when the robot is already closer than the margin, only a turn in place that does not bring it
closer is). With no safe command it stops. Where the window would stand or turn in place while a way is
there (``follow``, which the navigator asks after a second without progress), it follows the way instead,
heading first: at a gap only a little wider than the robot, every arc through it keeps less room than
standing still, and the window alone would turn back and forth before it. Preference: each candidate is also
followed for ``lookahead`` seconds without braking, and scored on where that arc points (toward the goal),
how much room it keeps, how fast it goes, and how long it runs before it would come within the margin.
The robot re-plans every period, so the long arc is a preference, the short one a guarantee.

The clearance comes from a distance transform of the scan points on a local grid, read at points along the
footprint's outline (``clearance_field``), so a decision costs a few milliseconds at 720 rays (``make bench``).
What a decision knows comes in one :class:`closed_loop.control.navigation.situation.Situation`; :func:`plan` runs
the window's stages in order, each a function of its own. Free of ROS.
"""
import dataclasses
import functools
import importlib
import math

import numpy

from closed_loop.control.navigation import wavefront
from closed_loop.control.navigation.clearance_field import (FIELD_ERROR_M, OUTLINE_STEP_M, DistanceField, clearances,
                                                            edge_clearance, keeps_margin, outline32)
from closed_loop.control.navigation.memory import BLIND_EXTRA_M
from closed_loop.control.navigation.pursuit import pursue
from closed_loop.control.navigation.situation import (PREDICTION_STEP_S, check_finite, predict, step_toward)
from closed_loop.control.safety import footprint_clearance, keeps_room, point_clearances

#: Largest gap between samples of the footprint's outline on the longer arcs that are only scored (m).
PREFERENCE_OUTLINE_STEP_M = 0.2
#: Step between the poses of the longer arcs that are only scored (s).
PREFERENCE_STEP_S = 0.2
#: Clearance beyond which more room adds nothing to a command's score (m).
CLEARANCE_CAP_M = 1.0
#: The way to the aim must be this much wider (m, each side) than the robot plus its margins: a gap the
#: window could only just pass is not one to aim for.
AIM_ROOM_M = 0.02
#: Where the scan and what is remembered show no such way, the newest scan alone is asked for one with this much
#: room (m, each side) beyond the robot's half-width: remembered points are carried by odometry, which drifts,
#: and the places closed after getting stuck can shut the only way out. It guides the arcs only; every command
#: still keeps the margin from the scan and what is remembered where the scan cannot see.
SCAN_WAY_ROOM_M = 0.03
#: At most this many candidates in doubt are checked exactly per decision (each costs about 0.1 ms).
EXACT_CHECKS = 4
#: An aim more than this far (rad) to a side decides which way to turn in place.
AIM_SIDE_RAD = 0.2
#: Already within the margin, a turn in place must open the clearance by this much (m) by the time it is at
#: rest, not only keep it: judged on what the scan sees of an obstacle, a turn that keeps its clearance can
#: bring a side the scan does not see closer (a rear corner creeping round into a post).
WITHIN_MARGIN_OPEN_M = 0.003
#: With a corridor (no goal), this near (m) to where its line is closed off, the robot stops: blocked.
BLOCKED_STOP_M = 0.3
#: Candidates per axis of the window.
LINEAR_SAMPLES = 5
ANGULAR_SAMPLES = 15


@dataclasses.dataclass(frozen=True)
class Plan:
    """The planner's answer: the command (m/s, rad/s), what it is and why, the chosen path's least
    clearance (m), the predicted poses of the chosen command ((K, 3) x, y, yaw in the robot's frame), and
    every candidate's (v, w, clearance, safe), the point aimed at and the way to the goal it lies on
    (``closed_loop.control.navigation.wavefront.Way``, None where the scan showed none), for display."""
    linear_x: float
    angular_z: float
    kind: str          # 'goal' (heading for it), 'avoid' (steering around), 'turn' (in place), 'stop'
    reason: str
    clearance_m: float
    path: numpy.ndarray
    candidates: numpy.ndarray
    aim_xy: tuple = (0.0, 0.0)   # the point the arcs were scored toward (the robot's frame, m)
    target: tuple = (0.0, 0.0)   # the chosen candidate (m/s, rad/s), which the command steps toward
    way: object = None


def prepare():
    """The planner's compiled parts (``arc_kernel``, the way's ``wave_kernel``, the navigator's escape's
    ``hybrid_kernel``) loaded, and compiled on a machine's first use (a few seconds), before a decision asks
    for them: a controller calls it as it is made, so its first decision is not the one that waits."""
    wavefront.prepare()
    importlib.import_module('closed_loop.control.navigation.escape').prepare()
    kernel = importlib.import_module('closed_loop.control.arc_kernel')
    poses = kernel.predict(0.0, 0.0, numpy.zeros(1), numpy.zeros(1), 1.0, 1.0, 0.1, 1, 0.1)
    one, none = numpy.ones((1, 1), numpy.float32), numpy.zeros(1, numpy.float32)
    kernel.least_on_outline(none, 1, poses, one, one, none, none, numpy.float32(1.0), numpy.float32(0.5))


@functools.lru_cache(maxsize=8)
def candidate_speeds(max_speed, max_yaw_rate):
    """The window's candidates, (v, w) each (C,): LINEAR_SAMPLES speeds from 0 to ``max_speed`` by
    ANGULAR_SAMPLES turn rates over +-``max_yaw_rate``, closer together near zero (u|u| over -1..1), where a
    small heading error is corrected. Made once for given limits (read-only arrays)."""
    vs = numpy.linspace(0.0, max_speed, LINEAR_SAMPLES)
    u = numpy.linspace(-1.0, 1.0, ANGULAR_SAMPLES)
    ws = max_yaw_rate * u * numpy.abs(u)
    v, w = (a.ravel() for a in numpy.meshgrid(vs, ws))
    v.flags.writeable = w.flags.writeable = False
    return v, w


def _confirm(score, safe, maybe, near, footprint, poses, margin):
    """The best-scoring candidate that is safe: one the grid left in doubt (``maybe``) is checked exactly
    against the points and its ``margin`` (each candidate's), best first, at most EXACT_CHECKS of them;
    ``safe`` and ``score`` are updated.
    None when none is safe."""
    for _ in range(EXACT_CHECKS):
        best = int(numpy.argmax(score))
        if score[best] == -numpy.inf or safe[best]:
            break
        maybe[best] = False
        if keeps_margin(near, footprint, poses[best], float(margin[best])):
            safe[best] = True
        else:
            score[best] = -numpy.inf
    score[~safe] = -numpy.inf
    best = int(numpy.argmax(score))
    return best if safe[best] else None


@dataclasses.dataclass
class _Window:
    """The candidates of one decision and what is known of each (the arrays of :func:`_window`)."""
    v: numpy.ndarray
    w: numpy.ndarray
    clear: numpy.ndarray          # least clearance along each safety path (the grid's)
    margin: numpy.ndarray         # the margin each must keep
    safe: numpy.ndarray
    maybe: numpy.ndarray          # within the grid's error of its margin: checked exactly if it scores best
    safe_poses: numpy.ndarray     # followed for the horizon, then braked
    safe_steps: int
    arcs: numpy.ndarray           # followed for the lookahead (scored only)
    along: numpy.ndarray          # clearance along the arcs (the grid's)
    long_steps: int
    near: numpy.ndarray           # the points a path can come near
    now: float                    # the footprint's clearance now
    candidates: numpy.ndarray     # (v, w, clearance, safe), for display


def plan(situation, settings):
    """The command for now (a :class:`Plan`) in ``situation`` (a ``situation.Situation``), by the stages of the
    module's docstring: the candidates and their safety (:func:`_window`), what they are scored toward
    (:func:`_aim`), the score and the exact check of the best (:func:`_choose`), a turn in place instead of
    standing (:func:`_turn_instead`), following the way instead (``pursuit.pursue``), and one period's step
    toward the choice (:func:`_command`)."""
    sit, s = situation, settings
    check_finite('v0, w0', sit.v0, sit.w0)
    check_finite('goal_xy', *sit.goal_xy)
    scanned, blind, points = sit.points()
    win = _window(sit, s, points, blind)
    way, aim_xy, stop = _aim(sit, s, scanned, win)
    if stop is not None:
        return stop
    if not (win.safe | win.maybe).any():
        return _stop(win, s, aim_xy, way)
    best, free, heading = _choose(sit, s, win, aim_xy)
    if best is None:
        return _stop(win, s, aim_xy, way)
    best = _turn_instead(sit, win, best, free, aim_xy)
    followed = None
    if sit.follow and win.v[best] == 0.0 and way is not None and win.now >= s.safety_margin:
        # The window would stand or turn in place, yet a way is there: follow it, heading first (a narrow gap
        # scores low on room for every arc through it, however the way leads there).
        followed = pursue(aim_xy, win.near, sit.footprint, sit.v0, sit.w0, s, win.safe_steps, sit.turning)
    return _command(sit, s, win, best, free, heading, followed, aim_xy, way)


def _window(sit, s, points, blind):
    """The candidates over the whole speed range, each predicted with the ramp from the speeds now at the
    accelerations, followed for the horizon then braked (safety) and for the lookahead (preference); each one's
    clearance on the distance grid against its margin (``required_margin``), and within the margin already,
    the turns in place the rule allows."""
    footprint, v0, w0 = sit.footprint, sit.v0, sit.w0
    top_v, top_w = max(s.max_speed, abs(v0)), max(s.max_yaw_rate, abs(w0))
    # Followed for the horizon, then both speeds brake at once: at rest after the longer of the two.
    safe_steps = int(math.ceil((s.horizon + max(top_v / s.accel, top_w / s.yaw_accel)) / PREDICTION_STEP_S)) + 1
    long_steps = int(math.ceil(s.lookahead / PREFERENCE_STEP_S))
    radius = footprint.radius_m
    longest_s = max(safe_steps * PREDICTION_STEP_S, long_steps * PREFERENCE_STEP_S)
    reach = top_v * longest_s + radius + CLEARANCE_CAP_M
    near = points[numpy.hypot(points[:, 0], points[:, 1]) <= reach] if len(points) else points
    field = DistanceField(near, reach)
    shape = outline32(footprint, OUTLINE_STEP_M)
    coarse = outline32(footprint, PREFERENCE_OUTLINE_STEP_M)

    # Candidates are targets over the whole speed range; each is predicted with the ramp from (v0, w0) at
    # the accelerations, and what is sent is the first period's step of that ramp (the dynamic window).
    v, w = candidate_speeds(s.max_speed, s.max_yaw_rate)
    safe_poses = predict(v0, w0, v, w, s, s.horizon, safe_steps)
    clear = clearances(field, shape, safe_poses, OUTLINE_STEP_M).min(axis=1)
    # Each candidate's margin grows with the faster of its speed and the speed now (required_margin).
    margin = s.safety_margin + s.margin_per_speed * numpy.maximum(v, abs(v0))
    safe = clear >= margin
    # The grid reads low by up to FIELD_ERROR_M: a candidate that reads that little short of the margin may
    # yet keep it, and is checked exactly if it scores best (below).
    maybe = ~safe & (clear >= margin - FIELD_ERROR_M)
    now = float(edge_clearance(field.at(shape).min(), OUTLINE_STEP_M))
    if now < s.safety_margin:
        now = footprint_clearance(near, footprint, 0.0, 0.0, 0.0)
    if now < s.safety_margin:
        # Already within the margin: only a turn in place that keeps the rule (``safety.keeps_room``: no point
        # within the margin closer, no other within it) and opens the clearance (WITHIN_MARGIN_OPEN_M), judged
        # exactly (the grid is too coarse to see a centimetre), and only while the robot is nearly at rest.
        maybe[:] = False
        for i in numpy.nonzero((v == 0.0) & ~safe)[0]:
            if abs(v0) < 0.05 and keeps_room(near, footprint, safe_poses[i], s.safety_margin)[0] and \
                    footprint_clearance(near, footprint, *safe_poses[i][-1]) >= now + WITHIN_MARGIN_OPEN_M:
                safe[i] = True
    # A turn in place keeps BLIND_EXTRA_M more from what it remembers where the scan cannot see (a back corner
    # swinging round through it).
    blind = blind[numpy.hypot(blind[:, 0], blind[:, 1]) <= radius + float(margin.max()) + BLIND_EXTRA_M]
    for i in numpy.nonzero((v == 0.0) & (w != 0.0) & (safe | maybe))[0] if len(blind) else ():
        if float(point_clearances(blind, footprint, safe_poses[i]).min()) < margin[i] + BLIND_EXTRA_M:
            safe[i] = maybe[i] = False
    arcs = predict(v0, w0, v, w, s, s.lookahead, long_steps, PREFERENCE_STEP_S)
    along = clearances(field, coarse, arcs, PREFERENCE_OUTLINE_STEP_M)
    candidates = numpy.column_stack((v, w, clear, safe))
    return _Window(v, w, clear, margin, safe, maybe, safe_poses, safe_steps, arcs, along, long_steps, near, now,
                   candidates)


def _aim(sit, s, scanned, win):
    """(the way, the point the arcs are scored toward, a stopping :class:`Plan` or None): a point along the way
    to the goal through the free space the scan shows (``wavefront``), else through what the newest scan alone
    shows (SCAN_WAY_ROOM_M), or the goal itself when neither shows one; with a corridor closed off ahead, a stop
    before it."""
    footprint, goal_xy, corridor = sit.footprint, sit.goal_xy, sit.corridor
    half_width = 0.5 * (footprint.y_max - footprint.y_min) + s.safety_margin + AIM_ROOM_M
    seen = numpy.concatenate([scanned] + [extra for extra in (sit.remembered, sit.closed)
                                          if extra is not None and len(extra)])
    way = wavefront.way(seen, goal_xy, half_width, max(1.0, s.max_speed * s.lookahead),
                        0.5 * (footprint.y_max - footprint.y_min), corridor, sit.kept_way)
    if way is None and corridor is None:
        way = wavefront.way(scanned, goal_xy, 0.5 * (footprint.y_max - footprint.y_min) + SCAN_WAY_ROOM_M,
                            max(1.0, s.max_speed * s.lookahead), 0.5 * (footprint.y_max - footprint.y_min))
    aim_xy = goal_xy if way is None else way.aim
    if corridor is not None and way is not None and way.goal != tuple(goal_xy):
        # The line is closed off within the corridor: go up to where, steering for the far point (which keeps
        # the heading; a near one would turn a small offset from the line into a large angle), and stop.
        if math.hypot(*way.goal) <= BLOCKED_STOP_M + 1e-9:     # the line's points are sums of half cells
            why = ('the way along the start heading is closed off %.2f m ahead (no way round within '
                   'hold_corridor): stopped before it' % math.hypot(*way.goal))
            return way, aim_xy, Plan(0.0, 0.0, 'stop', why, win.now, numpy.zeros((1, 3)), win.candidates,
                                     tuple(aim_xy), way=way)
        if way.aim == way.goal:
            aim_xy = goal_xy
    return way, aim_xy, None


def _stop(win, s, aim_xy, way):
    return Plan(0.0, 0.0, 'stop', 'no safe command: every path comes within %.2f m of an obstacle '
                '(safety_margin %.2f m)' % (max(float(win.clear.max()), 0.0), s.safety_margin),
                win.now, numpy.zeros((1, 3)), win.candidates, tuple(aim_xy), way=way)


def _choose(sit, s, win, aim_xy):
    """(the best candidate that is safe, or None; each one's free share of its arc; its heading toward the aim):
    each candidate scored on where its arc points (toward the aim), how much closer it gets, how much room it
    keeps and how fast it goes, for the free part of its arc; the best checked exactly where the grid doubts
    it (:func:`_confirm`)."""
    v, w, along, arcs, long_steps = win.v, win.w, win.along, win.arcs, win.long_steps
    safe, maybe = win.safe, win.maybe
    goal_distance = math.hypot(*sit.goal_xy)
    # How long each arc runs before it would come within the margin (1: the whole lookahead), and where its
    # free part comes closest to the goal (its end, unless it passes the goal): how far that is, how much
    # closer than now, pointing how well at the goal, with how much room around it.
    blocked = along < s.safety_margin - FIELD_ERROR_M / 2   # the grid's middle estimate: a preference only
    free_steps = numpy.where(blocked.any(axis=1), blocked.argmax(axis=1), long_steps)
    free = free_steps / long_steps
    reached = numpy.arange(long_steps)[None, :] < numpy.maximum(free_steps, 1)[:, None]
    to_aim = numpy.hypot(aim_xy[0] - arcs[..., 0], aim_xy[1] - arcs[..., 1])
    last = numpy.argmin(numpy.where(reached, to_aim, numpy.inf), axis=1)
    end = arcs[numpy.arange(len(v)), last]
    bearing = numpy.arctan2(aim_xy[1] - end[:, 1], aim_xy[0] - end[:, 0]) - end[:, 2]
    heading = 1.0 - numpy.abs(numpy.arctan2(numpy.sin(bearing), numpy.cos(bearing))) / math.pi
    progress = (math.hypot(*aim_xy) - to_aim[numpy.arange(len(v)), last]) / (s.max_speed * s.lookahead)
    room = numpy.minimum(numpy.where(reached, along, numpy.inf).min(axis=1), CLEARANCE_CAP_M) / CLEARANCE_CAP_M
    speed = v / s.max_speed
    # Near the goal, speed stops counting (no overshoot).
    if goal_distance < s.max_speed ** 2 / (2 * s.accel) + s.goal_tolerance:
        speed = speed * 0.0
    # An arc that runs into the margin counts for its free part only: the sooner, the less it is worth.
    score = (free * (s.heading_weight * heading + s.speed_weight * speed) + s.progress_weight * progress
             + s.clearance_weight * room)
    score = numpy.where(safe | maybe, score, -numpy.inf)
    best = _confirm(score, safe, maybe, win.near, sit.footprint, win.safe_poses, win.margin)
    win.candidates[:, 3] = safe
    return best, free, heading


def _turn_instead(sit, win, best, free, aim_xy):
    """``best``, or a turn in place where standing still beats every way forward."""
    v, w, safe, maybe, candidates = win.v, win.w, win.safe, win.maybe, win.candidates
    near, footprint, safe_poses, margin, turning = win.near, sit.footprint, win.safe_poses, win.margin, sit.turning
    turns = (safe | maybe) & (v == 0.0) & (w != 0.0)
    if v[best] == 0.0 and w[best] == 0.0 and turns.any() and (v > 0).any():
        # Standing still beats every way forward: turn in place rather than stand facing the obstacle,
        # toward the aim (the way round) when it lies to a side, else toward the side whose forward arcs
        # run freer; the fastest such turn the footprint can make, checked exactly if the grid doubts it.
        bearing = math.atan2(aim_xy[1], aim_xy[0])
        if turning:
            toward = turning
        elif abs(bearing) > AIM_SIDE_RAD:
            toward = math.copysign(1.0, bearing)
        else:
            left = free[(v > 0) & (w > 0)].max(initial=0.0)
            right = free[(v > 0) & (w < 0)].max(initial=0.0)
            toward = 1.0 if left >= right else -1.0
        order = sorted(numpy.nonzero(turns)[0], key=lambda i: (numpy.sign(w[i]) != toward, -abs(w[i])))
        for i in order[:EXACT_CHECKS]:
            if safe[i] or keeps_margin(near, footprint, safe_poses[i], float(margin[i])):
                safe[i] = candidates[i, 3] = True
                best = int(i)
                break
    return best


def _command(sit, s, win, best, free, heading, followed, aim_xy, way):
    """The :class:`Plan`: one period's step toward the choice (or the way followed), what it is and why."""
    v, w, safe, along, arcs, candidates = win.v, win.w, win.safe, win.along, win.arcs, win.candidates
    v0, w0, previous, goal_distance = sit.v0, sit.w0, sit.previous, math.hypot(*sit.goal_xy)
    # What is sent is one period's step toward the target (step_toward).
    period_s = 1.0 / s.rate_hz
    prev_v, prev_w = (None, None) if previous is None else previous
    if followed is not None:
        tv, tw, poses, clearance, why = followed
        vb = step_toward(tv, prev_v, v0, s.accel, period_s, s.max_speed)
        wb = step_toward(tw, prev_w, w0, s.yaw_accel, period_s, s.max_yaw_rate)
        return Plan(vb, wb, 'turn' if tv == 0.0 else 'avoid', why, clearance, poses, candidates, tuple(aim_xy),
                    (tv, tw), way)
    vb = step_toward(float(v[best]), prev_v, v0, s.accel, period_s, s.max_speed)
    wb = step_toward(float(w[best]), prev_w, w0, s.yaw_accel, period_s, s.max_yaw_rate)
    cb = float(along[best].min())
    # What a pure goal-seeker would do: the moving candidate pointing best at the goal, obstacles aside.
    moving = v > 0
    seek = int(numpy.argmax(numpy.where(moving, heading, -numpy.inf))) if moving.any() else best
    if v[best] == 0.0 and w[best] == 0.0:
        kind, why = 'stop', 'stopped: nothing safe beats standing still'
    elif v[best] == 0.0:
        kind, why = 'turn', 'turning in place (toward %.2f rad/s): no safe way forward' % w[best]
    elif not safe[seek] or free[seek] < 1.0 or cb < s.avoid_distance:
        kind, why = 'avoid', 'steering around an obstacle %.2f m from the path' % max(cb, 0.0)
    else:
        kind, why = 'goal', 'heading for the goal %.2f m away' % goal_distance
    return Plan(vb, wb, kind, why, cb, arcs[best], candidates, tuple(aim_xy), (float(v[best]), float(w[best])),
                way)
