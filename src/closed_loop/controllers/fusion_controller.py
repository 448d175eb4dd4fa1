"""fusion_controller's core (``closed_loop.fusion_navigator``), as its node drives it: the navigator's
timer and danger check, and the camera's red detection on each frame."""
import time

import cv2

from closed_loop.controllers import Controller
from closed_loop.fusion import CameraModel, FusionSettings, WaitSettings
from closed_loop.fusion_navigator import FusionNavigator
from closed_loop.guard import scan_points
from closed_loop.local_planner import NavigatorError
from closed_loop.navigator import GoalSettings, NavigatorSettings, NavState, in_danger, stale_input
from closed_loop.scan import ScanError, validate_scan
from closed_loop.tracking import TrackerSettings
from closed_loop.vision import VisionSettings, detect_red


class FusionController(Controller):
    name = 'fusion_controller'
    settings_class = NavigatorSettings
    extra_settings_classes = (GoalSettings, TrackerSettings, FusionSettings, WaitSettings)
    ends_at_rest = False
    uses_camera = True

    def __init__(self, settings, context, goal_settings=None, tracker_settings=None, fusion_settings=None,
                 wait_settings=None):
        Controller.__init__(self, settings, context)
        self.core = FusionNavigator(settings, tracker_settings or TrackerSettings(),
                                    fusion_settings or FusionSettings(), wait_settings or WaitSettings(),
                                    context.start, context.goal)
        self.vision = VisionSettings()
        self.scan = None
        self.sent = (0.0, 0.0)
        self.decision_ms = []
        #: Every step's mode and opinions, for tests: [(t, mode, ((track id, belief, in path), ...))].
        self.log = []

    def on_frame(self, now_s, rgb, intrinsics, odom):
        if self.context.camera_pose is None:
            return
        if self.core.camera is None:
            self.core.camera = CameraModel(intrinsics.fx, intrinsics.cx, intrinsics.width, self.context.camera_pose)
        found = detect_red(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), self.vision)
        self.core.on_detection(found.centroid_px[0] if found.detected else None, now_s,
                               (odom.x, odom.y, odom.yaw))

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
            step = self.core.update(now_s, (odom.x, odom.y, odom.yaw), odom.v, odom.w, self.scan,
                                    self.context.laser_pose, self.context.footprint)
        except (NavigatorError, ScanError):
            self.sent = (0.0, 0.0)
            return self.sent
        self.decision_ms.append((time.perf_counter() - started) * 1e3)
        self.sent = (step.linear_x, step.angular_z)
        self.mode = step.state.name
        self.finished = step.state in (NavState.REACHED, NavState.FAILED)
        self.log.append((now_s, self.mode, tuple((o.track.id, o.belief.name, o.in_path) for o in step.opinions)))
        return self.sent
