"""The camera's bearing, its association with LIDAR tracks, and the belief rule (closed_loop.control.fusion)."""
import math

import cv2
import pytest

from closed_loop.control.fusion import Belief, CameraModel, FusionSettings, associate, belief, fresh_detection
from closed_loop.sim.profiles import load_profile
from closed_loop.sim.rig import Rig
from closed_loop.geometry import Pose2D
from closed_loop.control.scan import Scan
from closed_loop.sim.sensors.camera import Camera, camera_intrinsics
from closed_loop.sim.sensors.lidar import Lidar
from closed_loop.control.tracking import Track, Tracker, TrackerSettings, clusters
from closed_loop.control.vision import VisionSettings, detect_red
from closed_loop.sim.world import parse_world

F = FusionSettings()
INTRINSICS = camera_intrinsics(320, 240, 1.085)
CAMERA = CameraModel(INTRINSICS.fx, INTRINSICS.cx, INTRINSICS.width, Pose2D(0.16, 0.0, 0.0))


def track(id_, x, y, moving=False, born_s=0.0, size=0.3):
    return Track(id_, x, y, 0.0, 0.0, born_s, born_s, size, [], moving)


def test_pixel_columns_map_to_bearings_left_positive():
    assert CAMERA.bearing(INTRINSICS.cx) == pytest.approx(0.0)
    assert CAMERA.bearing(-0.5) == pytest.approx(0.5 * 1.085, abs=1e-3)          # the left edge
    assert CAMERA.bearing(319.5) == pytest.approx(-0.5 * 1.085, abs=1e-3)
    assert CAMERA.half_fov == pytest.approx(0.5 * 1.085, abs=1e-2)


def test_a_red_box_rendered_by_the_simulator_is_found_at_its_bearing_and_matched_to_its_track():
    """The real camera and vision: a red box 0.8 m to the left and a blue one to the right; the red
    detection's column gives the red box's bearing from the camera, and associates with its track."""
    world = parse_world({'name': 'two_boxes', 'robot': {'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}}, 'obstacles': [
        {'name': 'red', 'type': 'box', 'position': [2.5, 0.8], 'size': [0.4, 0.4, 0.5], 'color': 'red'},
        {'name': 'blue', 'type': 'box', 'position': [2.5, -0.6], 'size': [0.4, 0.4, 0.5], 'color': 'blue'}]})
    profile = load_profile('closed_loop')
    rig = Rig(world, {'camera': True}, profile.urdf)
    try:
        for _ in range(20):
            rig.sim.step()
        rgb = rig.sample(Camera)
        scan = rig.sample(Lidar)
        lidar = rig.sensors[Lidar]
        intr = rig.sensors[Camera].intrinsics
    finally:
        rig.close()
    camera = CameraModel(intr.fx, intr.cx, intr.width, profile.laser_pose('camera_link'))
    found = detect_red(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), VisionSettings())
    assert found.detected
    u = found.centroid_px[0]
    # The visible faces' middle: the near face's centre (2.3, 0.8) and the side face's pull it a little.
    assert camera.bearing(u) == pytest.approx(math.atan2(0.8, 2.3 - camera.pose.x), abs=math.radians(3.0))
    layout, ls = lidar.layout, lidar.settings
    s = Scan(0.0, 'base_scan', layout.angle_min, layout.angle_max, layout.angle_increment, 0.0, 0.1,
             ls.range_min, ls.range_max, scan)
    tracks = Tracker(TrackerSettings()).update(0.0, clusters(s, profile.laser_pose('base_scan'), (0.0, 0.0, 0.0),
                                                             TrackerSettings()))
    assert len(tracks) == 2
    matched = associate(tracks, u, camera, (0.0, 0.0, 0.0), F)
    assert matched is not None and matched.y > 0.5


def test_near_objects_are_matched_from_the_camera_s_own_position():
    # Two posts 0.4 m ahead of the base, 0.12 m either side; seen from the camera (0.16 m ahead) they are
    # at +-26.6 degrees, from the base at +-16.7: a detection at the camera's angle picks the right one.
    tracks = [track(1, 0.4, 0.12, size=0.05), track(2, 0.4, -0.12, size=0.05)]
    u = INTRINSICS.cx - INTRINSICS.fx * math.tan(math.atan2(0.12, 0.24))
    assert associate(tracks, u, CAMERA, (0.0, 0.0, 0.0), F).id == 1
    # Odom: the robot at (5, 5) facing +y sees the same scene turned.
    moved = [track(1, 5.0 - 0.12, 5.4, size=0.05), track(2, 5.0 + 0.12, 5.4, size=0.05)]
    assert associate(moved, u, CAMERA, (5.0, 5.0, math.pi / 2), F).id == 1


def test_a_detection_off_every_track_or_behind_matches_nothing_and_no_camera_leaves_the_lidar():
    tracks = [track(1, 3.0, 0.0), track(2, -3.0, 0.0)]
    far_left = INTRINSICS.cx - INTRINSICS.fx * math.tan(math.radians(25.0))
    assert associate(tracks, far_left, CAMERA, (0.0, 0.0, 0.0), F) is None
    assert associate(tracks, INTRINSICS.cx, None, (0.0, 0.0, 0.0), F) is None
    assert associate(tracks, None, CAMERA, (0.0, 0.0, 0.0), F) is None


def test_a_stale_frame_is_not_used():
    assert fresh_detection(160.0, 10.0, 10.4, F) == 160.0
    assert fresh_detection(160.0, 10.0, 10.6, F) is None
    assert fresh_detection(160.0, None, 10.0, F) is None


def test_the_belief_rule_with_injected_time():
    walker, red_still, post = track(1, 3, 0, moving=True), track(2, 3, 1), track(3, 3, -1)
    assert belief(walker, None, 0.2, F)[0] is Belief.PERSON
    assert belief(red_still, red_still, 0.2, F)[0] is Belief.PERSON
    assert belief(post, red_still, 0.5, F)[0] is Belief.UNKNOWN          # too young to tell
    kind, why = belief(post, red_still, 1.0, F)
    assert kind is Belief.STATIC and 'not red' in why
