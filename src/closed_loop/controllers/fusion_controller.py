"""fusion_controller: the navigator that waits for people (``closed_loop.control.fusion_navigator``), the
lesson's third exercise.

avoid_obstacles, plus: the scan's clusters tracked in odom, the camera's red detection (from vision_node in
the graph, from the same detector on each frame in an episode) matched to a track through the camera's
intrinsics and its pose in the URDF, and a wait (WAITING, at rest) while a PERSON, or a near UNKNOWN, is in
the path. With no camera the belief is the LIDAR's alone (a moving track is still a person).

Drawings, besides avoid_obstacles': ``belief`` (the decision, why, and every track's id, belief, why,
position, speed and whether it is in the path) and ``tracks`` (in odom: a cylinder per track coloured by
belief, red PERSON, grey STATIC, yellow UNKNOWN, and an arrow for its velocity).
"""
from closed_loop.control.drawing import Drawing, Note, Shape
from closed_loop.control.fusion import Belief, CameraModel, FusionSettings, WaitSettings
from closed_loop.control.fusion_navigator import FusionNavigator
from closed_loop.control.navigation.navigator import GoalSettings
from closed_loop.control.tracking import TrackerSettings
from closed_loop.controllers.avoid_obstacles import AvoidObstacles

BELIEF_COLOURS = {Belief.PERSON: (0.95, 0.2, 0.1, 0.8), Belief.STATIC: (0.6, 0.6, 0.6, 0.8),
                  Belief.UNKNOWN: (1.0, 0.8, 0.0, 0.8)}
TRACK_HEIGHT_M = 0.5
#: Tracks slower than this (m/s) get no velocity arrow.
ARROW_MIN_SPEED_MPS = 0.05


class FusionController(AvoidObstacles):
    name = 'fusion_controller'
    extra_settings_classes = (GoalSettings, TrackerSettings, FusionSettings, WaitSettings)
    uses_camera = True
    outputs = dict(AvoidObstacles.outputs, belief=Note, tracks=Drawing)

    def __init__(self, settings, context, goal_settings=None, tracker_settings=None, fusion_settings=None,
                 wait_settings=None):
        AvoidObstacles.__init__(self, settings, context, goal_settings)
        self.tracker_settings = tracker_settings or TrackerSettings()
        self.fusion_settings = fusion_settings or FusionSettings()
        self.wait_settings = wait_settings or WaitSettings()
        self.camera = None

    def make_core(self, start, goal):
        core = FusionNavigator(self.settings, self.tracker_settings, self.fusion_settings, self.wait_settings,
                               start, goal, self.camera, on_transition=self._on_transition)
        core.record_timings = self.record_timings
        return core

    @property
    def timings(self):
        return {'fusion_ms': [] if self.navigator is None else self.navigator.fusion_ms}

    def on_camera_info(self, fx_px, cx_px, width_px):
        if self.context.camera_pose is None or not fx_px > 0.0 or not width_px:
            return
        self.camera = CameraModel(float(fx_px), float(cx_px), int(width_px), self.context.camera_pose)
        if self.navigator is not None:
            self.navigator.camera = self.camera

    def on_detection(self, u_px, stamp_s, odom):
        if self.navigator is None or odom is None:
            return
        self.navigator.on_detection(float(u_px), stamp_s, (odom.x, odom.y, odom.yaw))

    def after_step(self, now_s, step):
        self._news.update(('belief', 'tracks'))

    def drawings(self, wanted):
        news = self._news
        out = AvoidObstacles.drawings(self, wanted)
        step = self.step
        if step is None:
            return out
        if 'belief' in news and 'belief' in wanted:
            out['belief'] = Note({'mode': step.state.name, 'why': step.reason, 'tracks': [
                {'id': o.track.id, 'belief': o.belief.name, 'why': o.why, 'x': round(o.track.x, 3),
                 'y': round(o.track.y, 3), 'speed': round(o.track.speed, 3), 'in_path': o.in_path}
                for o in step.opinions]})
        if 'tracks' in news and 'tracks' in wanted:
            out['tracks'] = self.tracks_drawing(step.opinions)
        return out

    def tracks_drawing(self, opinions):
        shapes = []
        for o in opinions:
            t, colour = o.track, BELIEF_COLOURS[o.belief]
            size = max(t.size, 0.1)
            shapes.append(Shape('cylinder', 'tracks', 2 * t.id, colour, (size, size, TRACK_HEIGHT_M),
                                position=(t.x, t.y, 0.5 * TRACK_HEIGHT_M)))
            if t.speed > ARROW_MIN_SPEED_MPS:
                shapes.append(Shape('arrow', 'velocities', 2 * t.id + 1, colour, (0.04, 0.08, 0.1),
                                    ((t.x, t.y, TRACK_HEIGHT_M), (t.x + t.vx, t.y + t.vy, TRACK_HEIGHT_M))))
        return Drawing('odom', tuple(shapes), clear=True)
