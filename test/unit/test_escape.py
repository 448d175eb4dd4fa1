"""The navigator's escape from a pocket: its footprint plan (hybrid A*, heading first), the follower, and the
rule that keeps a turn in place within the margin from creeping."""
import math

import numpy
import pytest

from closed_loop.control.navigation import escape, hybrid_kernel
from closed_loop.control.safety import footprint_clearance
from closed_loop.control.navigation.situation import Situation
from closed_loop.control.navigation.window import plan
from closed_loop.control.navigation.navigator import NavigatorSettings
from closed_loop.geometry import Pose2D
from closed_loop.robot_model import Footprint
from closed_loop.control.scan import Scan

JACKAL = Footprint(-0.254, 0.254, -0.2155, 0.2155)
MARGIN = 0.055


def wall_with_gap(x, half_gap, step=0.01, half_length=2.5):
    """Points along x = ``x`` from -half_length to half_length but for |y| < half_gap."""
    ys = numpy.arange(-half_length, half_length, step)
    ys = ys[numpy.abs(ys) >= half_gap]
    return numpy.column_stack((numpy.full(len(ys), x), ys))


def check_moves(poses):
    """Each pose follows from the one before by the move it names."""
    for (x, y, yaw, _), (nx, ny, nyaw, m) in zip(poses, poses[1:]):
        direction, turn = hybrid_kernel.MOVES[int(m)]
        ex, ey, eyaw = hybrid_kernel.pose_along(x, y, yaw, direction, turn, 1.0)
        assert (nx, ny) == pytest.approx((ex, ey), abs=1e-9)
        assert math.cos(nyaw - eyaw) == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize('heading', [math.pi / 2, -math.pi / 2, math.pi])
def test_the_plan_passes_a_gap_narrower_than_the_turning_circle_heading_first(heading):
    # Facing along the wall (or away from it), 0.7 m from a gap 0.13 m wider than the Jackal: it cannot turn
    # through the gap, it must line up first.
    half_gap = JACKAL.y_max + MARGIN + 0.04
    points = wall_with_gap(0.7, half_gap)
    assert 2 * half_gap < 2 * JACKAL.radius_m
    poses = escape.find_way(points, (0.0, 0.0, heading), (1.6, 0.0), JACKAL, MARGIN)
    assert poses is not None
    check_moves(poses)
    assert math.hypot(poses[-1, 0] - 1.6, poses[-1, 1]) <= escape.GOAL_RADIUS_M
    # Every pose keeps the margin, but for the reading of the outline between its samples (a few mm).
    least = min(footprint_clearance(points - p[:2], JACKAL, 0.0, 0.0, p[2]) for p in poses)
    assert least >= MARGIN - 0.004
    # It goes through the gap lined up with it (forward or back).
    through = [p for p in poses if abs(p[0] - 0.7) < 0.05]
    assert through and all(abs(math.cos(p[2])) > 0.95 for p in through)


def test_the_plan_keeps_the_doubt_from_what_is_remembered_where_the_scan_cannot_see():
    # The gap above (0.08 m wider than the footprint and its margins), with one side of it remembered where the
    # scan cannot see, 0.09 m in doubt: too narrow for the margin and the doubt; widened by 0.07 m on that side,
    # a way that keeps both.
    half_gap = JACKAL.y_max + MARGIN + 0.04
    points = wall_with_gap(0.7, half_gap)
    left = points[points[:, 1] > 0]
    doubt = numpy.full(len(left), 0.09)
    assert escape.find_way(points, (0.0, 0.0, 0.0), (1.6, 0.0), JACKAL, MARGIN, left, doubt) is None
    left = left + (0.0, 0.07)
    points = numpy.concatenate((points[points[:, 1] < 0], left))
    poses = escape.find_way(points, (0.0, 0.0, 0.0), (1.6, 0.0), JACKAL, MARGIN, left, doubt)
    assert poses is not None
    least = min(footprint_clearance(left - p[:2], JACKAL, 0.0, 0.0, p[2]) for p in poses)
    assert least >= MARGIN + 0.09 - 0.004


def test_no_plan_where_the_gap_is_narrower_than_the_footprint_and_margin():
    half_gap = JACKAL.y_max + MARGIN - 0.02
    assert escape.find_way(wall_with_gap(0.7, half_gap), (0.0, 0.0, 0.0), (1.6, 0.0), JACKAL, MARGIN) is None


def test_no_plan_out_of_a_closed_ring():
    around = numpy.linspace(0, 2 * math.pi, 400, endpoint=False)
    ring = 0.8 * numpy.column_stack((numpy.cos(around), numpy.sin(around)))
    assert escape.find_way(ring, (0.0, 0.0, 0.0), (2.0, 0.0), JACKAL, MARGIN) is None


def test_a_start_already_within_the_margin_may_leave_but_not_come_closer():
    # A wall 0.03 m behind the Jackal's back (within the margin): the plan leaves it, never nearer.
    points = numpy.column_stack((numpy.full(300, JACKAL.x_min - 0.03), numpy.linspace(-1.5, 1.5, 300)))
    poses = escape.find_way(points, (0.0, 0.0, 0.0), (1.0, 0.5), JACKAL, MARGIN)
    assert poses is not None
    clear = [footprint_clearance(points - p[:2], JACKAL, 0.0, 0.0, p[2]) for p in poses]
    assert min(clear) >= 0.03 - escape.PLAN_ROOM_M - 0.004


def test_the_aim_is_along_the_way_followed():
    route = numpy.array([(-0.5, 0.0), (0.0, 0.0), (1.0, 0.0), (1.0, 3.0)])
    assert escape.aim(route, (5.0, 5.0)) == pytest.approx((1.0, 1.0))
    assert escape.aim(None, (3.0, 4.0)) == pytest.approx((1.2, 1.6))
    assert escape.aim(route, (1.0, 1.0)) == (1.0, 1.0)       # the goal is nearer than ESCAPE_AIM_M


@pytest.mark.parametrize('limits', [(escape.SPEED_MPS, escape.MAX_TURN_RADPS), (0.25, 0.4)])
def test_the_follower_brings_a_unicycle_to_the_plan_s_end(limits):
    # The plan through the gap followed from its start by a unicycle that does what it is told, 10 Hz, within
    # the follower's own limits and a slower robot's. The plan's arcs ask more turn than either allows at the
    # follower's speed: a turn rate cut to the limit at that speed drives a wider arc (into the wall here).
    half_gap = JACKAL.y_max + MARGIN + 0.04
    points = wall_with_gap(0.7, half_gap)
    poses = escape.find_way(points, (0.0, 0.0, math.pi / 2), (1.6, 0.0), JACKAL, MARGIN)
    follower = escape.Follower(poses)
    x, y, yaw = 0.0, 0.0, math.pi / 2
    least = math.inf
    for _ in range(600):
        cmd = follower.command((x, y, yaw), limits)
        if cmd is None:
            break
        v, w, why = cmd
        assert why.startswith('escape:') and abs(v) <= limits[0] and abs(w) <= limits[1]
        for _ in range(10):
            x, y, yaw = x + 0.01 * v * math.cos(yaw), y + 0.01 * v * math.sin(yaw), yaw + 0.01 * w
        least = min(least, footprint_clearance(points - (x, y), JACKAL, 0.0, 0.0, yaw))
    assert cmd is None
    assert math.hypot(x - poses[-1, 0], y - poses[-1, 1]) < 0.1
    assert least > 0.03


def test_a_turn_in_place_within_the_margin_must_open_the_clearance():
    # A post just off the Jackal's back left corner, 0.03 m from it (within the 0.05 m margin): a slow turn
    # (the window's slowest, 0.03 rad/s) keeps the clearance but hardly opens it, and is not taken as safe;
    # a fast turn away opens it.
    s = NavigatorSettings(max_speed=1.0, max_yaw_rate=1.5, accel=2.0, yaw_accel=6.0)
    corner = numpy.array([JACKAL.x_min, JACKAL.y_max])
    post = corner + 0.03 * corner / numpy.linalg.norm(corner)
    rays = 720
    angles = -math.pi + numpy.arange(rays) * 2 * math.pi / rays
    ranges = numpy.full(rays, numpy.inf)
    ranges[int(round((math.atan2(post[1], post[0]) + math.pi) / (2 * math.pi / rays))) % rays] = \
        numpy.linalg.norm(post)
    scan = Scan(0.0, 'laser', -math.pi, angles[-1], 2 * math.pi / rays, 0.0, 0.1, 0.05, 8.0, ranges)
    p = plan(Situation(scan, Pose2D(0.0, 0.0, 0.0), JACKAL, 0.0, 0.0, (5.0, 0.0)), s)
    v, w, safe = p.candidates[:, 0], p.candidates[:, 1], p.candidates[:, 3].astype(bool)
    slowest = (v == 0.0) & (numpy.abs(w) > 0) & numpy.isclose(numpy.abs(w), numpy.abs(w[w != 0]).min())
    assert slowest.sum() == 2 and not safe[slowest].any()
    assert safe[(v == 0.0) & (w == w.min())].all()


class Reasons:
    """An episode's onlooker (``closed_loop.batch.lockstep.Tap``'s calls) that keeps the navigator's reasons."""

    def begin(self, rig, controller, judge):
        self.controller, self.reasons, self.routes, self.last = controller, [], [], None

    def decided(self, t_s):
        step = self.controller.step
        if step is None or step is self.last:
            return
        self.last = step
        self.reasons.append(step.reason)
        if step.reason.startswith('escape:'):
            # What ~plan shows while it escapes: the escape's plan ahead of it, from near the robot.
            drawn = self.controller.drawings({'plan'}).get('plan')
            x, y, _ = self.controller.pose
            self.routes.append(drawn is not None and len(drawn.points) >= 1
                               and math.hypot(drawn.points[0][0] - x, drawn.points[0][1] - y)
                               <= hybrid_kernel.MOVE_M + escape.OFF_PLAN_M)

    def scan(self, t_s, ranges):
        pass

    frame = command = stepped = scan


def test_a_jackal_escapes_a_barn_pocket_where_the_window_alone_times_out(monkeypatch):
    # A BARN-method world (fill 0.35, seed 23) where the navigator without its escape times out in a pocket
    # (chosen among the benchmark's: changes to the navigator move which worlds need the escape).
    from closed_loop.batch.episode import EpisodeSpec, run_episode
    spec = EpisodeSpec(world={'generator': {'method': 'barn', 'seed': 23, 'fill': 0.35, 'smoothing': 2}},
                       robot='jackal', controller='avoid_obstacles', time_limit_s=80.0)
    tap = Reasons()
    result = run_episode(spec, tap=tap)
    assert (result.outcome, result.contacts) == ('reached', 0), result.why
    assert any(reason.startswith('escape:') for reason in tap.reasons)
    assert tap.routes and all(tap.routes)
    monkeypatch.setattr(escape, 'ESCAPE_AFTER_S', math.inf)
    alone = run_episode(spec, tap=Reasons())
    assert alone.outcome != 'reached' and alone.contacts == 0, alone.why


@pytest.mark.parametrize('wall_m, slowed', [(0.12, False), (0.07, True)])
def test_a_move_whose_arc_back_onto_the_plan_is_not_safe_is_sent_with_its_turn_slowed(wall_m, slowed):
    # The Jackal 0.06 m right of a plan straight along x: the follower steers left, back onto it (0.2 m/s, 0.18
    # rad/s), toward a wall ``wall_m`` from its left side. Far enough, that command is sent. Nearer, it keeps the
    # margin at no slower speed with that turn (the arc swings the front corner out), and the escape waited
    # until it dropped the plan; now the turn is slowed too.
    from closed_loop.control.navigation.move_check import MoveCheck
    wall = numpy.column_stack((numpy.arange(-1.0, 2.0, 0.01), numpy.full(300, JACKAL.y_max + wall_m)))
    front = Scan(0.0, 'laser', -3 * math.pi / 4, 3 * math.pi / 4, math.pi / 360, 0.0, 0.1, 0.1, 8.0,
                 numpy.full(541, numpy.inf))
    check = MoveCheck(NavigatorSettings(), JACKAL, 0.0, 0.0, front, Pose2D(0.0, 0.0, 0.0), wall, numpy.zeros((0, 2)),
                      numpy.zeros(0), 0.0)
    straight = int(numpy.nonzero((hybrid_kernel.MOVES[:, 0] == 1) & (hybrid_kernel.MOVES[:, 1] == 0))[0][0])
    plan = numpy.array([(x, 0.06, 0.0, straight if x else -1) for x in numpy.arange(0.0, 1.05, 0.1)])
    run = escape.Escape()
    run.follower = escape.Follower(plan)
    v, w, why = run.command(0.0, (0.0, 0.0, 0.0), None, (1.0, 0.06), JACKAL, 0.055, check, 0.5)
    full_v, full_w, _ = escape.Follower(plan).command((0.0, 0.0, 0.0))
    assert full_v == pytest.approx(escape.SPEED_MPS) and full_w > 0.1 and 'along the plan' in why
    speed_only = [check.safe(full_v * f, full_w, 0.5, full_v * f) for f in (1.0, 0.5, 0.25)]
    if not slowed:
        assert (v, w) == pytest.approx((full_v, full_w)) and speed_only[0]
    else:
        assert not any(speed_only)
        assert 0.0 < v < full_v and 0.0 <= w < full_w
        assert check.safe(v, w, 0.5, v)
