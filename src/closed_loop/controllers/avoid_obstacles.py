"""avoid_obstacles: the reactive navigator (``closed_loop.control.navigation.navigator``), the lesson's first exercise.

It goes to a goal around obstacles with the robot's footprint, or, with no goal, holds its start heading.
The goal is ``goal_x``, ``goal_y`` (odom, m) where given, else ``goal_distance`` ahead of where it starts
(0: none), and a new one may come at any time (``move_base_simple/goal``). The navigator starts at the
first odometry. A scan that makes the command being followed unsafe (its predicted path now comes within
``safety_margin`` of the scan) is acted on at once. A missing or stale scan or odometry (older than
``scan_timeout``) means zero. Its mode: GOAL_SEEKING, AVOIDING, RECOVERING, REACHED or FAILED.

Drawings: ``window`` (in the base frame: the chosen arc coloured by what it is, every candidate's end, blue
if safe and red if not, and the point the arcs were scored toward), ``plan`` (nav_msgs/Path in odom: the
way to the goal that point lies on, through what the scans show), ``map`` (in odom, at most once every MAP_PERIOD_S:
the 0.1 m cells where it remembers a scan point, lime green) and ``goal`` (the goal being followed).
"""
import math
import time

import numpy

from closed_loop.control.drawing import Drawing, Goal, Route, Shape
from closed_loop.control.scan import scan_points
from closed_loop.control.navigation.situation import NavigatorError
from closed_loop.control.navigation.window import prepare
from closed_loop.control.loop import stale_input
from closed_loop.control.markers import arrow_end
from closed_loop.control.navigation.move_check import in_danger
from closed_loop.control.navigation.navigator import GoalSettings, Navigator, NavigatorSettings, NavState
from closed_loop.control.navigation.memory import CELL_M
from closed_loop.control.scan import ScanError, validate_scan
from closed_loop.controllers import STOP, Controller, ControllerError

PLAN_COLOURS = {'goal': (0.1, 0.85, 0.2, 1.0), 'avoid': (1.0, 0.75, 0.0, 1.0), 'turn': (1.0, 0.75, 0.0, 1.0),
                'stop': (0.95, 0.1, 0.1, 1.0)}
SAFE_COLOUR, UNSAFE_COLOUR = (0.3, 0.6, 1.0, 0.8), (0.95, 0.1, 0.1, 0.5)
AIM_COLOUR = (0.6, 0.2, 0.9, 1.0)   # purple: no other display of the shipped rviz config uses it
MAP_COLOUR = (0.5, 1.0, 0.0, 1.0)   # lime: nor this
#: Drawn this high above the ground (m), so the plan shows over the scan's points.
DRAW_Z_M = 0.05
#: The remembered map is sent at most this often (s of the node's clock), as a costmap is.
MAP_PERIOD_S = 1.0


class AvoidObstacles(Controller):
    name = 'avoid_obstacles'
    settings_class = NavigatorSettings
    extra_settings_classes = (GoalSettings,)
    ends_at_rest = False
    uses_odom = uses_goal = needs_footprint = True
    warn_modes = (NavState.RECOVERING.name, NavState.FAILED.name)
    outputs = {'window': Drawing, 'plan': Route, 'map': Drawing, 'goal': Goal}

    def __init__(self, settings, context, goal_settings=None, *extra_settings):
        Controller.__init__(self, settings, context)
        prepare()                   # the planner's compiled parts loaded now, not at the first decision
        self.goal_settings = goal_settings or GoalSettings()
        self.extra_settings = extra_settings
        self.navigator = None       # made at the first odometry, which gives the start pose
        self.scan = None
        self.sent = STOP
        self.step = None            # the last decision's navigator step
        self.pose = None            # the pose (odom) it was taken at
        self._map_sent_s = None
        self._news = set()          # outputs with news since drawings() was last asked
        #: The wall time (ms) of each decision that planned, when ``record_timings`` is set (benchmarks).
        self.record_timings = False
        self.decision_ms = []

    def make_core(self, start, goal):
        """What this controller drives: here the navigator (a subclass drives one with its interface)."""
        return Navigator(self.settings, start, goal, on_transition=self._on_transition)

    @property
    def goal(self):
        return None if self.navigator is None else self.navigator.goal

    def _start(self, now_s, odom):
        """The navigator, from the first odometry: the start pose and the goal."""
        goal = self.context.goal
        if goal is None and self.goal_settings.goal_distance > 0:
            d = self.goal_settings.goal_distance
            goal = (odom.x + d * math.cos(odom.yaw), odom.y + d * math.sin(odom.yaw))
        self.navigator = self.make_core((odom.x, odom.y, odom.yaw), goal)
        self._news.add('goal')
        self.log.info('start at (%.2f, %.2f, %.2f rad) in odom; %s' % (
            odom.x, odom.y, odom.yaw, 'goal (%.2f, %.2f)' % goal if goal is not None
            else 'no goal: holding the start heading'))

    def set_goal(self, goal_xy, now_s):
        if self.navigator is None:
            raise ControllerError('no odometry yet')
        try:
            self.navigator.set_goal(goal_xy, now_s)
        except NavigatorError as error:
            raise ControllerError(str(error))
        self._news.add('goal')

    def reconfigure(self, settings):
        Controller.reconfigure(self, settings)
        if self.navigator is not None:
            self.navigator.reconfigure(settings)

    def _on_transition(self, old, new, now_s, why):
        self.enter(new.name, now_s, why)

    def _odometry(self, now_s, odom):
        """Start the navigator at the first usable odometry, whichever call brings it."""
        if self.navigator is None and odom is not None and all(math.isfinite(v) for v in odom):
            self._start(now_s, odom)

    def on_scan(self, now_s, scan, odom):
        self._odometry(now_s, odom)
        if scan is not None:
            try:
                validate_scan(scan)
            except ScanError as error:
                self.log.error('scan rejected: %s' % error)
                scan = None
        self.scan = scan
        laser_pose = self.context.laser_pose
        if scan is None or in_danger(self.sent, scan_points(scan, laser_pose) if self.navigator is None
                                     else self.navigator.scanned(scan, laser_pose), self.settings,
                                     self.context.footprint):
            return self.on_tick(now_s, odom)
        return None

    def on_tick(self, now_s, odom):
        self._odometry(now_s, odom)
        if self.navigator is None:
            return self._stop('no odometry yet')
        if self.scan is None:
            return self._stop('no usable scan')
        problem = stale_input(now_s, (('scan', self.scan.stamp_s), ('odometry', odom.stamp_s)),
                              self.settings.scan_timeout)
        if problem is not None:
            return self._stop(problem)
        started = time.perf_counter()
        try:
            step = self.navigator.update(now_s, (odom.x, odom.y, odom.yaw), odom.v, odom.w, self.scan,
                                         self.context.laser_pose, self.context.footprint)
        except (NavigatorError, ScanError) as error:
            return self._stop(str(error))
        if step.plan is not None or step.route is not None:
            if self.record_timings:
                self.decision_ms.append((time.perf_counter() - started) * 1e3)
            self._news.update(('window', 'plan'))
        if self._map_sent_s is None or not 0.0 <= now_s - self._map_sent_s < MAP_PERIOD_S:
            self._map_sent_s = now_s
            self._news.add('map')
        self.pose = (odom.x, odom.y, odom.yaw)
        self.fault = None
        self.sent = (step.linear_x, step.angular_z)
        self.step = step
        self.enter(step.state.name, now_s, step.reason)
        self.finished = step.state in (NavState.REACHED, NavState.FAILED)
        self.after_step(now_s, step)
        return self.sent

    def _stop(self, why):
        self.fault = why
        self.sent = STOP
        return STOP

    def after_step(self, now_s, step):
        """Called after each decision (a subclass keeps more from it)."""

    # -- what it draws ---------------------------------------------------------------------------------------
    def drawings(self, wanted):
        news, self._news = self._news, set()
        out = {}
        if 'goal' in news and 'goal' in wanted and self.goal is not None:
            out['goal'] = Goal(self.navigator.goal)
        plan = None if self.step is None else self.step.plan
        if 'window' in news and 'window' in wanted and plan is not None:
            out['window'] = self.window_drawing(plan)
        if 'plan' in news and 'plan' in wanted and self.step.route is not None:
            out['plan'] = Route(tuple((float(x), float(y)) for x, y in self.step.route))
        elif 'plan' in news and 'plan' in wanted and plan is not None:
            out['plan'] = self.route(plan, self.pose)
        if 'map' in news and 'map' in wanted and self.navigator is not None:
            out['map'] = self.map_drawing(self.navigator.remembered())
        return out

    @staticmethod
    def map_drawing(remembered):
        """What the navigator remembers, in odom: a square on each cell where it holds a scan point. One marker,
        which each new map replaces in place (no delete-all before it: rviz may carry out a delete-all while the
        new marker still waits for its transform, and show no map in between); an empty map clears it."""
        (x0, y0), occupied = remembered
        rows, cols = numpy.nonzero(occupied)
        cells = tuple((float(x0 + (j + 0.5) * CELL_M), float(y0 + (i + 0.5) * CELL_M), DRAW_Z_M)
                      for i, j in zip(rows, cols))
        if not cells:
            return Drawing('odom', (), clear=True)
        return Drawing('odom', (Shape('points', 'remembered', 0, MAP_COLOUR, (CELL_M, CELL_M, 0.0), cells),))

    @staticmethod
    def route(plan, pose):
        """The way ``plan`` aimed along, in odom from ``pose`` (x, y, yaw): from the robot to the goal; to the
        goal straight where the scan showed no way."""
        points = numpy.array([(0.0, 0.0), plan.aim_xy]) if plan.way is None else plan.way.route()
        x, y, yaw = pose
        c, s = math.cos(yaw), math.sin(yaw)
        return Route(tuple((float(x + c * px - s * py), float(y + s * px + c * py)) for px, py in points))

    def window_drawing(self, plan):
        """The plan in the base frame: the chosen arc, every candidate's end, and the aim."""
        chosen = Shape('line', 'chosen', 0, PLAN_COLOURS.get(plan.kind, PLAN_COLOURS['goal']), (0.03, 0.0, 0.0),
                       ((0.0, 0.0, DRAW_Z_M),) + tuple((float(x), float(y), DRAW_Z_M) for x, y, _ in plan.path))
        ends, colours = [], []
        for v, w, _clearance, safe in plan.candidates:
            # Where the candidate would take the robot in one horizon, drawn as a dot.
            x, y = arrow_end(v, w, self.settings.horizon)
            ends.append((x, y, DRAW_Z_M))
            colours.append(SAFE_COLOUR if safe else UNSAFE_COLOUR)
        candidates = Shape('points', 'candidates', 1, scale=(0.04, 0.04, 0.0), points=tuple(ends),
                           colours=tuple(colours))
        # The point the arcs were scored toward: a way round the obstacles to the goal (control.navigation.wavefront).
        aim = Shape('sphere', 'aim', 2, AIM_COLOUR, (0.15, 0.15, 0.15),
                    position=(float(plan.aim_xy[0]), float(plan.aim_xy[1]), DRAW_Z_M))
        return Drawing('base', (chosen, candidates, aim))
