"""avoid_obstacles' core (the navigator), as ``closed_loop.nodes.avoid_obstacles`` drives it."""
import time

from closed_loop.controllers import Controller
from closed_loop.control.guard import scan_points
from closed_loop.control.local_planner import NavigatorError
from closed_loop.control.navigator import GoalSettings, Navigator, NavigatorSettings, NavState, in_danger, stale_input
from closed_loop.control.scan import ScanError, validate_scan


class AvoidObstacles(Controller):
    name = 'avoid_obstacles'
    settings_class = NavigatorSettings
    extra_settings_classes = (GoalSettings,)
    ends_at_rest = False

    def __init__(self, settings, context, *extra_settings):
        Controller.__init__(self, settings, context)
        self.navigator = self.make_core(settings, context, *extra_settings)
        self.scan = None
        self.sent = (0.0, 0.0)
        #: The wall time (ms) of each decision that planned, for benchmarks.
        self.decision_ms = []

    def make_core(self, settings, context, *extra_settings):
        """What this controller drives: here the navigator (a subclass drives one with its interface)."""
        return Navigator(settings, context.start, context.goal)

    def after_step(self, now_s, step):
        """Called with each decision's step (a subclass records more from it)."""

    def on_scan(self, now_s, scan, odom):
        try:
            validate_scan(scan)
        except ScanError:
            scan = None
        self.scan = scan
        if scan is None or in_danger(self.sent, scan_points(scan, self.context.laser_pose), self.settings,
                                     self.context.footprint):
            return self.on_tick(now_s, odom)
        return None

    def on_tick(self, now_s, odom):
        if self.scan is None or stale_input(now_s, self.scan.stamp_s, odom.stamp_s, self.settings.scan_timeout):
            self.sent = (0.0, 0.0)
            return self.sent
        started = time.perf_counter()
        try:
            step = self.navigator.update(now_s, (odom.x, odom.y, odom.yaw), odom.v, odom.w, self.scan,
                                         self.context.laser_pose, self.context.footprint)
        except (NavigatorError, ScanError):
            self.sent = (0.0, 0.0)
            return self.sent
        if step.plan is not None:
            self.decision_ms.append((time.perf_counter() - started) * 1e3)
        self.sent = (step.linear_x, step.angular_z)
        self.mode = step.state.name
        self.finished = step.state in (NavState.REACHED, NavState.FAILED)
        self.after_step(now_s, step)
        return self.sent
