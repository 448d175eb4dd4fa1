"""Clusters of scan points in odom and tracks over time (closed_loop.control.tracking), on synthetic scans."""
import math

import pytest

from closed_loop.geometry import Pose2D
from closed_loop.control.tracking import Tracker, TrackerSettings, clusters
from test_navigator import scan_of

LASER = Pose2D(0.0, 0.0, 0.0)
S = TrackerSettings()


def scan_from(pose, circles=(), segments=(), rays=720):
    """A scan taken by a robot at ``pose`` (x, y, yaw in odom) of discs and segments given in odom."""
    x, y, yaw = pose
    c, s = math.cos(yaw), math.sin(yaw)

    def local(px, py):
        dx, dy = px - x, py - y
        return c * dx + s * dy, -s * dx + c * dy
    return scan_of([local(cx, cy) + (r,) for cx, cy, r in circles],
                   [(local(*a), local(*b)) for a, b in segments], rays=rays)


def test_discs_and_a_wall_are_three_clusters_each_where_it_is():
    found = clusters(scan_from((0, 0, 0), circles=[(2.0, 1.0, 0.2), (3.0, -1.0, 0.1)],
                               segments=[((-1.0, 3.0), (4.0, 3.0))]), LASER, (0.0, 0.0, 0.0), S)
    assert len(found) == 3
    discs = sorted((c for c in found if c.size < 1.0), key=lambda c: c.x)
    wall = [c for c in found if c.size >= 1.0]
    assert len(wall) == 1 and wall[0].size > 4.0
    for cluster, (cx, cy, r) in zip(discs, [(2.0, 1.0, 0.2), (3.0, -1.0, 0.1)]):
        assert math.hypot(cluster.x - cx, cluster.y - cy) < r          # the visible face's mean
        assert cluster.size <= 2 * r + 1e-6


def test_a_far_object_stays_one_cluster_and_two_near_ones_do_not_merge():
    far = clusters(scan_from((0, 0, 0), circles=[(7.5, 0.0, 0.25)], rays=360), LASER, (0, 0, 0), S)
    assert len(far) == 1
    near = clusters(scan_from((0, 0, 0), circles=[(2.0, 0.15, 0.05), (2.0, -0.15, 0.05)]), LASER, (0, 0, 0), S)
    assert len(near) == 2


def test_an_object_behind_where_the_scan_wraps_is_one_cluster():
    found = clusters(scan_from((0, 0, 0), circles=[(-2.0, 0.0, 0.2)]), LASER, (0.0, 0.0, 0.0), S)
    assert len(found) == 1 and found[0].x == pytest.approx(-1.85, abs=0.1)


def test_clusters_are_placed_in_odom_from_the_robot_pose():
    pose = (1.0, 2.0, math.pi / 2)
    found = clusters(scan_from(pose, circles=[(1.0, 4.0, 0.2)]), LASER, pose, S)
    assert len(found) == 1 and math.hypot(found[0].x - 1.0, found[0].y - 3.85) < 0.1


def run(tracker, poses_and_objects, dt=0.1):
    for k, (pose, circles) in enumerate(poses_and_objects):
        tracks = tracker.update(k * dt, clusters(scan_from(pose, circles=circles), LASER, pose, S))
    return tracks


def test_a_walker_is_moving_with_its_velocity_and_a_post_is_not_while_the_robot_drives():
    # The robot drives at 0.5 m/s along x; a walker crosses at 1 m/s along y; a post stands still.
    frames = [((0.05 * k, 0.0, 0.0), [(4.0, -2.0 + 0.1 * k, 0.2), (3.0, 1.5, 0.1)]) for k in range(20)]
    tracks = run(Tracker(S), frames)
    walker = min(tracks, key=lambda t: abs(t.x - 4.0))
    post = min(tracks, key=lambda t: math.hypot(t.x - 3.0, t.y - 1.5))
    assert walker is not post and len(tracks) == 2
    assert walker.moving and walker.vx == pytest.approx(0.0, abs=0.1) and walker.vy == pytest.approx(1.0, abs=0.1)
    assert not post.moving and post.speed < 0.05
    assert walker.age_s(1.9) == pytest.approx(1.9)


def test_a_track_is_not_moving_before_its_history_spans_the_window():
    frames = [((0.0, 0.0, 0.0), [(3.0, -1.0 + 0.1 * k, 0.2)]) for k in range(5)]
    (track,) = run(Tracker(S), frames)
    assert track.speed > 0.5 and not track.moving


def test_the_robot_turning_in_place_does_not_move_a_still_object():
    frames = [((0.0, 0.0, 0.15 * k), [(2.0, 1.0, 0.2)]) for k in range(20)]
    (track,) = run(Tracker(S), frames)
    assert not track.moving and track.speed < 0.05


def test_a_jump_beyond_the_gate_is_a_new_track_and_an_unseen_track_is_dropped():
    tracker = Tracker(S)
    run(tracker, [((0, 0, 0), [(2.0, 0.0, 0.2)])])
    tracks = tracker.update(0.1, clusters(scan_from((0, 0, 0), circles=[(2.0, 2.0, 0.2)]), LASER, (0, 0, 0), S))
    assert sorted(t.id for t in tracks) == [1, 2]
    assert [t.id for t in tracker.update(1.15, [])] == []         # both unseen for over track_timeout


def test_a_wall_is_not_tracked():
    tracker = Tracker(S)
    assert tracker.update(0.0, clusters(scan_from((0, 0, 0), segments=[((2.0, -3.0), (2.0, 3.0))]),
                                        LASER, (0, 0, 0), S)) == []


def test_no_returns_no_clusters():
    assert clusters(scan_from((0, 0, 0)), LASER, (0, 0, 0), S) == []
