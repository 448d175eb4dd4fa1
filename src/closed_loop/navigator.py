"""The reactive navigator's local planner: a dynamic window over (v, w), each candidate's path predicted and
checked against the scan with the robot's footprint rectangle, the safe ones scored toward the goal.

Why a dynamic window (Fox, Burgard and Thrun 1997; ROS's dwa_local_planner): it plans in the robot's own
command space, so speed and acceleration limits hold by construction; it judges a command by the path the
robot would sweep, with its real rectangle, not a point or a disc, so it neither enters a gap narrower
than the robot nor cuts a corner; and it needs no map, only the newest scan. A gap-following or VFH+
histogram picks a direction and leaves the footprint to a margin; the window checks the footprint itself.

Safety: each candidate is followed for ``horizon`` seconds (a control period and the scan's delay, with room
to spare) and then braked to rest at the robot's deceleration; its clearance is the least distance between
the footprint, at every predicted pose, and any scan point. A command whose clearance comes under
``safety_margin`` is never chosen (when the robot is already closer than the margin, only a turn in place
that does not bring it closer is). With no safe command it stops. Preference: each candidate is also
followed for ``lookahead`` seconds without braking, and scored on where that arc points (toward the goal),
how much room it keeps, how fast it goes, and how long it runs before it would come within the margin.
The robot re-plans every period, so the long arc is a preference, the short one a guarantee.

The clearance comes from a distance transform of the scan points on a local grid (OpenCV), read at points
along the footprint's outline, so a decision costs about a millisecond at 720 rays. Free of ROS.
"""
import dataclasses
import enum
import math

import cv2
import numpy

from closed_loop import robot_model
from closed_loop.guard import footprint_clearance, path_clearance, scan_points
from closed_loop.scan import sample_angles
from closed_loop.settings import MIN_RATE_HZ, SettingsError, param

#: Grid cell of the distance transform (m); clearances are read this much on the safe side.
GRID_CELL_M = 0.04
#: Step between predicted poses (s), and the largest gap between samples of the footprint's outline (m):
#: between two samples or two poses an obstacle point cannot slip through more than the margin allows.
PREDICTION_STEP_S = 0.1
OUTLINE_STEP_M = 0.05
#: Step between the poses of the longer arcs that are only scored (s).
PREFERENCE_STEP_S = 0.2
#: Clearance beyond which more room adds nothing to a command's score (m).
CLEARANCE_CAP_M = 1.0
#: Candidates per axis of the window.
LINEAR_SAMPLES = 5
ANGULAR_SAMPLES = 15


class NavigatorError(ValueError):
    """Unusable input to the planner (a bad pose, goal or speed)."""


@dataclasses.dataclass
class NavigatorSettings:
    """avoid_obstacles' ``~parameters``; the speed and acceleration limits come from the robot profile."""
    rate_hz: float = param(10.0, 'Hz', 'control timer rate (ROS clock)', minimum=MIN_RATE_HZ)
    scan_timeout: float = param(0.5, 's', 'stop when the newest scan (or odometry) is older than this',
                                minimum=0.0, maximum=5.0, exclusive_minimum=True)
    scan_frame: str = param(robot_model.SCAN_FRAME, '', "the laser's frame_id: scans in any other frame are "
                            'refused (stop)')
    max_speed: float = param(0.5, 'm/s', 'forward speed limit', minimum=0.0, exclusive_minimum=True, live=True)
    max_yaw_rate: float = param(1.5, 'rad/s', 'turn rate limit', minimum=0.0, exclusive_minimum=True, live=True)
    accel: float = param(1.0, 'm/s^2', 'linear acceleration and braking the plan counts on', minimum=0.05,
                         live=True)
    yaw_accel: float = param(3.0, 'rad/s^2', 'yaw acceleration the plan counts on', minimum=0.1, live=True)
    safety_margin: float = param(0.1, 'm', 'least clearance between the footprint and any scan point along '
                                 'a chosen path', minimum=0.05, maximum=1.0, live=True)
    avoid_distance: float = param(0.5, 'm', 'a chosen path closer than this to an obstacle (or a turn '
                                  'away from the goal) is AVOIDING', minimum=0.0, live=True)
    horizon: float = param(0.5, 's', 'safety: how long a candidate is assumed followed before braking '
                           '(control period, scan delay and room to spare)', minimum=0.1, maximum=3.0, live=True)
    lookahead: float = param(2.0, 's', 'preference: how far along each candidate arc is scored', minimum=0.5,
                             maximum=6.0, live=True)
    goal_tolerance: float = param(0.3, 'm', 'REACHED within this distance of the goal', minimum=0.05,
                                  live=True)
    hold_lookahead: float = param(3.0, 'm', 'with no goal: aim this far ahead along the start heading',
                                  minimum=0.5, live=True)
    stuck_timeout: float = param(6.0, 's', 'RECOVERING after this long without getting closer to the goal',
                                 minimum=0.5, live=True)
    give_up_timeout: float = param(60.0, 's', 'FAILED after this long without getting closer to the goal',
                                   minimum=1.0, live=True)
    heading_weight: float = param(0.6, '', 'score weight of pointing at the goal', minimum=0.0, live=True)
    progress_weight: float = param(1.0, '', 'score weight of getting closer to the goal', minimum=0.0, live=True)
    clearance_weight: float = param(1.0, '', 'score weight of clearance (up to 1 m)', minimum=0.0, live=True)
    speed_weight: float = param(0.2, '', 'score weight of going fast', minimum=0.0, live=True)

    def check_together(self):
        if not self.give_up_timeout > self.stuck_timeout:
            raise SettingsError('~give_up_timeout: expected more than stuck_timeout (%g s), got %r'
                                % (self.stuck_timeout, self.give_up_timeout))


@dataclasses.dataclass
class GoalSettings:
    """Where avoid_obstacles heads unless ``move_base_simple/goal`` says otherwise (its ``~parameters``;
    ``~goal_x`` and ``~goal_y``, both or neither, give the goal in odom)."""
    goal_distance: float = param(10.0, 'm', 'with no ~goal_x/~goal_y: the goal is this far ahead along the '
                                 'start heading; 0: no goal, hold the start heading forever', minimum=0.0)


@dataclasses.dataclass(frozen=True)
class Plan:
    """The planner's answer: the command (m/s, rad/s), what it is and why, the chosen path's least
    clearance (m), the predicted poses of the chosen command ((K, 3) x, y, yaw in the robot's frame), and
    every candidate's (v, w, clearance, safe) for display."""
    linear_x: float
    angular_z: float
    kind: str          # 'goal' (heading for it), 'avoid' (steering around), 'turn' (in place), 'stop'
    reason: str
    clearance_m: float
    path: numpy.ndarray
    candidates: numpy.ndarray


def outline(footprint, step_m=OUTLINE_STEP_M):
    """Points (M, 2) along the footprint rectangle's edges, at most ``step_m`` apart, corners included."""
    x0, x1, y0, y1 = footprint.x_min, footprint.x_max, footprint.y_min, footprint.y_max
    nx = max(1, int(math.ceil((x1 - x0) / step_m)))
    ny = max(1, int(math.ceil((y1 - y0) / step_m)))
    xs, ys = numpy.linspace(x0, x1, nx + 1), numpy.linspace(y0, y1, ny + 1)
    return numpy.unique(numpy.concatenate([
        numpy.column_stack((xs, numpy.full_like(xs, y0))), numpy.column_stack((xs, numpy.full_like(xs, y1))),
        numpy.column_stack((numpy.full_like(ys, x0), ys)), numpy.column_stack((numpy.full_like(ys, x1), ys))]),
        axis=0)


class DistanceField:
    """Distance (m) from any point of a square around the robot to the nearest scan point, for the planner.

    Cells beyond the square read as ``reach_m`` (the square is sized so no predicted pose leaves it). A
    reading is lowered by one cell's diagonal, so the field never overstates a clearance.
    """

    def __init__(self, points, reach_m):
        self.cell = GRID_CELL_M
        self.half = int(math.ceil(reach_m / self.cell))
        self.size = size = 2 * self.half + 1
        self.reach_m = reach_m
        free = numpy.full((size, size), 255, numpy.uint8)
        if len(points):
            ij = numpy.round(points / self.cell).astype(numpy.int64) + self.half
            inside = (ij[:, 0] >= 0) & (ij[:, 0] < size) & (ij[:, 1] >= 0) & (ij[:, 1] < size)
            free[ij[inside, 1], ij[inside, 0]] = 0
        if free.all():
            self._flat = None
        else:
            field = cv2.distanceTransform(free, cv2.DIST_L2, cv2.DIST_MASK_PRECISE) * self.cell \
                - self.cell * math.sqrt(2.0)
            # The border reads as reach_m: a lookup beyond the square is clipped onto it.
            field[0, :] = field[-1, :] = field[:, 0] = field[:, -1] = reach_m
            self._flat = field.ravel()

    def at_xy(self, x, y):
        """Clearance (m) at points (``x``, ``y``: arrays of one shape) in the robot's frame. The square is
        sized so that nothing the planner asks about lies beyond it; a point that did would read the
        border's value."""
        if self._flat is None:
            return numpy.full(numpy.shape(x), math.inf)
        return self._flat.take(self.index(x, y), mode='clip')

    def index(self, x, y):
        offset = self.half + 0.5
        ix = (x * (1.0 / self.cell) + offset).astype(numpy.intp)
        iy = (y * (1.0 / self.cell) + offset).astype(numpy.intp)
        return iy * self.size + ix

    def at(self, xy):
        """Clearance (m) at points ``xy`` (..., 2) in the robot's frame."""
        return self.at_xy(xy[..., 0], xy[..., 1])


def predict(v0, w0, v, w, settings, horizon_s, steps, step_s=PREDICTION_STEP_S):
    """Poses (C, K, 3) for candidates ``v``, ``w`` (C,) from (v0, w0): speeds move toward the candidate at the
    accelerations for ``horizon_s``, then to zero at the same rates; K = ``steps`` poses, PREDICTION_STEP_S
    apart (the speed of each step is the one reached at its end: the pose runs slightly ahead)."""
    dt = step_s
    t = numpy.arange(1, steps + 1) * dt
    follow = t <= horizon_s + 1e-9

    def speeds(start, target, rate):
        target = numpy.asarray(target, float)[:, None]
        along = start + numpy.clip(target - start, -rate * t, rate * t)          # ramp toward the candidate
        at_end = start + numpy.clip(target - start, -rate * horizon_s, rate * horizon_s)
        after = numpy.sign(at_end) * numpy.maximum(numpy.abs(at_end) - rate * (t - horizon_s), 0.0)
        return numpy.where(follow, along, after)
    vs = speeds(v0, v, settings.accel)
    ws = speeds(w0, w, settings.yaw_accel)
    yaw = numpy.cumsum(ws * dt, axis=1)
    mid = yaw - 0.5 * ws * dt
    x = numpy.cumsum(vs * numpy.cos(mid) * dt, axis=1)
    y = numpy.cumsum(vs * numpy.sin(mid) * dt, axis=1)
    return numpy.stack((x, y, yaw), axis=2).astype(numpy.float32)


def clearances(field, shape, poses):
    """Clearance (m) of the footprint outline ``shape`` (M, 2) at each of ``poses`` (C, K, 3): (C, K)."""
    c, s = numpy.cos(poses[..., 2])[..., None], numpy.sin(poses[..., 2])[..., None]
    px = poses[..., 0][..., None] + c * shape[:, 0] - s * shape[:, 1]
    py = poses[..., 1][..., None] + s * shape[:, 0] + c * shape[:, 1]
    return field.at_xy(px, py).min(axis=2)


def _check_finite(name, *values):
    for value in values:
        if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
            raise NavigatorError('%s: expected finite numbers, got %r' % (name, values))


def plan(scan, laser_pose, footprint, v0, w0, goal_xy, settings):
    """The command for now: a :class:`Plan`.

    ``scan``: a :class:`closed_loop.scan.Scan` (REP 117); ``laser_pose``: the laser's pose in the base
    frame (:class:`closed_loop.robot_model.Pose2DInBase`); ``footprint``: the robot's rectangle; ``v0``,
    ``w0``: the robot's speeds now (m/s, rad/s); ``goal_xy``: the goal in the robot's frame (m).
    """
    _check_finite('v0, w0', v0, w0)
    _check_finite('goal_xy', *goal_xy)
    s = settings
    points = scan_points(scan, laser_pose)
    top_v, top_w = max(s.max_speed, abs(v0)), max(s.max_yaw_rate, abs(w0))
    safe_steps = int(math.ceil((s.horizon + top_v / s.accel + top_w / s.yaw_accel) / PREDICTION_STEP_S)) + 1
    long_steps = int(math.ceil(s.lookahead / PREFERENCE_STEP_S))
    radius = math.hypot(max(abs(footprint.x_min), abs(footprint.x_max)),
                        max(abs(footprint.y_min), abs(footprint.y_max)))
    longest_s = max(safe_steps * PREDICTION_STEP_S, long_steps * PREFERENCE_STEP_S)
    reach = top_v * longest_s + radius + CLEARANCE_CAP_M
    near = points[numpy.hypot(points[:, 0], points[:, 1]) <= reach] if len(points) else points
    field = DistanceField(near, reach)
    shape = outline(footprint).astype(numpy.float32)

    # Candidates are targets over the whole speed range; each is predicted with the ramp from (v0, w0) at
    # the accelerations, and what is sent is the first period's step of that ramp (the dynamic window).
    vs = numpy.linspace(0.0, s.max_speed, LINEAR_SAMPLES)
    ws = numpy.linspace(-s.max_yaw_rate, s.max_yaw_rate, ANGULAR_SAMPLES)
    v, w = (a.ravel() for a in numpy.meshgrid(vs, ws))
    safe_poses = predict(v0, w0, v, w, s, s.horizon, safe_steps)
    clear = clearances(field, shape, safe_poses).min(axis=1)
    safe = clear >= s.safety_margin
    now = float(field.at(shape).min())
    if now < s.safety_margin:
        # Already within the margin: only a turn in place that brings no point closer, judged exactly (the
        # grid is too coarse to see a centimetre), and only while the robot is nearly at rest.
        now = footprint_clearance(near, footprint, 0.0, 0.0, 0.0)
        for i in numpy.nonzero((v == 0.0) & ~safe)[0]:
            if abs(v0) < 0.05 and path_clearance(near, footprint, safe_poses[i]) >= now:
                safe[i] = True
    arcs = predict(v0, w0, v, w, s, s.lookahead, long_steps, PREFERENCE_STEP_S)
    along = clearances(field, shape, arcs)
    candidates = numpy.column_stack((v, w, clear, safe))

    goal_distance = math.hypot(*goal_xy)
    if not safe.any():
        return Plan(0.0, 0.0, 'stop', 'no safe command: every path comes within %.2f m of an obstacle '
                    '(safety_margin %.2f m)' % (max(float(clear.max()), 0.0), s.safety_margin),
                    now, numpy.zeros((1, 3)), candidates)
    # How long each arc runs before it would come within the margin (1: the whole lookahead), and how the
    # free part of it ends: pointing at the goal, closer to it, with room around it.
    blocked = along < s.safety_margin
    free_steps = numpy.where(blocked.any(axis=1), blocked.argmax(axis=1), long_steps)
    free = free_steps / long_steps
    last = numpy.maximum(free_steps - 1, 0)
    end = arcs[numpy.arange(len(v)), last]
    bearing = numpy.arctan2(goal_xy[1] - end[:, 1], goal_xy[0] - end[:, 0]) - end[:, 2]
    heading = 1.0 - numpy.abs(numpy.arctan2(numpy.sin(bearing), numpy.cos(bearing))) / math.pi
    progress = (goal_distance - numpy.hypot(goal_xy[0] - end[:, 0], goal_xy[1] - end[:, 1])) \
        / (s.max_speed * s.lookahead)
    reached = numpy.arange(long_steps)[None, :] < numpy.maximum(free_steps, 1)[:, None]
    room = numpy.minimum(numpy.where(reached, along, numpy.inf).min(axis=1), CLEARANCE_CAP_M) / CLEARANCE_CAP_M
    speed = v / s.max_speed
    # Near the goal, speed stops counting (no overshoot).
    if goal_distance < s.max_speed ** 2 / (2 * s.accel) + s.goal_tolerance:
        speed = speed * 0.0
    # An arc that runs into the margin counts for its free part only: the sooner, the less it is worth.
    score = (free * (s.heading_weight * heading + s.speed_weight * speed) + s.progress_weight * progress
             + s.clearance_weight * room)
    score = numpy.where(safe, score, -numpy.inf)
    best = int(numpy.argmax(score))
    turns = safe & (v == 0.0) & (w != 0.0)
    if v[best] == 0.0 and w[best] == 0.0 and turns.any() and (v > 0).any():
        # Standing still beats every way forward: turn in place, toward the side whose forward arcs run
        # freer, rather than stand facing the obstacle.
        left = free[(v > 0) & (w > 0)].max(initial=0.0)
        right = free[(v > 0) & (w < 0)].max(initial=0.0)
        side = numpy.sign(w) == (1.0 if left >= right else -1.0)
        pick = turns & side if (turns & side).any() else turns
        best = int(numpy.argmax(numpy.where(pick, numpy.abs(w), -numpy.inf)))
    period_s = 1.0 / s.rate_hz
    vb = float(numpy.clip(v[best], v0 - s.accel * period_s, v0 + s.accel * period_s))
    wb = float(numpy.clip(w[best], w0 - s.yaw_accel * period_s, w0 + s.yaw_accel * period_s))
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
    return Plan(vb, wb, kind, why, cb, arcs[best], candidates)


# --- the states on top ---------------------------------------------------------------------------------------

#: Backing up needs the scan to see behind: rays within this of straight back (rad).
REAR_HALF_ANGLE_RAD = math.radians(30.0)


def rear_seen(scan, laser_pose):
    """True if the scan has rays toward the whole rear sector (a 270-degree LIDAR facing forward has
    none: then what is behind is unknown, and backing up is not safe)."""
    angles = numpy.asarray(sample_angles(scan)) + laser_pose.yaw
    off_back = numpy.abs(numpy.arctan2(numpy.sin(angles - math.pi), numpy.cos(angles - math.pi)))
    covered = off_back <= REAR_HALF_ANGLE_RAD
    if not covered.any():
        return False
    spacing = abs(scan.angle_increment)
    return covered.sum() * spacing >= 2 * REAR_HALF_ANGLE_RAD - 2 * spacing


class NavState(enum.Enum):
    """What the navigator is doing (its ``~mode``)."""
    GOAL_SEEKING = 'GOAL_SEEKING'
    AVOIDING = 'AVOIDING'
    RECOVERING = 'RECOVERING'
    REACHED = 'REACHED'
    FAILED = 'FAILED'


#: Getting this much closer to the goal (m) counts as progress.
PROGRESS_M = 0.1
#: Recovery: back up at this speed for this long (if the rear is clear), then turn in place at this rate
#: for this long toward the side not tried last time (if turning is safe).
BACKUP_SPEED_MPS = 0.15
BACKUP_S = 1.0
RECOVERY_TURN_RADPS = 0.8
RECOVERY_TURN_S = 2.0


@dataclasses.dataclass(frozen=True)
class Step:
    """One decision of :class:`Navigator`: the state, the command (m/s, rad/s), why, and the plan if one
    was made (None while recovering, reached or failed)."""
    state: NavState
    linear_x: float
    angular_z: float
    reason: str
    plan: object = None


class Navigator:
    """GOAL_SEEKING / AVOIDING / RECOVERING / REACHED / FAILED over :func:`plan`, advanced by :meth:`update`
    with injected time, the pose in odom and the newest scan.

    With a goal (odom, m) it heads there and is REACHED within ``goal_tolerance`` (then zero). Without one it
    holds the heading it started with: it aims ``hold_lookahead`` ahead of its projection on the start line,
    so after an obstacle it returns to that line and heading, and it never reaches anything. No progress
    toward the goal (or along the line) for ``stuck_timeout``: RECOVERING (back up if the rear is clear, turn
    in place toward the other side than last time if that is safe, then seek again); none for
    ``give_up_timeout``: FAILED (zero). ``on_transition(old, new, now_s, why)`` is called on every change.
    """

    def __init__(self, settings, start_pose, goal_xy=None, on_transition=None):
        self.settings = settings
        self._start = start_pose            # (x, y, yaw) in odom: the line held without a goal
        self._on_transition = on_transition
        self.state = NavState.GOAL_SEEKING
        self._side = 1.0
        self.set_goal(goal_xy)

    def set_goal(self, goal_xy, now_s=None):
        """Head for ``goal_xy`` (odom, m) from now; None: hold the start heading."""
        if goal_xy is not None:
            _check_finite('goal', *goal_xy)
        self.goal = None if goal_xy is None else (float(goal_xy[0]), float(goal_xy[1]))
        self._best = None
        self._progress_s = now_s     # the last progress (give_up_timeout counts from it)
        self._stuck_from_s = now_s   # the last progress or the end of the last recovery (stuck_timeout)
        self._recovery = None
        if self.state is not NavState.GOAL_SEEKING and now_s is not None:
            self._enter(NavState.GOAL_SEEKING, now_s, 'new goal')

    def reconfigure(self, settings):
        self.settings = settings

    def target(self, pose):
        """The point aimed at, in the robot's frame, and the measure of progress (larger is better)."""
        x, y, yaw = pose
        if self.goal is not None:
            gx, gy = self.goal
            progress = -math.hypot(gx - x, gy - y)
        else:
            sx, sy, syaw = self._start
            along = (x - sx) * math.cos(syaw) + (y - sy) * math.sin(syaw)
            ahead = along + self.settings.hold_lookahead
            gx, gy = sx + ahead * math.cos(syaw), sy + ahead * math.sin(syaw)
            progress = along
        dx, dy = gx - x, gy - y
        c, s = math.cos(yaw), math.sin(yaw)
        return (c * dx + s * dy, -s * dx + c * dy), progress

    def update(self, now_s, pose, v0, w0, scan, laser_pose, footprint):
        """The :class:`Step` for now: ``pose`` (x, y, yaw) in odom, speeds (m/s, rad/s), the newest scan."""
        _check_finite('now_s', now_s)
        _check_finite('pose', *pose)
        s = self.settings
        if self.state in (NavState.REACHED, NavState.FAILED):
            return Step(self.state, 0.0, 0.0, self.state.name.lower())
        goal_local, progress = self.target(pose)
        if self.goal is not None and math.hypot(*goal_local) <= s.goal_tolerance:
            self._enter(NavState.REACHED, now_s, 'within %.2f m of the goal' % math.hypot(*goal_local))
            return Step(self.state, 0.0, 0.0, 'reached')
        if self._progress_s is None or self._best is None or progress > self._best + PROGRESS_M \
                or now_s < self._progress_s:
            self._best = progress if self._best is None else max(progress, self._best)
            self._progress_s = self._stuck_from_s = now_s
        stalled = now_s - self._progress_s
        if stalled >= s.give_up_timeout:
            self._enter(NavState.FAILED, now_s, 'no progress for %.1f s (give_up_timeout)' % stalled)
            return Step(self.state, 0.0, 0.0, 'failed')
        if self.state is NavState.RECOVERING:
            step = self._recover(now_s, v0, w0, scan, laser_pose, footprint)
            if step is not None:
                return step
        elif now_s - self._stuck_from_s >= s.stuck_timeout:
            self._recovery = {'started_s': now_s, 'side': self._side}
            self._side = -self._side
            self._enter(NavState.RECOVERING, now_s, 'no progress for %.1f s (stuck_timeout)' % stalled)
            step = self._recover(now_s, v0, w0, scan, laser_pose, footprint)
            if step is not None:
                return step
        p = plan(scan, laser_pose, footprint, v0, w0, goal_local, s)
        state = NavState.GOAL_SEEKING if p.kind == 'goal' else NavState.AVOIDING
        self._enter(state, now_s, p.reason)
        return Step(state, p.linear_x, p.angular_z, p.reason, p)

    def _recover(self, now_s, v0, w0, scan, laser_pose, footprint):
        """The recovery's command now, or None when it is over (then seek again, with a fresh timer)."""
        s = self.settings
        elapsed = now_s - self._recovery['started_s']
        points = scan_points(scan, laser_pose)
        now_clear = footprint_clearance(points, footprint, 0.0, 0.0, 0.0)

        def safe(v, w, seconds):
            poses = predict(v0, w0, numpy.array([v]), numpy.array([w]), s, seconds,
                            int(math.ceil((seconds + 1.0) / PREDICTION_STEP_S)))[0]
            clearance = path_clearance(points, footprint, poses)
            return clearance >= s.safety_margin or clearance >= now_clear - 1e-3
        if elapsed < BACKUP_S:
            if rear_seen(scan, laser_pose) and safe(-BACKUP_SPEED_MPS, 0.0, BACKUP_S - elapsed):
                return Step(NavState.RECOVERING, -BACKUP_SPEED_MPS, 0.0, 'backing up')
            self._recovery['started_s'] = now_s - BACKUP_S   # the rear is not clear: go on to the turn
            elapsed = BACKUP_S
        if elapsed < BACKUP_S + RECOVERY_TURN_S:
            w = self._recovery['side'] * RECOVERY_TURN_RADPS
            if safe(0.0, w, min(s.horizon, BACKUP_S + RECOVERY_TURN_S - elapsed)):
                return Step(NavState.RECOVERING, 0.0, w, 'turning to try the other side')
        self._recovery = None
        self._stuck_from_s = now_s
        self._enter(NavState.GOAL_SEEKING, now_s, 'recovery done')
        return None

    def _enter(self, state, now_s, why):
        if state is not self.state:
            old, self.state = self.state, state
            if self._on_transition is not None:
                self._on_transition(old, state, now_s, why)
