"""The reactive navigator: its settings, and the states over the local planner (``closed_loop.control.local_planner``).

GOAL_SEEKING and AVOIDING follow the planner's choice; RECOVERING (close the place just ahead to the way
for a while, back up where the scan sees the rear clear, back out while it has no room to turn (along the way it
came, else straight or on an arc), then turn toward the side not tried last time) comes after ``stuck_timeout`` without progress;
after ESCAPE_AFTER_S without progress, AVOIDING along an escape's plan for the footprint (``closed_loop.control.escape``);
REACHED within ``goal_tolerance`` of the goal; FAILED after ``give_up_timeout`` without progress. With no
goal the navigator holds the start heading. Time is injected, so every transition is tested with plain
numbers. Free of ROS.
"""
import dataclasses
import enum
import math

import numpy

from closed_loop.control import escape
from closed_loop.control.scan import scan_points
from closed_loop.control.local_planner import check_finite, plan, step_toward
from closed_loop.control.move_check import MoveCheck
from closed_loop.control.scan_memory import ScanMemory, from_frame, to_frame
from closed_loop.control.trail import TRAIL_LOOKBACK_M, TRAIL_STEP_M, Trail, back_toward, rear_seen
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
#: Recovery: back up at this speed for this long (if the scan sees the rear clear); while turning in place is
#: not safe, back out along the way it came (``closed_loop.control.trail``, what the map says is clear), or
#: where that move is not safe or there is no trail, straight back or on a backing arc (each move checked
#: against the scan and what it remembers), up to BACKOUT_M from where the recovery began and BACKOUT_S from
#: its start; then turn in place at this rate for this long toward the side
#: not tried last time (if turning is safe).
BACKUP_SPEED_MPS = 0.15
BACKUP_S = 1.0
BACKOUT_M = 0.6
BACKOUT_S = 8.0
#: Where neither the way it came nor straight back keeps the margin, a backing arc at this turn rate (rad/s).
BACKING_ARC_RADPS = 0.4
RECOVERY_TURN_RADPS = 0.8
RECOVERY_TURN_S = 2.0
#: After this long (s) without progress, where the window would stand or turn in place, the way is followed
#: instead, heading first (local_planner.plan's ``follow``).
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
        """What it remembers of the scans, as :meth:`closed_loop.control.scan_memory.ScanMemory.occupancy` gives
        it (odom)."""
        return self._memory.occupancy()

    def corridor(self, pose):
        """With no goal, the line along the start heading through the robot and ``hold_corridor``, in the
        robot's frame (for :func:`closed_loop.control.wavefront.way`); None with a goal."""
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
        check_finite('now_s', now_s)
        check_finite('pose', *pose)
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
        if lasted(stalled, s.give_up_timeout):
            self._enter(NavState.FAILED, now_s, 'no progress for %.1f s (give_up_timeout)' % stalled)
            return Step(self.state, 0.0, 0.0, 'failed')
        if self.state is not NavState.RECOVERING:
            self._trail.add(pose[0], pose[1])
        if self.state is NavState.RECOVERING:
            step = self._recover(now_s, pose, v0, w0, scan, laser_pose, footprint)
            if step is not None:
                return step
        elif lasted(now_s - self._stuck_from_s, s.stuck_timeout) and not self._escape.active:
            self._recovery = {'started_s': now_s, 'side': self._side, 'turn_s': None, 'from': pose[:2],
                              'end': self._trail.back(BACKOUT_M) if len(self._trail) > 1 else None}
            self._way = None
            self._side = -self._side
            self._closed.append(((pose[0] + CLOSED_AHEAD_M * math.cos(pose[2]),
                                  pose[1] + CLOSED_AHEAD_M * math.sin(pose[2])), now_s + CLOSED_FOR_S))
            self._enter(NavState.RECOVERING, now_s, 'no progress for %.1f s (stuck_timeout): the place %.2f m '
                        'ahead is closed to the way for %.0f s' % (stalled, CLOSED_AHEAD_M, CLOSED_FOR_S))
            step = self._recover(now_s, pose, v0, w0, scan, laser_pose, footprint)
            if step is not None:
                return step
        if scan is not self._remembered_scan:
            self._remembered_scan, self._scanned = scan, self.scanned(scan, laser_pose)
            self._memory.add(now_s, pose, self._scanned, scan, laser_pose, footprint)
        step = self._escaping(now_s, pose, v0, w0, scan, laser_pose, footprint, stalled, goal_local)
        if step is not None:
            return step
        if self.goal is not None and math.hypot(*goal_local) < FINAL_APPROACH_M:
            step = self._final_approach(now_s, pose, goal_local, v0, w0, scan, laser_pose, footprint)
            if step is not None:
                return step
        p = plan(scan, laser_pose, footprint, v0, w0, goal_local, s, self._memory.points(pose), self._turning,
                 self._scanned, self._command, self.corridor(pose), self._closed_points(now_s, pose),
                 None if self._way is None else to_frame(self._way, pose), stalled >= FOLLOW_AFTER_S)
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

    def _final_approach(self, now_s, pose, goal_local, v0, w0, scan, laser_pose, footprint):
        """The last metre, where the window's coarse speeds would circle the goal: turn toward it, and drive
        at it slower the closer it is, if that path keeps the margin (``move_check.MoveCheck``); else None."""
        s = self.settings
        distance, bearing = math.hypot(*goal_local), math.atan2(goal_local[1], goal_local[0])
        w = max(-FINAL_TURN_RADPS, min(FINAL_TURN_RADPS, s.max_yaw_rate, FINAL_TURN_GAIN * bearing))
        v = 0.0 if abs(bearing) > FINAL_DRIVE_RAD else min(s.max_speed, FINAL_SPEED_GAIN * distance) * math.cos(bearing)
        check = MoveCheck(s, footprint, v0, w0, scan, laser_pose, self.scanned(scan, laser_pose),
                          self._memory.points(pose), self._memory.t, now_s)
        if not check.safe(v, w, s.horizon, speed=max(v, abs(v0))):
            return None
        period_s = 1.0 / s.rate_hz
        # One period's step toward (v, w), as the window's (local_planner.step_toward).
        prev_v, prev_w = (None, None) if self._command is None else self._command
        v = step_toward(v, prev_v, v0, s.accel, period_s, s.max_speed)
        w = step_toward(w, prev_w, w0, s.yaw_accel, period_s, s.max_yaw_rate)
        why = 'final approach to the goal %.2f m away' % distance
        self._turning = 0.0
        self._enter(NavState.GOAL_SEEKING, now_s, why)
        return Step(NavState.GOAL_SEEKING, v, w, why)

    def _escaping(self, now_s, pose, v0, w0, scan, laser_pose, footprint, stalled, goal_local):
        """The escape's command (``closed_loop.control.escape``), as one period's step, or None."""
        s = self.settings
        if not self._escape.due(now_s, stalled):
            return None
        route = None if self._way is None else to_frame(self._way, pose)
        check = MoveCheck(s, footprint, v0, w0, scan, laser_pose, self._scanned, self._memory.points(pose),
                          self._memory.t, now_s)
        cmd = self._escape.command(
            now_s, pose, lambda: (numpy.concatenate((from_frame(self._scanned, pose), self._memory.xy)),
                                  from_frame(check.blind, pose), check.doubt),
            tuple(from_frame(numpy.array([escape.aim(route, goal_local)]), pose)[0]), footprint,
            s.safety_margin + escape.PLAN_ROOM_M, check, s.horizon, (s.max_speed, s.max_yaw_rate))
        if cmd is None:
            return None
        prev_v, prev_w = (None, None) if self._command is None else self._command
        v = step_toward(cmd[0], prev_v, v0, s.accel, 1.0 / s.rate_hz, s.max_speed)
        w = step_toward(cmd[1], prev_w, w0, s.yaw_accel, 1.0 / s.rate_hz, s.max_yaw_rate)
        self._stuck_from_s = now_s
        self._enter(NavState.AVOIDING, now_s, cmd[2])
        return Step(NavState.AVOIDING, v, w, cmd[2], route=self._escape.route())

    def _recover(self, now_s, pose, v0, w0, scan, laser_pose, footprint):
        """The recovery's command now, or None when it is over (then seek again, with a fresh timer)."""
        s = self.settings
        elapsed = now_s - self._recovery['started_s']
        safe = MoveCheck(s, footprint, v0, w0, scan, laser_pose, self.scanned(scan, laser_pose),
                         self._memory.points(pose), self._memory.t, now_s).safe
        r = self._recovery
        turn = r['side'] * RECOVERY_TURN_RADPS
        if r['turn_s'] is None:
            end = r['end']
            if not lasted(elapsed, BACKUP_S) and rear_seen(scan, laser_pose):
                if safe(-BACKUP_SPEED_MPS, 0.0, BACKUP_S - elapsed):
                    return Step(NavState.RECOVERING, -BACKUP_SPEED_MPS, 0.0, 'backing up')
            elif not lasted(elapsed, BACKOUT_S) and math.hypot(r['from'][0] - pose[0], r['from'][1] - pose[1]) < BACKOUT_M \
                    and not safe(0.0, turn, min(s.horizon, RECOVERY_TURN_S)):
                # No room to turn: back out the way it came, or else straight back or on a backing arc.
                moves = [(-BACKUP_SPEED_MPS, 0.0, 'backing straight out')] + [
                    (-BACKUP_SPEED_MPS, side * BACKING_ARC_RADPS, 'backing out on an arc')
                    for side in (r['side'], -r['side'])]
                if end is not None and math.hypot(end[0] - pose[0], end[1] - pose[1]) > TRAIL_STEP_M:
                    self._trail.drop_behind(pose[0], pose[1])
                    moves.insert(0, back_toward(pose, self._trail.back(TRAIL_LOOKBACK_M), BACKUP_SPEED_MPS,
                                                s.max_yaw_rate) + ('backing out the way it came',))
                for v, w, what in moves:
                    if safe(v, w, BACKUP_S):
                        return Step(NavState.RECOVERING, v, w, what + ': no room to turn here')
            r['turn_s'] = now_s
        if not lasted(now_s - r['turn_s'], RECOVERY_TURN_S) and safe(0.0, turn, min(s.horizon, RECOVERY_TURN_S -
                                                                              (now_s - r['turn_s']))):
            return Step(NavState.RECOVERING, 0.0, turn, 'turning to try the other side')
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
