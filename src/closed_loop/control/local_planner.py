"""The reactive navigator's local planner: a dynamic window over (v, w), each candidate's path predicted and
checked against the scan with the robot's footprint rectangle, the safe ones scored toward the goal. Its
settings and the states on top are in ``closed_loop.control.navigator``.

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
footprint's outline (``closed_loop.control.clearance_field``), so a decision costs a few milliseconds at 720 rays (``make bench``). Free
of ROS.
"""
import dataclasses
import functools
import importlib
import math

import numpy

from closed_loop.control import wavefront
from closed_loop.control.clearance_field import (FIELD_ERROR_M, OUTLINE_STEP_M, DistanceField, clearances, edge_clearance,
                                         keeps_margin, outline32)
from closed_loop.control import safety
from closed_loop.control.scan import scan_points
from closed_loop.control.safety import footprint_clearance, keeps_room, point_clearances
from closed_loop.control.scan_memory import BLIND_EXTRA_M, blind_points

#: Step between predicted poses (s): between two poses an obstacle point cannot slip through more than the
#: margin allows.
PREDICTION_STEP_S = 0.1
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
#: bring a side the scan does not see closer (a Jackal's rear corner crept into a post at 0.03 rad/s).
WITHIN_MARGIN_OPEN_M = 0.003
#: With a corridor (no goal), this near (m) to where its line is closed off, the robot stops: blocked.
BLOCKED_STOP_M = 0.3
#: Following the way where the window would stand: turn in place toward the aim while it lies more than
#: PURSUIT_TURN_RAD to a side (at the first of PURSUIT_TURN_RADPS that keeps the margin), else drive an arc
#: through it at the first of PURSUIT_SPEEDS (x max_speed) that does.
PURSUIT_TURN_RAD = 0.3
PURSUIT_KEEP_RAD = 1.5
PURSUIT_TURN_RADPS = (0.8, 0.4)
PURSUIT_SPEEDS = (0.5, 0.25, 0.125)
#: Candidates per axis of the window.
LINEAR_SAMPLES = 5
ANGULAR_SAMPLES = 15


class NavigatorError(ValueError):
    """Unusable input to the planner (a bad pose, goal or speed)."""


@dataclasses.dataclass(frozen=True)
class Plan:
    """The planner's answer: the command (m/s, rad/s), what it is and why, the chosen path's least
    clearance (m), the predicted poses of the chosen command ((K, 3) x, y, yaw in the robot's frame), and
    every candidate's (v, w, clearance, safe), the point aimed at and the way to the goal it lies on
    (``closed_loop.control.wavefront.Way``, None where the scan showed none), for display."""
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


def predict(v0, w0, v, w, settings, horizon_s, steps, step_s=PREDICTION_STEP_S):
    """Poses (C, K, 3) float32 for candidates ``v``, ``w`` (C,) from (v0, w0): ``safety.predict`` at the
    settings' accelerations (``accel``, ``yaw_accel``)."""
    return safety.predict(v0, w0, v, w, settings.accel, settings.yaw_accel, horizon_s, steps, step_s)


def prepare():
    """The planner's compiled parts (``arc_kernel``, the way's ``wave_kernel``, the navigator's escape's
    ``hybrid_kernel``) loaded, and compiled on a machine's first use (a few seconds), before a decision asks
    for them: a controller calls it as it is made, so its first decision is not the one that waits."""
    wavefront.prepare()
    importlib.import_module('closed_loop.control.escape').prepare()
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


def _pursue(aim_xy, near, footprint, v0, w0, s, steps, turning=0.0):
    """Toward ``aim_xy`` (the robot's frame) along the way, heading first: a turn in place while it lies more
    than PURSUIT_TURN_RAD to a side, else an arc through it at the fastest of PURSUIT_SPEEDS (x
    ``max_speed``) whose path keeps the margin (``safety.keeps_room``); (v, w, predicted poses, their clearance, why),
    or None when none keeps it. ``turning``: the side (+1 left, -1 right) of a turn in place at the last
    decision, which goes on while the aim lies more than PURSUIT_KEEP_RAD to the other side (an aim that
    swings between ahead and behind from one scan to the next would turn the robot back and forth)."""
    distance, bearing = math.hypot(*aim_xy), math.atan2(aim_xy[1], aim_xy[0])
    if abs(bearing) > PURSUIT_TURN_RAD:
        side = turning if turning and abs(bearing) > PURSUIT_KEEP_RAD else math.copysign(1.0, bearing)
        options = [(0.0, side * min(s.max_yaw_rate, rate)) for rate in PURSUIT_TURN_RADPS]
        why = 'turning in place toward the way round (%.2f rad off)' % bearing
    else:
        curvature = 2.0 * aim_xy[1] / max(distance ** 2, 1e-9)
        options = [(f * s.max_speed, max(-s.max_yaw_rate, min(s.max_yaw_rate, f * s.max_speed * curvature)))
                   for f in PURSUIT_SPEEDS]
        why = 'following the way round %.2f m to its aim' % distance
    for v, w in options:
        poses = predict(v0, w0, numpy.array([v]), numpy.array([w]), s, s.horizon, steps)[0]
        safe, clearance = keeps_room(near, footprint, poses, required_margin(s, max(v, abs(v0))))
        if safe:
            return v, w, poses, clearance, why
    return None


def required_margin(settings, speed):
    """The clearance (m) a path driven at ``speed`` (m/s, the faster of the command's and the robot's) must
    keep: ``safety_margin`` at rest, ``margin_per_speed`` more per m/s (a base at speed strays farther
    from the predicted arc: a skid-steer one turns less than its wheels say)."""
    return settings.safety_margin + settings.margin_per_speed * abs(speed)


def check_finite(name, *values):
    for value in values:
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            raise NavigatorError('%s: expected finite numbers, got %r' % (name, values))


def step_toward(target, previous, measured, rate, period_s, limit):
    """One period's step of a speed toward ``target``, at most ``rate`` x ``period_s``, from the command
    sent last (``previous``; None: the ``measured`` speed), and never more than that step above the
    measured speed in magnitude, nor beyond +-``limit``.

    From the measured speed alone, a base that overshoots its command (a skid-steer one, in a turn) would
    be sent ever more of it; the magnitude bound keeps a base held back (stopped by a watchdog) from
    being sent a jump the plan did not predict."""
    step = rate * period_s
    base = measured if previous is None else previous
    value = min(max(target, base - step), base + step)
    reach = min(abs(measured) + step, limit)
    return float(min(max(value, -reach), reach))


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


def plan(scan, laser_pose, footprint, v0, w0, goal_xy, settings, remembered=None, turning=0.0, scanned=None,
         previous=None, corridor=None, closed=None, kept_way=None, follow=False):
    """The command for now: a :class:`Plan`.

    ``scan``: a :class:`closed_loop.control.scan.Scan` (REP 117); ``laser_pose``: the laser's pose in the base
    frame (:class:`closed_loop.geometry.Pose2D`); ``footprint``: the robot's rectangle; ``v0``,
    ``w0``: the robot's speeds now (m/s, rad/s); ``goal_xy``: the goal in the robot's frame (m);
    ``remembered``: (M, 2) points of earlier scans in the robot's frame (``closed_loop.control.scan_memory``), used
    to choose the way around, and for safety only where the scanner cannot see now; ``turning``: +1 or -1 while the last decision was a
    turn in place that way (it goes on that way rather than swing back and forth between two ways
    round), 0 otherwise; ``scanned``: the scan's points in the robot's frame if already computed;
    ``previous``: the command sent last (m/s, rad/s), which the step is taken from; ``corridor``: where
    the way round may go (``closed_loop.control.wavefront.aim``'s), None for anywhere; ``closed``: points
    (M, 2, the robot's frame) the way keeps off as it does the scan's (places closed to it), never for safety;
    ``kept_way``: (N, 2) the way followed until now, in the robot's frame (``closed_loop.control.wavefront.way``'s
    ``kept``); ``follow``: where the window would stand or turn in place, follow the way instead, heading first
    (the navigator asks this once it has made no progress for a while).
    """
    check_finite('v0, w0', v0, w0)
    check_finite('goal_xy', *goal_xy)
    s = settings
    scanned = scan_points(scan, laser_pose) if scanned is None else scanned
    # Where the scanner cannot see (behind a LIDAR of less than a full turn), what was seen there before
    # is the best knowledge there is: remembered points in that blind sector count for safety too, so a
    # turn does not swing the robot's back into something it saw a moment ago.
    blind = blind_points(remembered, scan, laser_pose) if remembered is not None and len(remembered) else scanned[:0]
    points = numpy.concatenate((scanned, blind)) if len(blind) else scanned
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

    goal_distance = math.hypot(*goal_xy)
    # What the arcs are scored toward: a point along the way to the goal through the free space the scan
    # shows (closed_loop.control.wavefront), else through what the newest scan alone shows (SCAN_WAY_ROOM_M),
    # or the goal itself when neither shows one.
    half_width = 0.5 * (footprint.y_max - footprint.y_min) + s.safety_margin + AIM_ROOM_M
    seen = numpy.concatenate([scanned] + [extra for extra in (remembered, closed) if extra is not None and len(extra)])
    way = wavefront.way(seen, goal_xy, half_width, max(1.0, s.max_speed * s.lookahead),
                        0.5 * (footprint.y_max - footprint.y_min), corridor, kept_way)
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
            return Plan(0.0, 0.0, 'stop', why, now, numpy.zeros((1, 3)), candidates, tuple(aim_xy), way=way)
        if way.aim == way.goal:
            aim_xy = goal_xy
    if not (safe | maybe).any():
        return Plan(0.0, 0.0, 'stop', 'no safe command: every path comes within %.2f m of an obstacle '
                    '(safety_margin %.2f m)' % (max(float(clear.max()), 0.0), s.safety_margin),
                    now, numpy.zeros((1, 3)), candidates, tuple(aim_xy), way=way)
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
    best = _confirm(score, safe, maybe, near, footprint, safe_poses, margin)
    candidates[:, 3] = safe
    if best is None:
        return Plan(0.0, 0.0, 'stop', 'no safe command: every path comes within %.2f m of an obstacle '
                    '(safety_margin %.2f m)' % (max(float(clear.max()), 0.0), s.safety_margin),
                    now, numpy.zeros((1, 3)), candidates, tuple(aim_xy), way=way)
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
    followed = None
    if follow and v[best] == 0.0 and way is not None and now >= s.safety_margin:
        # The window would stand or turn in place, yet a way is there: follow it, heading first (a narrow gap
        # scores low on room for every arc through it, however the way leads there).
        followed = _pursue(aim_xy, near, footprint, v0, w0, s, safe_steps, turning)
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
