"""LIDAR and camera together: which track the red detection is, and what each obstacle ahead is believed to
be (lesson exercise 3). Free of ROS.

**Camera bearing.** A pixel column ``u`` of a pinhole camera with intrinsics ``fx``, ``cx`` (the first row
of ``camera_info``'s K) looks along ``atan2(cx - u, fx)`` from the camera's axis, left positive (the
optical frame's x points right). The camera's pose on the robot is fixed by the URDF (``camera_link``,
``robot_model.frame_pose_2d``), so a track's bearing *as the camera sees it* is computed from the
camera's own position, which keeps the match right for near objects, where the camera and the LIDAR see
them at different angles.

**Association.** The detection is the track within the camera's field of view whose camera bearing is
nearest to the detection's, if that is within ``bearing_tolerance`` plus the half-angle the track's size
subtends. A detection older than ``max_frame_age``, or no camera at all, associates with nothing: the
belief is then the LIDAR's alone.

**Belief rule**, per track:

- PERSON: it is moving (``closed_loop.control.tracking``), or the camera's red detection is matched to it;
- STATIC: it has been tracked for at least ``static_after`` and is neither;
- UNKNOWN: anything younger (not yet seen long enough to tell).
"""
import dataclasses
import enum
import math

from closed_loop.settings import param


class Belief(enum.Enum):
    PERSON = 'PERSON'
    STATIC = 'STATIC'
    UNKNOWN = 'UNKNOWN'


@dataclasses.dataclass
class FusionSettings:
    """The fusion rule's ``~parameters``."""
    bearing_tolerance: float = param(math.radians(4.0), 'rad', 'a detection matches a track whose bearing '
                                     'from the camera is this close (plus the track\'s half-width)',
                                     minimum=0.0, maximum=0.5)
    max_frame_age: float = param(0.5, 's', 'a camera detection older than this is not used', minimum=0.0,
                                 exclusive_minimum=True, maximum=5.0)
    static_after: float = param(1.0, 's', 'a track seen this long, not moving and not red, is STATIC',
                                minimum=0.0, maximum=30.0)


@dataclasses.dataclass(frozen=True)
class CameraModel:
    """What the association needs of the camera: ``fx``, ``cx`` (px), the image width (px), and its pose
    on the robot (``geometry.Pose2D`` of ``camera_link``, x forward)."""
    fx: float
    cx: float
    width: int
    pose: object

    def bearing(self, u):
        """The bearing (rad, left positive, from the camera's axis) of pixel column ``u``."""
        return math.atan2(self.cx - u, self.fx)

    @property
    def half_fov(self):
        return max(math.atan2(self.cx, self.fx), math.atan2(self.width - self.cx, self.fx))

    def bearing_of(self, point_base):
        """The bearing (rad) of a point in the base frame, as the camera sees it."""
        dx, dy = point_base[0] - self.pose.x, point_base[1] - self.pose.y
        return _wrap(math.atan2(dy, dx) - self.pose.yaw)


def _wrap(angle):
    return math.atan2(math.sin(angle), math.cos(angle))


def to_base(robot_pose, x, y):
    """An odom point in the base frame of a robot at ``robot_pose`` (x, y, yaw in odom)."""
    rx, ry, yaw = robot_pose
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = x - rx, y - ry
    return c * dx + s * dy, -s * dx + c * dy


def associate(tracks, detection_u, camera, robot_pose, settings):
    """The track the red detection at pixel column ``detection_u`` is, or None. ``tracks``: the tracker's
    (positions in odom); ``robot_pose``: (x, y, yaw) in odom when the frame was taken."""
    if detection_u is None or camera is None:
        return None
    seen = camera.bearing(detection_u)
    best = None
    for track in tracks:
        bx, by = to_base(robot_pose, track.x, track.y)
        if bx - camera.pose.x <= 0.0:
            continue                                           # behind the camera
        bearing = camera.bearing_of((bx, by))
        if abs(bearing) > camera.half_fov:
            continue
        distance = math.hypot(bx - camera.pose.x, by - camera.pose.y)
        allowed = settings.bearing_tolerance + math.atan2(0.5 * track.size, max(distance, 1e-6))
        off = abs(_wrap(bearing - seen))
        if off <= allowed and (best is None or off < best[0]):
            best = (off, track)
    return None if best is None else best[1]


def belief(track, red_track, now_s, settings):
    """The :class:`Belief` of ``track`` (see the module's rule) and why, given the track the camera
    matched (``red_track``, or None)."""
    if track.moving:
        return Belief.PERSON, 'moving at %.2f m/s' % track.speed
    if red_track is not None and red_track.id == track.id:
        return Belief.PERSON, 'red, matched by the camera'
    if track.age_s(now_s) >= settings.static_after:
        return Belief.STATIC, 'still for %.1f s, not red' % track.age_s(now_s)
    return Belief.UNKNOWN, 'tracked for %.1f s only' % track.age_s(now_s)


def fresh_detection(detection_u, frame_stamp_s, now_s, settings):
    """``detection_u`` if the frame it came from is recent enough (``max_frame_age``), else None."""
    if detection_u is None or frame_stamp_s is None:
        return None
    age = now_s - frame_stamp_s
    return detection_u if -settings.max_frame_age <= age <= settings.max_frame_age else None


@dataclasses.dataclass
class WaitSettings:
    """When the fusion controller waits (its ``~parameters``)."""
    look_ahead: float = param(2.5, 'm', 'a PERSON or UNKNOWN track within this far ahead, in the robot\'s path, '
                              'makes it wait', minimum=0.2, maximum=10.0)
    path_margin: float = param(0.2, 'm', 'the path is the robot\'s width plus this much each side (and the '
                               'track\'s half-size)', minimum=0.0, maximum=2.0)
    predict_s: float = param(2.0, 's', 'a moving track counts as in the path if its straight-line motion '
                             'brings it there within this time', minimum=0.0, maximum=10.0)
    hold_s: float = param(1.0, 's', 'the path must be clear this long before the robot goes on', minimum=0.0,
                          maximum=30.0)
    unknown_look_ahead: float = param(1.0, 'm', 'an UNKNOWN track (too new to tell) makes the robot wait only '
                                      'this near; farther, it will be known before the robot gets there',
                                      minimum=0.2, maximum=10.0)


#: Predicted positions of a moving track are checked this often (s) over ``predict_s``.
PREDICT_STEP_S = 0.25


def in_path(track, robot_pose, half_width, now_s, settings, look_ahead=None):
    """True if ``track`` (odom), now or along its straight-line motion over ``predict_s``, lies in the
    rectangle ahead of a robot at ``robot_pose``: 0 to ``look_ahead`` (default the settings') along its
    heading, ``half_width`` (the robot's half-width) plus ``path_margin`` plus the track's half-size either
    side."""
    look_ahead = settings.look_ahead if look_ahead is None else look_ahead
    reach = half_width + settings.path_margin + 0.5 * track.size
    steps = int(settings.predict_s / PREDICT_STEP_S) if track.moving else 0
    px, py = track.predicted(now_s)
    for k in range(steps + 1):
        t = k * PREDICT_STEP_S
        bx, by = to_base(robot_pose, px + track.vx * t, py + track.vy * t)
        if 0.0 < bx <= look_ahead + 0.5 * track.size and abs(by) <= reach:
            return True
    return False
