"""The fusion controller's core: the navigator (``closed_loop.control.navigation.navigator``) with an eye for people (lesson
exercise 3). Free of ROS.

Each scan updates the tracks (``closed_loop.control.tracking``); the newest fresh camera detection, if any, is
matched to one (``closed_loop.control.fusion``); each track gets its belief. Then:

- a PERSON track in the robot's path (``fusion.in_path``: up to ``look_ahead`` ahead, within the robot's
  width plus margins, now or where its motion takes it within ``predict_s``), or an UNKNOWN one within
  ``unknown_look_ahead``: WAITING, at rest, until the path has been clear for ``hold_s``; then on to the
  goal, the navigator's progress timers started afresh (a wait is not being stuck). UNKNOWN waits too, the
  more cautious of the two reactions, but only near: a track farther away will be known (STATIC after
  ``static_after``, or PERSON) before the robot gets there;
- otherwise (nothing in the path, or only STATIC tracks and walls) the navigator drives, and goes round
  what is static as it always does.
"""
import dataclasses
import enum
import time

from closed_loop.control.fusion import Belief, associate, belief, fresh_detection, in_path
from closed_loop.control.loop import lasted
from closed_loop.control.navigation.navigator import Navigator, NavState
from closed_loop.control.tracking import Tracker, clusters


class FusionState(enum.Enum):
    """What the fusion controller is doing (its ``~mode``, besides the navigator's own)."""
    WAITING = 'WAITING'


@dataclasses.dataclass(frozen=True)
class Opinion:
    """One track's belief: the track, the belief, why, and whether it is in the robot's path."""
    track: object
    belief: Belief
    why: str
    in_path: bool


@dataclasses.dataclass(frozen=True)
class FusionStep:
    """One decision: the state (``FusionState.WAITING``, or the navigator's ``NavState``), the command,
    why, the navigator's plan if it made one, the opinions of every track, and the navigator's escape's way
    ahead while it follows one."""
    state: enum.Enum
    linear_x: float
    angular_z: float
    reason: str
    plan: object = None
    opinions: tuple = ()
    route: object = None


class FusionNavigator:
    """The navigator, waiting for people (see the module's docstring). ``camera``: a
    ``fusion.CameraModel``, or None for none."""

    def __init__(self, nav_settings, tracker_settings, fusion_settings, wait_settings, start_pose, goal_xy,
                 camera=None, on_transition=None):
        self.navigator = Navigator(nav_settings, start_pose, goal_xy, on_transition=on_transition)
        self.tracker = Tracker(tracker_settings)
        self.fusion_settings, self.wait_settings = fusion_settings, wait_settings
        self.camera = camera
        self.waiting = False
        self._clear_since = None
        self._last_scan = None
        self._detection = None           # (pixel column or None, frame stamp s, robot pose at the frame)
        self.opinions = ()
        #: The wall time (ms) of each scan's tracking, association and beliefs, when ``record_timings`` is set.
        self.record_timings = False
        self.fusion_ms = []

    @property
    def goal(self):
        return self.navigator.goal

    def set_goal(self, goal_xy, now_s=None):
        """Head for a new goal (odom), or hold the start heading (None); the tracks stay."""
        self.navigator.set_goal(goal_xy, now_s)

    def reconfigure(self, settings):
        self.navigator.reconfigure(settings)

    def scanned(self, scan, laser_pose):
        return self.navigator.scanned(scan, laser_pose)

    def remembered(self):
        return self.navigator.remembered()

    def on_detection(self, u, stamp_s, pose):
        """A camera frame's red detection: its pixel column (None: no red in it), stamp and the robot's pose."""
        self._detection = (u, stamp_s, pose)

    def update(self, now_s, pose, v0, w0, scan, laser_pose, footprint):
        if scan is not self._last_scan:
            started = time.perf_counter()
            self._last_scan = scan
            tracks = self.tracker.update(scan.stamp_s, clusters(scan, laser_pose, pose, self.tracker.settings))
            red = None
            if self._detection is not None:
                u, stamp, frame_pose = self._detection
                u = fresh_detection(u, stamp, now_s, self.fusion_settings)
                red = associate(tracks, u, self.camera, frame_pose, self.fusion_settings)
            half_width = 0.5 * (footprint.y_max - footprint.y_min)
            opinions = []
            for t in tracks:
                kind, why = belief(t, red, now_s, self.fusion_settings)
                reach = self.wait_settings.unknown_look_ahead if kind is Belief.UNKNOWN else None
                opinions.append(Opinion(t, kind, why, in_path(t, pose, half_width, now_s, self.wait_settings, reach)))
            self.opinions = tuple(opinions)
            if self.record_timings:
                self.fusion_ms.append((time.perf_counter() - started) * 1e3)
        blocking = [o for o in self.opinions if o.in_path and o.belief is not Belief.STATIC]
        if self.navigator.state in (NavState.REACHED, NavState.FAILED):
            blocking = []
        if blocking:
            self.waiting, self._clear_since = True, None
            o = blocking[0]
            return FusionStep(FusionState.WAITING, 0.0, 0.0, 'waiting: %s track %d in the path (%s)'
                              % (o.belief.name, o.track.id, o.why), None, self.opinions)
        if self.waiting:
            if self._clear_since is None:
                self._clear_since = now_s
            clear_s = now_s - self._clear_since
            if not lasted(clear_s, self.wait_settings.hold_s):
                return FusionStep(FusionState.WAITING, 0.0, 0.0, 'path clear for %.1f s (hold_s %.1f s)'
                                  % (clear_s, self.wait_settings.hold_s), None, self.opinions)
            self.waiting = False
            self.navigator.set_goal(self.navigator.goal, now_s)        # a wait is not being stuck
        step = self.navigator.update(now_s, pose, v0, w0, scan, laser_pose, footprint)
        return FusionStep(step.state, step.linear_x, step.angular_z, step.reason, step.plan, self.opinions,
                          step.route)
