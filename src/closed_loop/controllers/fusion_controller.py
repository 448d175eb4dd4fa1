"""fusion_controller's core (``closed_loop.control.fusion_navigator``), as its node drives it: avoid_obstacles'
timer and danger check, and the camera's red detection on each frame."""
import cv2

from closed_loop.controllers.avoid_obstacles import AvoidObstacles
from closed_loop.control.fusion import CameraModel, FusionSettings, WaitSettings
from closed_loop.control.fusion_navigator import FusionNavigator
from closed_loop.control.navigator import GoalSettings
from closed_loop.control.tracking import TrackerSettings
from closed_loop.control.vision import VisionSettings, detect_red


class FusionController(AvoidObstacles):
    name = 'fusion_controller'
    extra_settings_classes = (GoalSettings, TrackerSettings, FusionSettings, WaitSettings)
    uses_camera = True

    def __init__(self, settings, context, *extra_settings):
        AvoidObstacles.__init__(self, settings, context, *extra_settings)
        self.vision = VisionSettings()
        #: Every step's mode and opinions, for tests: [(t, mode, ((track id, belief, in path), ...))].
        self.log = []

    def make_core(self, settings, context, goal_settings=None, tracker_settings=None, fusion_settings=None,
                  wait_settings=None):
        return FusionNavigator(settings, tracker_settings or TrackerSettings(), fusion_settings or FusionSettings(),
                               wait_settings or WaitSettings(), context.start, context.goal)

    @property
    def timings(self):
        return {'fusion_ms': self.navigator.fusion_ms}

    def on_frame(self, now_s, rgb, intrinsics, odom):
        if self.context.camera_pose is None:
            return
        if self.navigator.camera is None:
            self.navigator.camera = CameraModel(intrinsics.fx, intrinsics.cx, intrinsics.width,
                                                self.context.camera_pose)
        found = detect_red(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), self.vision)
        self.navigator.on_detection(found.centroid_px[0] if found.detected else None, now_s,
                                    (odom.x, odom.y, odom.yaw))

    def after_step(self, now_s, step):
        self.log.append((now_s, self.mode, tuple((o.track.id, o.belief.name, o.in_path) for o in step.opinions)))
