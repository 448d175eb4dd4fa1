"""What the navigator shows of itself: the way it follows (``~plan``), what it remembers (``~map``) and its
window (``~window``), from the core (avoid_obstacles) to the ROS messages (closed_loop.nodes.drawing_messages)."""
import math

import numpy
import pytest

from closed_loop.control.navigation import wavefront
from closed_loop.control.drawing import Drawing, Route
from closed_loop.control.scan import scan_points
from closed_loop.control.navigation.navigator import NavigatorSettings
from closed_loop.control.scan import Scan
from closed_loop.control.navigation.memory import CELL_M, ScanMemory
from closed_loop.controllers import Context, Odom
from closed_loop.controllers.avoid_obstacles import MAP_PERIOD_S, AvoidObstacles
from closed_loop.controllers.fusion_controller import FusionController
from closed_loop.geometry import Pose2D
from closed_loop.robot_model import Footprint

JACKAL = Footprint(-0.254, 0.254, -0.2155, 0.2155)
LASER = Pose2D(0.0, 0.0, 0.0)
RAYS = 720


def wall_scan(x=1.5, y0=-2.0, y1=0.6, stamp_s=0.0, rays=RAYS, range_max=8.0):
    """A full-turn scan from the origin of one wall across x = ``x`` from ``y0`` to ``y1``."""
    angles = -math.pi + numpy.arange(rays) * (2 * math.pi / rays)
    with numpy.errstate(divide='ignore', invalid='ignore'):
        t = x / numpy.cos(angles)
        y = t * numpy.sin(angles)
    ranges = numpy.where((t > 0) & (y >= y0) & (y <= y1) & (t <= range_max), t, numpy.inf)
    return Scan(stamp_s, 'base_scan', -math.pi, -math.pi + (rays - 1) * 2 * math.pi / rays, 2 * math.pi / rays,
                0.0, 0.1, 0.12, range_max, ranges)


def test_the_way_round_a_wall_runs_from_the_robot_to_the_goal_and_keeps_its_room():
    points = scan_points(wall_scan(), LASER)
    way = wavefront.way(points, (4.0, 0.0), 0.3, 1.5)
    route = way.route()
    assert tuple(route[0]) == (0.0, 0.0) and tuple(route[-1]) == (4.0, 0.0)
    # It goes round the wall's open end (its left, above y = 0.6), not through it.
    crossing = route[numpy.argmin(numpy.abs(route[:, 0] - 1.5))]
    assert crossing[1] > 0.6
    # Every cell on it keeps the half-width from the wall (to the grid's accuracy), and the aim is on it.
    inner = route[1:-1]
    nearest = numpy.hypot(inner[:, None, 0] - points[None, :, 0], inner[:, None, 1] - points[None, :, 1]).min(axis=1)
    assert nearest.min() >= 0.3 - wavefront.CELL_M / wavefront.FINE
    assert numpy.hypot(*(route - numpy.array(way.aim)).T).min() < 1e-9
    # Steps along it are a cell or a diagonal apart.
    steps = numpy.hypot(*numpy.diff(inner, axis=0).T)
    assert steps.max() <= wavefront.CELL_M * math.sqrt(2) + 1e-9


def test_in_the_open_the_way_is_the_straight_line():
    way = wavefront.way(numpy.zeros((0, 2)), (4.0, 1.0), 0.3, 1.5)
    assert way.route().tolist() == [[0.0, 0.0], [4.0, 1.0]]


def test_the_memory_as_a_grid_has_a_cell_where_each_point_is_and_none_elsewhere():
    memory = ScanMemory(60.0)
    assert not memory.occupancy()[1].any()
    scan = wall_scan()
    memory.add(0.0, (1.0, -2.0, 0.5), scan_points(scan, LASER), scan, LASER)
    (x0, y0), grid = memory.occupancy()
    rows, cols = numpy.nonzero(grid)
    centres = numpy.column_stack((x0 + (cols + 0.5) * CELL_M, y0 + (rows + 0.5) * CELL_M))
    # Each remembered point lies in a marked cell, and each marked cell holds a remembered point.
    for x, y in memory.xy:
        assert grid[int(math.floor((y - y0) / CELL_M + 1e-9)), int(math.floor((x - x0) / CELL_M + 1e-9))]
    assert numpy.abs(centres[:, None, :] - memory.xy[None, :, :]).max(axis=2).min(axis=1).max() <= CELL_M / 2 + 1e-9
    assert grid.sum() == len(memory.xy)


def navigator_at(goal=(4.0, 0.0)):
    core = AvoidObstacles(NavigatorSettings(), Context(LASER, JACKAL, goal))
    return core


def test_the_plan_is_the_way_in_odom_from_where_the_robot_is_and_the_map_comes_once_a_second():
    core = navigator_at(goal=(5.0, 1.0))
    pose = (1.0, 1.0, 0.0)
    sent = {}
    for k in range(25):
        now = 0.1 * k
        odom = Odom(pose[0], pose[1], pose[2], 0.0, 0.0, now)
        core.on_scan(now, wall_scan(stamp_s=now), odom)
        core.on_tick(now, odom)
        for name, value in core.drawings({'window', 'plan', 'map'}).items():
            sent.setdefault(name, []).append((now, value))
    assert len(sent['window']) == len(sent['plan']) == 25
    assert [now for now, _ in sent['map']] == pytest.approx([0.0, 1.0, 2.0])
    assert MAP_PERIOD_S == 1.0
    plan = sent['plan'][-1][1]
    assert isinstance(plan, Route)
    # The goal is 4 m ahead in odom, the wall 1.5 m ahead of the robot: the way starts at the robot, goes round
    # the wall's open end (on the left, in odom above y = 1.6) and ends at the goal.
    points = numpy.array(plan.points)
    assert tuple(points[0]) == pytest.approx((1.0, 1.0)) and tuple(points[-1]) == pytest.approx((5.0, 1.0))
    assert points[numpy.argmin(numpy.abs(points[:, 0] - 2.5)), 1] > 1.6
    # The map is in odom, where the wall is (x = 2.5 m from y = -1 to 1.6).
    drawing = sent['map'][-1][1]
    assert isinstance(drawing, Drawing) and drawing.frame == 'odom' and not drawing.clear
    cells = numpy.array(drawing.shapes[0].points)
    assert numpy.abs(cells[:, 0] - 2.5).max() <= CELL_M
    assert cells[:, 1].min() == pytest.approx(-1.0, abs=CELL_M) and cells[:, 1].max() == pytest.approx(1.6, abs=CELL_M)
    # Only what someone listens to is built.
    assert core.drawings(set()) == {}


def test_the_plan_as_a_ros_path_and_the_map_as_markers():
    rospy = pytest.importorskip('rospy', reason='ROS 1 is not on this interpreter (make compat)')
    from nav_msgs.msg import Path
    from visualization_msgs.msg import MarkerArray
    from closed_loop.nodes.drawing_messages import PUBLICATIONS, to_message
    frames = {'odom': 'odom', 'base': 'base_footprint'}
    stamp = rospy.Time(12, 5)
    msg = to_message(Route(((1.0, 2.0), (3.5, -1.0))), frames, stamp)
    assert PUBLICATIONS[Route] == (Path, False)
    assert isinstance(msg, Path) and msg.header.frame_id == 'odom' and msg.header.stamp == stamp
    assert [(p.pose.position.x, p.pose.position.y, p.pose.orientation.w) for p in msg.poses] == [
        (1.0, 2.0, 1.0), (3.5, -1.0, 1.0)]
    assert all(p.header.frame_id == 'odom' for p in msg.poses)
    remembered = ((0.0, 0.0), numpy.array([[True, False], [False, True]]))
    markers = to_message(AvoidObstacles.map_drawing(remembered), frames, stamp)
    # One marker that replaces the last map in place: no delete-all that rviz could carry out before it.
    assert isinstance(markers, MarkerArray) and [m.action for m in markers.markers] == [markers.markers[0].ADD]
    assert numpy.allclose([(p.x, p.y) for p in markers.markers[0].points], [(0.05, 0.05), (0.15, 0.15)])
    # Nothing remembered: the last map is cleared.
    empty = to_message(AvoidObstacles.map_drawing(((0.0, 0.0), numpy.zeros((1, 1), bool))), frames, stamp)
    assert [m.action for m in empty.markers] == [empty.markers[0].DELETEALL]


def test_the_fusion_controller_shows_the_same_plan_and_map():
    core = FusionController(NavigatorSettings(), Context(LASER, JACKAL, (5.0, 1.0)))
    for k in range(3):
        now = 0.1 * k
        odom = Odom(1.0, 1.0, 0.0, 0.0, 0.0, now)
        core.on_scan(now, wall_scan(stamp_s=now), odom)
        core.on_tick(now, odom)
    drawn = core.drawings({'window', 'plan', 'map'})
    assert isinstance(drawn['plan'], Route) and tuple(drawn['plan'].points[-1]) == pytest.approx((5.0, 1.0))
    cells = numpy.array(drawn['map'].shapes[0].points)
    assert numpy.abs(cells[:, 0] - 2.5).max() <= CELL_M
