"""The reactive navigator: its settings, and the states over the local planner (``closed_loop.control.navigation.window``).

GOAL_SEEKING and AVOIDING follow the planner's choice; RECOVERING (close the place just ahead to the way
for a while, back up where the scan sees the rear clear, back out while it has no room to turn (along the way it
came, else straight or on an arc), then turn toward the side not tried last time) comes after ``stuck_timeout`` without progress;
after ESCAPE_AFTER_S without progress, AVOIDING along an escape's plan for the footprint (``closed_loop.control.navigation.escape``);
REACHED within ``goal_tolerance`` of the goal; FAILED after ``give_up_timeout`` without progress. With no
goal the navigator holds the start heading. Time is injected, so every transition is tested with plain
numbers. Free of ROS.
"""
import dataclasses
import enum
import math

import numpy

from closed_loop.control.navigation import escape
from closed_loop.control.scan import scan_points
from closed_loop.control.navigation.situation import Situation, check_finite, step_toward
from closed_loop.control.navigation.window import plan
from closed_loop.control.navigation.move_check import MoveCheck
from closed_loop.control.navigation.memory import ScanMemory, from_frame, to_frame
from closed_loop.control.navigation.recovery import Recovery
from closed_loop.control.navigation.trail import Trail
from closed_loop.control.loop import LoopSettings, lasted
from closed_loop.settings import SettingsError, param


@dataclasses.dataclass
class NavigatorSettings(LoopSettings):
    """avoid_obstacles' ``~parameters``; the speed and acceleration limits come from the robot profile."""
    max_speed: float = param(0.5, 'm/s', 'forward speed limit', minimum=0.0, exclusive_minimum=True, live=True)
    max_yaw_rate: float = param(1.5, 'rad/s', 'turn rate limit', minimum=0.0, exclusive_minimum=True, live=True)
    accel: float = param(1.0, 'm/s^2', 'linear acceleration and braking the plan counts on', minimum=0.05,
                         live=True)
    yaw_accel: float = param(3.0, 'rad/s^2', 'yaw acceleration the plan counts on', minimum=0.1, live=True)
    safety_margin: float = param(0.05, 'm', 'least clearance between the footprint and any scan point along '
                                 'a chosen path, at rest (margin_per_speed adds to it at speed)', minimum=0.05,
                                 maximum=1.0, live=True)
    margin_per_speed: float = param(0.08, 's', 'the margin a path keeps grows by this much per m/s of the '
                                    'faster of its speed and the speed now (a base at speed strays farther from '
                                    'its predicted arc)', minimum=0.0, maximum=1.0, live=True)
    avoid_distance: float = param(0.5, 'm', 'a chosen path closer than this to an obstacle (or a turn '
                                  'away from the goal) is AVOIDING', minimum=0.0, live=True)
    horizon: float = param(0.5, 's', 'safety: how long a candidate is assumed followed before braking '
                           '(control period, scan delay and room to spare)', minimum=0.1, maximum=3.0, live=True)
    lookahead: float = param(2.0, 's', 'preference: how far along each candidate arc is scored', minimum=0.5,
                             maximum=6.0, live=True)
    goal_tolerance: float = param(0.1, 'm', 'REACHED within this distance of the goal', minimum=0.05,
                                  live=True)
    memory_time: float = param(60.0, 's', 'scan points are remembered this long (in odom) to choose the way '
                               'around (and, where the LIDAR cannot see, for safety); 0: no memory', minimum=0.0,
                               maximum=120.0, live=True)
    hold_lookahead: float = param(3.0, 'm', 'with no goal: aim this far ahead of the robot along the start '
                                  'heading',
                                  minimum=0.5, live=True)
    hold_corridor: float = param(2.0, 'm', 'with no goal: the way round an obstacle keeps within this distance '
                                 'of the line ahead along the start heading (a wall across it blocks the way, '
                                 'to be stopped at, not gone round)', minimum=0.0, exclusive_minimum=True, live=True)
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


class NavState(enum.Enum):
    """What the navigator is doing (its ``~mode``)."""
    GOAL_SEEKING = 'GOAL_SEEKING'
    AVOIDING = 'AVOIDING'
    RECOVERING = 'RECOVERING'
    REACHED = 'REACHED'
    FAILED = 'FAILED'


#: Getting this much closer to the goal (m) counts as progress.
PROGRESS_M = 0.1
#: Within this distance of the goal (m), a direct approach (turn toward it at FINAL_TURN_GAIN x bearing, at
#: most FINAL_TURN_RADPS, drive once within FINAL_DRIVE_RAD of it at FINAL_SPEED_GAIN x distance) replaces
#: the window, if safe.
FINAL_APPROACH_M = 1.0
FINAL_TURN_GAIN = 1.5
FINAL_TURN_RADPS = 1.0
FINAL_SPEED_GAIN = 1.0
FINAL_DRIVE_RAD = 0.5
#: After this long (s) without progress, where the window would stand or turn in place, the way is followed
#: instead, heading first (``window.plan``'s ``follow``).
FOLLOW_AFTER_S = 1.0
#: Where it was stuck is closed to the way for CLOSED_FOR_S: a disc of CLOSED_RADIUS_M (drawn as points
#: CLOSED_STEP_M apart round its centre, which the way keeps its half-width and margin from) CLOSED_AHEAD_M
#: ahead of the robot, so the next way found leads elsewhere. Closed places are for the way only, never for
#: safety.
CLOSED_AHEAD_M = 0.35
CLOSED_RADIUS_M = 0.3
CLOSED_STEP_M = 0.1
CLOSED_FOR_S = 60.0


@dataclasses.dataclass(frozen=True)
class Step:
    """One decision of :class:`Navigator`: the state, the command (m/s, rad/s), why, the plan if one
    was made (None while recovering, escaping, reached or failed), and the escape's way ahead ((N, 2) odom)
    while it follows one."""
    state: NavState
    linear_x: float
    angular_z: float
    reason: str
    plan: object = None
    route: object = None


class Navigator:
    """GOAL_SEEKING / AVOIDING / RECOVERING / REACHED / FAILED over :func:`plan`, advanced by :meth:`update`
    with injected time, the pose in odom and the newest scan.

    With a goal (odom, m) it heads there and is REACHED within ``goal_tolerance`` (then zero). Without one it
    holds the heading it started with (the lesson's "resume the original direction"): it aims
    ``hold_lookahead`` ahead of itself along the start heading, so after an obstacle it turns back to that
    heading (on a line beside the first one), and it never reaches anything; the way round keeps within
    ``hold_corridor`` of that line, so a wall across the whole way is a block it stops at, not a thing to
    go round. No progress toward the goal (or along the line) for ``stuck_timeout``: RECOVERING (close the
    place just ahead to the way for CLOSED_FOR_S, back up if the rear is clear, back out (along the way it
    came, else straight or on an arc) while turning in place is not safe, turn in place toward the other side than last time if that is
    safe, then seek again); none for ``give_up_timeout``: FAILED (zero). ``on_transition(old, new, now_s,
    why)`` is called on every change.
    """

    def __init__(self, settings, start_pose, goal_xy=None, on_transition=None):
        self.settings = settings
        self._start = start_pose            # (x, y, yaw) in odom: the line held without a goal
        self._on_transition = on_transition
        self.state = NavState.GOAL_SEEKING
        self._side = 1.0
        self._memory = ScanMemory(settings.memory_time)
        self._turning = 0.0          # the way of the last turn in place, while it goes on
        self._command = None         # the command of the last step, (m/s, rad/s)
        self._remembered_scan = None
        self._scanned = None         # its points in the robot's frame
        self._points_of = None       # (scan, laser pose, its points): the last scan turned into points
        self.set_goal(goal_xy)

    def set_goal(self, goal_xy, now_s=None):
        """Head for ``goal_xy`` (odom, m) from now; None: hold the start heading."""
        if goal_xy is not None:
            check_finite('goal', *goal_xy)
        self.goal = None if goal_xy is None else (float(goal_xy[0]), float(goal_xy[1]))
        self._best = None
        self._progress_s = now_s     # the last progress (give_up_timeout counts from it)
        self._stuck_from_s = now_s   # the last progress or the end of the last recovery (stuck_timeout)
        self._recovery = None
        self._closed = []            # places closed to the way: (x, y) in odom, until when (s)
        self._trail = Trail()        # the way it came (odom), to back out along
        self._way = None             # the way followed, (N, 2) in odom, kept while it stays open (wavefront.way)
        self._command = None         # the first step is taken from the measured speed
        self._escape = escape.Escape()
        self._stalled = 0.0          # since the last progress (s), as the decision's progress stage last found
        if self.state is not NavState.GOAL_SEEKING and now_s is not None:
            self._enter(NavState.GOAL_SEEKING, now_s, 'new goal')

    def reconfigure(self, settings):
        self.settings = settings
        self._memory.memory_s = settings.memory_time

    def target(self, pose):
        """The point aimed at, in the robot's frame, and the measure of progress (larger is better)."""
        x, y, yaw = pose
        if self.goal is not None:
            gx, gy = self.goal
            progress = -math.hypot(gx - x, gy - y)
        else:
            sx, sy, syaw = self._start
            along = (x - sx) * math.cos(syaw) + (y - sy) * math.sin(syaw)
            gx = x + self.settings.hold_lookahead * math.cos(syaw)
            gy = y + self.settings.hold_lookahead * math.sin(syaw)
            progress = along
        dx, dy = gx - x, gy - y
        c, s = math.cos(yaw), math.sin(yaw)
        return (c * dx + s * dy, -s * dx + c * dy), progress

    def scanned(self, scan, laser_pose):
        """The scan's points in the robot's frame (``scan.scan_points``), worked out once a scan: the node
        asks on the scan's arrival (is the command being followed still safe?), the decision after it."""
        if self._points_of is None or self._points_of[0] is not scan or self._points_of[1] != laser_pose:
            self._points_of = (scan, laser_pose, scan_points(scan, laser_pose))
        return self._points_of[2]

    def remembered(self):
        """What it remembers of the scans, as :meth:`closed_loop.control.navigation.memory.ScanMemory.occupancy` gives
        it (odom)."""
        return self._memory.occupancy()

    def corridor(self, pose):
        """With no goal, the line along the start heading through the robot and ``hold_corridor``, in the
        robot's frame (for :func:`closed_loop.control.navigation.wavefront.way`); None with a goal."""
        if self.goal is not None:
            return None
        relative = self._start[2] - pose[2]
        return (0.0, 0.0), (math.cos(relative), math.sin(relative)), self.settings.hold_corridor

    def update(self, now_s, pose, v0, w0, scan, laser_pose, footprint):
        """The :class:`Step` for now: ``pose`` (x, y, yaw) in odom, speeds (m/s, rad/s), the newest scan."""
        step = self._decide(now_s, pose, v0, w0, scan, laser_pose, footprint)
        self._command = (step.linear_x, step.angular_z)   # the next step is taken from it
        return step

    def _decide(self, now_s, pose, v0, w0, scan, laser_pose, footprint):
        """The stages of a decision (``closed_loop.control.navigation``), in order: the first with a command
        gives it."""
        check_finite('now_s', now_s)
        check_finite('pose', *pose)
        if self.state in (NavState.REACHED, NavState.FAILED):
            return Step(self.state, 0.0, 0.0, self.state.name.lower())
        goal_local, progress = self.target(pose)
        sit = Situation(scan, laser_pose, footprint, v0, w0, goal_local, previous=self._command)
        for stage in (self._arrived, self._progress, self._recovering, self._perceive, self._escaping,
                      self._approaching, self._planning):
            step = stage(now_s, pose, sit, progress)
            if step is not None:
                return step
        raise AssertionError('the window always answers')

    def _arrived(self, now_s, pose, sit, progress):
        """REACHED within ``goal_tolerance`` of the goal."""
        distance = math.hypot(*sit.goal_xy)
        if self.goal is not None and distance <= self.settings.goal_tolerance:
            self._enter(NavState.REACHED, now_s, 'within %.2f m of the goal' % distance)
            return Step(self.state, 0.0, 0.0, 'reached')
        return None

    def _progress(self, now_s, pose, sit, progress):
        """The progress timers (``stalled``: since the last progress), FAILED after ``give_up_timeout`` without
        it; the way it came, while it is not recovering."""
        if self._progress_s is None or self._best is None or progress > self._best + PROGRESS_M \
                or now_s < self._progress_s:
            self._best = progress if self._best is None else max(progress, self._best)
            self._progress_s = self._stuck_from_s = now_s
        self._stalled = now_s - self._progress_s
        if lasted(self._stalled, self.settings.give_up_timeout):
            self._enter(NavState.FAILED, now_s, 'no progress for %.1f s (give_up_timeout)' % self._stalled)
            return Step(self.state, 0.0, 0.0, 'failed')
        if self.state is not NavState.RECOVERING:
            self._trail.add(pose[0], pose[1])
        return None

    def _recovering(self, now_s, pose, sit, progress):
        """The recovery's command while it goes on; one begins after ``stuck_timeout`` without progress (unless an
        escape is under way), closing the place just ahead to the way."""
        if self.state is not NavState.RECOVERING:
            if not lasted(now_s - self._stuck_from_s, self.settings.stuck_timeout) or self._escape.active:
                return None
            self._recovery = Recovery(now_s, self._side, pose, self._trail)
            self._way = None
            self._side = -self._side
            self._closed.append(((pose[0] + CLOSED_AHEAD_M * math.cos(pose[2]),
                                  pose[1] + CLOSED_AHEAD_M * math.sin(pose[2])), now_s + CLOSED_FOR_S))
            self._enter(NavState.RECOVERING, now_s, 'no progress for %.1f s (stuck_timeout): the place %.2f m '
                        'ahead is closed to the way for %.0f s' % (self._stalled, CLOSED_AHEAD_M, CLOSED_FOR_S))
        return self._recover(now_s, pose, sit)

    def _perceive(self, now_s, pose, sit, progress):
        """The newest scan into what it remembers (once a scan); never a command."""
        if sit.scan is not self._remembered_scan:
            self._remembered_scan, self._scanned = sit.scan, self.scanned(sit.scan, sit.laser_pose)
            self._memory.add(now_s, pose, self._scanned, sit.scan, sit.laser_pose, sit.footprint)
        return None

    def _approaching(self, now_s, pose, sit, progress):
        if self.goal is not None and math.hypot(*sit.goal_xy) < FINAL_APPROACH_M:
            return self._final_approach(now_s, pose, sit)
        return None

    def _planning(self, now_s, pose, sit, progress):
        """The dynamic window's choice (``window.plan``), with what it remembers, the places closed to the way,
        the way followed so far, and whether to follow it (FOLLOW_AFTER_S without progress)."""
        p = plan(dataclasses.replace(
            sit, remembered=self._memory.points(pose), scanned=self._scanned, turning=self._turning,
            corridor=self.corridor(pose), closed=self._closed_points(now_s, pose),
            kept_way=None if self._way is None else to_frame(self._way, pose),
            follow=self._stalled >= FOLLOW_AFTER_S), self.settings)
        self._way = None if p.way is None else from_frame(p.way.route(), pose)
        self._turning = math.copysign(1.0, p.target[1]) if p.kind == 'turn' else 0.0
        if p.kind == 'goal' and self.goal is None:      # (its aim is a point ahead on the start heading, no goal)
            p = dataclasses.replace(p, reason='no goal: holding the start heading, %.2f m along it so far' % progress)
        state = NavState.GOAL_SEEKING if p.kind == 'goal' else NavState.AVOIDING
        self._enter(state, now_s, p.reason)
        return Step(state, p.linear_x, p.angular_z, p.reason, p)

    def _closed_points(self, now_s, pose):
        """The places closed to the way, as points (M, 2) in the robot's frame at ``pose`` (odom)."""
        self._closed = [(xy, until) for xy, until in self._closed if until > now_s]
        if not self._closed:
            return None
        n = max(3, int(math.ceil(2 * math.pi * CLOSED_RADIUS_M / CLOSED_STEP_M)))
        around = 2 * math.pi * numpy.arange(n) / n
        disc = numpy.concatenate(([[0.0, 0.0]], CLOSED_RADIUS_M * numpy.column_stack((numpy.cos(around),
                                                                                     numpy.sin(around)))))
        return to_frame(numpy.concatenate([disc + xy for xy, _ in self._closed]), pose)

    def _final_approach(self, now_s, pose, sit):
        """The last metre, where the window's coarse speeds would circle the goal: turn toward it, and drive
        at it slower the closer it is, if that path keeps the margin (``move_check.MoveCheck``); else None."""
        s, v0, w0 = self.settings, sit.v0, sit.w0
        distance, bearing = math.hypot(*sit.goal_xy), math.atan2(sit.goal_xy[1], sit.goal_xy[0])
        w = max(-FINAL_TURN_RADPS, min(FINAL_TURN_RADPS, s.max_yaw_rate, FINAL_TURN_GAIN * bearing))
        v = 0.0 if abs(bearing) > FINAL_DRIVE_RAD else min(s.max_speed, FINAL_SPEED_GAIN * distance) * math.cos(bearing)
        if not self._check(now_s, pose, sit).safe(v, w, s.horizon, speed=max(v, abs(v0))):
            return None
        period_s = 1.0 / s.rate_hz
        # One period's step toward (v, w), as the window's (``situation.step_toward``).
        prev_v, prev_w = (None, None) if self._command is None else self._command
        v = step_toward(v, prev_v, v0, s.accel, period_s, s.max_speed)
        w = step_toward(w, prev_w, w0, s.yaw_accel, period_s, s.max_yaw_rate)
        why = 'final approach to the goal %.2f m away' % distance
        self._turning = 0.0
        self._enter(NavState.GOAL_SEEKING, now_s, why)
        return Step(NavState.GOAL_SEEKING, v, w, why)

    def _check(self, now_s, pose, sit, scanned=None):
        """The ``move_check.MoveCheck`` of moves now: the scan's points and what is remembered where it cannot
        see."""
        return MoveCheck(self.settings, sit.footprint, sit.v0, sit.w0, sit.scan, sit.laser_pose,
                         self.scanned(sit.scan, sit.laser_pose) if scanned is None else scanned,
                         self._memory.points(pose), self._memory.t, now_s)

    def _escaping(self, now_s, pose, sit, progress):
        """The escape's command (``closed_loop.control.navigation.escape``), as one period's step, or None."""
        s, v0, w0 = self.settings, sit.v0, sit.w0
        if not self._escape.due(now_s, self._stalled):
            return None
        route = None if self._way is None else to_frame(self._way, pose)
        check = self._check(now_s, pose, sit, self._scanned)
        cmd = self._escape.command(
            now_s, pose, lambda: (numpy.concatenate((from_frame(self._scanned, pose), self._memory.xy)),
                                  from_frame(check.blind, pose), check.doubt),
            tuple(from_frame(numpy.array([escape.aim(route, sit.goal_xy)]), pose)[0]), sit.footprint,
            s.safety_margin + escape.PLAN_ROOM_M, check, s.horizon, (s.max_speed, s.max_yaw_rate))
        if cmd is None:
            return None
        prev_v, prev_w = (None, None) if self._command is None else self._command
        v = step_toward(cmd[0], prev_v, v0, s.accel, 1.0 / s.rate_hz, s.max_speed)
        w = step_toward(cmd[1], prev_w, w0, s.yaw_accel, 1.0 / s.rate_hz, s.max_yaw_rate)
        self._stuck_from_s = now_s
        self._enter(NavState.AVOIDING, now_s, cmd[2])
        return Step(NavState.AVOIDING, v, w, cmd[2], route=self._escape.route())

    def _recover(self, now_s, pose, sit):
        """The recovery's command now (``recovery.Recovery``), or None when it is over (then seek again, with a
        fresh timer)."""
        move = self._recovery.command(now_s, pose, sit, self._check(now_s, pose, sit).safe, self._trail,
                                      self.settings)
        if move is not None:
            return Step(NavState.RECOVERING, *move)
        elapsed = now_s - self._recovery.started_s
        self._recovery = None
        self._stuck_from_s = now_s
        self._enter(NavState.GOAL_SEEKING, now_s, 'recovery done' if elapsed > 0.0 else
                    'recovery done: no move kept the margin (no room to turn or to back out)')
        return None

    def _enter(self, state, now_s, why):
        if state is not self.state:
            old, self.state = self.state, state
            if self._on_transition is not None:
                self._on_transition(old, state, now_s, why)
