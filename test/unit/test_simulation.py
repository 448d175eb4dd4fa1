"""The pybullet simulator core, for real (DIRECT mode, no ROS): geometry, sensors, driving, contacts."""
import dataclasses
import math
import os

import numpy as np
import pytest

from closed_loop import robot_model
from closed_loop.sim.drive import STOP, VelocityCommand
from closed_loop.settings import SettingsError, check
from closed_loop.sim.rig import Rig
from closed_loop.sim.sensors.camera import CameraSettings, camera_intrinsics
from closed_loop.sim.sensors.lidar import LidarSettings, scan_layout
from closed_loop.sim.simulation import SimSettings
from conftest import SimWithSensors
from closed_loop.sim.obstacles import moving_obstacle_xy
from closed_loop.sim.world import load_world, parse_world

WORLDS_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'worlds'))
DEG = math.pi / 180.0
FRONT = 180                 # index of the ray at angle 0 in the default 360-ray layout
WALL_FACE_X_M = 3.0         # near face of front_wall in worlds/wall.yaml
ROBOT_HALF_LENGTH_M = 0.15  # base_link's box in urdf/closed_loop.urdf is 0.30 m long
# Tolerances: the ray test is exact to float32; physics and rendering are not.
RAY_TOL_M = 1e-3
PIXEL_TOL = 2.0
# A teleop or controller publishes at about this rate; the watchdog must hold between messages.
COMMAND_PERIOD_S = 0.1


def world(name):
    return load_world(os.path.join(WORLDS_DIR, name + '.yaml'))


@pytest.fixture
def make_sim():
    """Build Simulations from a world and settings overrides; every one is closed after the test."""
    sims = []

    def make(a_world, **overrides):
        sim = SimWithSensors(Rig(a_world, overrides))
        sims.append(sim)
        return sim
    yield make
    for sim in sims:
        sim.close()


def steps_for(sim, seconds):
    return int(round(seconds / sim.dt_s))


def run(sim, seconds, twist=None):
    """Step ``seconds`` of simulated time, re-sending ``twist`` every COMMAND_PERIOD_S if given."""
    every = steps_for(sim, COMMAND_PERIOD_S)
    for i in range(steps_for(sim, seconds)):
        if twist is not None and i % every == 0:
            sim.command(twist)
        sim.step()


def ray_angles(sim):
    layout = sim.layout
    return layout.angle_min + layout.angle_increment * np.arange(layout.samples)


def planar_speed(sim):
    (linear, _) = sim.ground_truth()[1]
    return math.hypot(linear[0], linear[1])


# --- scan layout and camera intrinsics ----------------------------------------------------------

def test_scan_layout_full_turn():
    layout = scan_layout(-math.pi, math.pi, 360)
    assert layout.samples == 360
    assert layout.angle_min == -math.pi
    assert layout.angle_increment == pytest.approx(2 * math.pi / 360, rel=1e-12)
    # The last ray stops one increment short of pi: pi itself is the first ray again.
    assert layout.angle_max == pytest.approx(math.pi - layout.angle_increment, rel=1e-12)
    assert layout.angle_min + FRONT * layout.angle_increment == pytest.approx(0.0, abs=1e-12)


def test_scan_layout_full_turn_from_another_start():
    layout = scan_layout(0.0, 2 * math.pi, 8)
    assert layout.angle_increment == pytest.approx(math.pi / 4)
    assert layout.angle_max == pytest.approx(7 * math.pi / 4)


def test_scan_layout_partial_sweep_includes_both_ends():
    layout = scan_layout(-math.pi / 2, math.pi / 2, 181)
    assert layout.angle_increment == pytest.approx(DEG, rel=1e-12)
    assert layout.angle_max == pytest.approx(math.pi / 2, rel=1e-12)
    assert layout.angle_min + 90 * layout.angle_increment == pytest.approx(0.0, abs=1e-12)
    narrow = scan_layout(-0.5, 0.5, 3)
    assert (narrow.angle_min, narrow.angle_max, narrow.angle_increment) == \
        pytest.approx((-0.5, 0.5, 0.5))


def test_scan_layout_single_ray():
    layout = scan_layout(0.25, 1.0, 1)
    assert (layout.angle_min, layout.angle_max, layout.angle_increment, layout.samples) == \
        (0.25, 0.25, 0.0, 1)


def test_camera_intrinsics_centre_and_focal_length():
    intrinsics = camera_intrinsics(320, 240, math.pi / 2)
    # Pixel centres are at integers, so the middle of 320 columns is 159.5, not 160.
    assert (intrinsics.cx, intrinsics.cy) == (159.5, 119.5)
    assert intrinsics.fx == pytest.approx(160.0)
    assert intrinsics.fy == intrinsics.fx
    assert (intrinsics.width, intrinsics.height) == (320, 240)
    narrow = camera_intrinsics(160, 100, 1.085)
    assert narrow.fx == pytest.approx(80.0 / math.tan(0.5425))
    assert (narrow.cx, narrow.cy) == (79.5, 49.5)


# --- SimSettings --------------------------------------------------------------------------------

def test_sim_settings_defaults_pass_their_own_checks():
    assert check(SimSettings()) == SimSettings()
    settings = check(LidarSettings())
    assert settings.range_max > settings.range_min
    assert type(settings.scan_samples) is int
    assert check(CameraSettings()) == CameraSettings()


@pytest.mark.parametrize('overrides,named', [
    ({'range_min': 3.5, 'range_max': 3.5}, '~range_max: '),
    ({'range_min': 2.0, 'range_max': 1.0}, '~range_max: '),
    ({'scan_angle_min': 0.5, 'scan_angle_max': 0.5}, '~scan_angle_max: '),
    ({'scan_angle_min': 1.0, 'scan_angle_max': -1.0}, '~scan_angle_max: '),
    ({'scan_angle_min': -math.pi, 'scan_angle_max': math.pi + 0.01}, '~scan_angle_max: '),
    ({'camera_near': 1.0, 'camera_far': 1.0}, '~camera_far: '),
    ({'camera_near': 2.0, 'camera_far': 0.5}, '~camera_far: '),
])
def test_sim_settings_check_together_rejects_inconsistent_pairs(overrides, named):
    cls = CameraSettings if named.startswith('~camera') else LidarSettings
    with pytest.raises(SettingsError) as caught:
        check(dataclasses.replace(cls(), **overrides))
    assert str(caught.value).startswith(named)


def test_sim_settings_accept_a_full_turn_from_zero():
    settings = check(dataclasses.replace(LidarSettings(), scan_angle_min=0.0, scan_angle_max=2 * math.pi))
    assert settings.scan_angle_max == 2 * math.pi


# --- LIDAR ----------------------------------------------------------------------------------------

def test_lidar_sits_at_the_robot_centre(make_sim):
    sim = make_sim(world('wall'))
    position = sim.link_pose(robot_model.SCAN_FRAME).position
    assert position == pytest.approx((0.0, 0.0, 0.17), abs=0.005)


def test_wall_scan_matches_the_geometry(make_sim):
    sim = make_sim(world('wall'))
    ranges = sim.scan()
    assert ranges.dtype == np.float32
    assert ranges.shape == (360,)
    assert sim.layout == scan_layout(-math.pi, math.pi, 360)
    assert ranges[FRONT] == pytest.approx(WALL_FACE_X_M, abs=RAY_TOL_M)
    slant = WALL_FACE_X_M / math.cos(30 * DEG)
    assert ranges[FRONT - 30] == pytest.approx(slant, abs=RAY_TOL_M)
    assert ranges[FRONT + 30] == pytest.approx(slant, abs=RAY_TOL_M)
    for index in (0, 90, 270, 359):   # behind, right, left, just left of behind
        assert ranges[index] == np.inf
    # Every ray: the plane x = 3 m where it is within range_max (3.5 m, i.e. |angle| < 31 deg).
    angles = ray_angles(sim)
    reach = sim.settings.range_max * np.cos(angles)
    hits = reach > WALL_FACE_X_M + 0.01
    misses = reach < WALL_FACE_X_M - 0.01
    assert hits.sum() == 61   # -30 .. +30 deg
    assert np.allclose(ranges[hits], WALL_FACE_X_M / np.cos(angles[hits]), atol=RAY_TOL_M)
    assert np.all(ranges[misses] == np.inf)


def test_ranges_are_measured_from_the_sensor_not_from_range_min(make_sim):
    # With rays starting 1 m out, "fraction * range_max" would read 2.8 m and
    # "fraction * (range_max - range_min)" 2.0 m; the wall is 3.0 m from the sensor.
    sim = make_sim(world('wall'), range_min=1.0)
    ranges = sim.scan()
    assert ranges[FRONT] == pytest.approx(WALL_FACE_X_M, abs=RAY_TOL_M)
    assert ranges[FRONT + 30] == pytest.approx(WALL_FACE_X_M / math.cos(30 * DEG), abs=RAY_TOL_M)


def test_partial_sweep_points_each_ray_at_its_angle(make_sim):
    sim = make_sim(world('wall'), scan_angle_min=-math.pi / 2, scan_angle_max=math.pi / 2,
                   scan_samples=181)
    ranges = sim.scan()
    assert ranges.shape == (181,)
    assert ranges[90] == pytest.approx(WALL_FACE_X_M, abs=RAY_TOL_M)
    # Index 60 is -30 deg; an off-by-one in the layout would read 3.0 / cos(29 or 31 deg).
    assert ranges[60] == pytest.approx(WALL_FACE_X_M / math.cos(30 * DEG), abs=RAY_TOL_M)
    assert ranges[120] == pytest.approx(WALL_FACE_X_M / math.cos(30 * DEG), abs=RAY_TOL_M)
    assert ranges[0] == np.inf and ranges[180] == np.inf


POST_NEAR_FACE_M = 0.3
POST_HALF_WIDTH_M = 0.05


def post_world():
    """A thin tall post straight ahead, its near face 0.3 m from the LIDAR axis, nothing else."""
    return parse_world({'name': 'post', 'obstacles': [
        {'name': 'post', 'type': 'box', 'position': [POST_NEAR_FACE_M + POST_HALF_WIDTH_M, 0.0],
         'size': [2 * POST_HALF_WIDTH_M, 2 * POST_HALF_WIDTH_M, 1.0]}]})


def test_an_obstacle_closer_than_range_min_reads_minus_inf(make_sim):
    sim = make_sim(post_world(), range_min=0.5)
    ranges = sim.scan()
    angles = np.abs(ray_angles(sim))
    # The post's near corners are atan(0.05 / 0.3) = 9.5 deg off the axis.
    covered = angles < 9 * DEG + 1e-9
    clear = angles > 10 * DEG - 1e-9
    assert covered.sum() == 19
    assert np.all(ranges[covered] == -np.inf)
    assert np.all(ranges[clear] == np.inf)


def test_the_same_obstacle_beyond_range_min_is_measured(make_sim):
    sim = make_sim(post_world())
    ranges = sim.scan()
    angles = ray_angles(sim)
    covered = np.abs(angles) < 9 * DEG + 1e-9
    assert np.allclose(ranges[covered], POST_NEAR_FACE_M / np.cos(angles[covered]), atol=RAY_TOL_M)


def test_noise_free_scans_are_exact_and_repeat(make_sim):
    sim = make_sim(world('wall'))
    first, second = sim.scan(), sim.scan()
    assert np.array_equal(first, second)
    assert first[FRONT] == pytest.approx(WALL_FACE_X_M, abs=RAY_TOL_M)


def noisy_scans(make_sim, seed, count=2, stddev=0.05):
    sim = make_sim(world('wall'), scan_noise_stddev=stddev, noise_seed=seed)
    return [sim.scan() for _ in range(count)]


def test_the_same_seed_gives_the_same_noise(make_sim):
    a = noisy_scans(make_sim, seed=7)
    b = noisy_scans(make_sim, seed=7)
    assert np.array_equal(a[0], b[0])
    assert np.array_equal(a[1], b[1])


def test_a_different_seed_gives_different_noise(make_sim):
    a = noisy_scans(make_sim, seed=7)[0]
    b = noisy_scans(make_sim, seed=8)[0]
    finite = np.isfinite(a)
    assert not np.array_equal(a[finite], b[finite])


def test_noise_is_drawn_afresh_for_each_scan_and_only_on_returns(make_sim):
    exact = make_sim(world('wall')).scan()
    first, second = noisy_scans(make_sim, seed=3)
    finite = np.isfinite(exact)
    # No return stays +inf: noise must not invent an obstacle.
    assert np.array_equal(np.isfinite(first), finite)
    assert not np.array_equal(first[finite], second[finite])
    errors = first[finite] - exact[finite]
    assert 0.025 < float(np.std(errors)) < 0.1
    assert abs(float(np.mean(errors))) < 0.03
    settings = LidarSettings()
    assert np.all((first[finite] >= settings.range_min) & (first[finite] <= settings.range_max))


# --- driving ----------------------------------------------------------------------------------

DRIVE_SPEED_MPS = 0.5


def test_driving_forward_moves_the_robot_and_odometry_agrees(make_sim):
    sim = make_sim(world('wall'))
    run(sim, 1.0, VelocityCommand(DRIVE_SPEED_MPS, 0.0))
    pose = sim.ground_truth()[0]
    # 0.5 m/s for 1 s, less the 0.25 s ramp at 2 m/s^2 (0.0625 m): about 0.44 m.
    assert 0.42 < pose.position[0] < 0.5
    assert abs(pose.position[1]) < 0.01
    assert abs(pose.yaw) < 0.02
    assert sim.odometry.x == pytest.approx(pose.position[0], abs=0.03)
    assert sim.odometry.y == pytest.approx(pose.position[1], abs=0.03)
    assert sim.commanded_twist() == VelocityCommand(DRIVE_SPEED_MPS, 0.0)
    wheel_rps = DRIVE_SPEED_MPS / sim.model.wheel_radius_m
    assert sim.wheel_velocities() == pytest.approx((wheel_rps, wheel_rps), rel=0.05)


def test_the_robot_brakes_to_rest_when_commands_stop(make_sim):
    sim = make_sim(world('wall'))
    run(sim, 1.0, VelocityCommand(DRIVE_SPEED_MPS, 0.0))
    sim.command(VelocityCommand(DRIVE_SPEED_MPS, 0.0))
    timeout_s = sim.settings.cmd_vel_timeout
    # Until the timeout the last command still holds.
    run(sim, timeout_s - 2 * sim.dt_s)
    wheel_rps = DRIVE_SPEED_MPS / sim.model.wheel_radius_m
    assert sim.wheel_velocities() == pytest.approx((wheel_rps, wheel_rps), rel=0.05)
    braking_s = DRIVE_SPEED_MPS / sim.settings.max_linear_accel
    settle_s = 0.1
    run(sim, 2 * sim.dt_s + braking_s + settle_s)
    assert sim.commanded_twist() == STOP
    assert max(abs(w) for w in sim.wheel_velocities()) < 0.05
    assert planar_speed(sim) < 0.01
    before = sim.ground_truth()[0].position
    run(sim, 0.5)
    after = sim.ground_truth()[0].position
    assert math.hypot(after[0] - before[0], after[1] - before[1]) < 0.002


def test_turning_in_place_counter_clockwise(make_sim):
    sim = make_sim(world('empty'))
    run(sim, 1.0, VelocityCommand(0.0, 1.0))
    pose = sim.ground_truth()[0]
    # 1 rad/s for 1 s, less the ramp at 6 rad/s^2 (1/12 rad).
    assert pose.yaw == pytest.approx(1.0 - 1.0 / 12.0, abs=0.05)
    assert math.hypot(pose.position[0], pose.position[1]) < 0.01
    assert sim.odometry.yaw == pytest.approx(pose.yaw, abs=0.05)
    assert math.hypot(sim.odometry.x, sim.odometry.y) < 0.01
    left, right = sim.wheel_velocities()
    assert left < 0.0 < right


@pytest.mark.parametrize('cone', [True, False])
def test_a_skid_steer_turn_in_place_and_the_friction_model(cone):
    # The Jackal told 0.8 rad/s in place, a turn and a half: under its profile's friction pyramid it turns at 0.7 to
    # 1 rad/s at every heading, 0.8 on average; under pybullet's friction cone its rate swings with its heading in
    # the world (it stalls near the world's axes).
    from closed_loop.sim.profiles import load_profile
    profile = load_profile('jackal')
    sim = SimWithSensors(Rig(world('empty'), dict(profile.node_params('sim'), friction_cone=cone), profile.urdf))
    try:
        rates, last = [], None
        for i in range(steps_for(sim, 10.0)):
            if i % steps_for(sim, COMMAND_PERIOD_S) == 0:
                sim.command(VelocityCommand(0.0, 0.8))
                yaw = sim.ground_truth()[0].yaw
                if last is not None and sim.time_s > 1.0:
                    rates.append(math.atan2(math.sin(yaw - last), math.cos(yaw - last)) / COMMAND_PERIOD_S)
                last = yaw
            sim.step()
        slowest, fastest = min(rates), max(rates)
        if cone:
            assert slowest < 0.25 and fastest > 3 * slowest
        else:
            assert 0.7 < slowest and fastest < 1.0 and abs(sum(rates) / len(rates) - 0.8) < 0.05
    finally:
        sim.close()


def test_commands_beyond_the_limits_are_clipped(make_sim):
    sim = make_sim(world('empty'), max_linear_speed=0.3)
    run(sim, 1.0, VelocityCommand(5.0, 0.0))
    assert sim.commanded_twist() == VelocityCommand(0.3, 0.0)
    assert planar_speed(sim) == pytest.approx(0.3, abs=0.02)


# --- contacts and reset -----------------------------------------------------------------------

def drive_until_contact(sim, limit_s=10.0):
    """Drive forward until ``new_contacts`` reports something; return (contacts, time)."""
    for i in range(steps_for(sim, limit_s)):
        if i % steps_for(sim, COMMAND_PERIOD_S) == 0:
            sim.command(VelocityCommand(DRIVE_SPEED_MPS, 0.0))
        sim.step()
        began = sim.new_contacts()
        if began:
            return began, sim.time_s
    raise AssertionError('no contact within %g s' % limit_s)


def contacts_over(sim, seconds, twist=None):
    """Every non-empty ``new_contacts`` result while stepping ``seconds``."""
    reported = []
    every = steps_for(sim, COMMAND_PERIOD_S)
    for i in range(steps_for(sim, seconds)):
        if twist is not None and i % every == 0:
            sim.command(twist)
        sim.step()
        began = sim.new_contacts()
        if began:
            reported.append(began)
    return reported


def test_driving_into_the_wall_is_one_contact(make_sim):
    sim = make_sim(world('wall'))
    began, _ = drive_until_contact(sim)
    assert began == ['front_wall']
    x = sim.ground_truth()[0].position[0]
    assert x + ROBOT_HALF_LENGTH_M == pytest.approx(WALL_FACE_X_M, abs=0.02)
    sim.command(STOP)
    assert contacts_over(sim, 1.0) == []
    assert sim.contact_count == 1
    # Back off and come again: a second contact.
    assert contacts_over(sim, 1.0, VelocityCommand(-0.3, 0.0)) == []
    assert sim.touching() == []
    began, _ = drive_until_contact(sim)
    assert began == ['front_wall']
    assert sim.contact_count == 2


def test_pushing_against_the_wall_stays_one_contact(make_sim):
    sim = make_sim(world('wall'))
    drive_until_contact(sim)
    assert contacts_over(sim, 1.0, VelocityCommand(DRIVE_SPEED_MPS, 0.0)) == []
    assert sim.contact_count == 1


@pytest.mark.parametrize('post_y_m, touches', [(0.3825, False), (0.365, True)])
def test_a_contact_is_a_touch_not_a_point_bullet_lists_a_few_millimetres_apart(post_y_m, touches):
    # Bullet lists contact points a few millimetres apart too, with their distance. A Jackal turning in place
    # beside a post whose corner passes it about 4 mm away touches nothing; 1.75 cm nearer, it does.
    import pybullet
    from closed_loop.sim.profiles import load_profile
    profile = load_profile('jackal')
    post = {'name': 'post', 'type': 'cylinder', 'position': [0.0, post_y_m, 0.5], 'radius': 0.075, 'height': 1.0}
    # Under pybullet's friction cone, where the Jackal's turn stalls and slides and Bullet lists points it passes
    # millimetres away; under the profile's friction pyramid its turn is even and the points it lists are touches.
    sim = SimWithSensors(Rig(parse_world({'name': 'post_beside', 'obstacles': [post]}),
                             dict(profile.node_params('sim'), friction_cone=True), profile.urdf))
    try:
        listed, began, least = [], [], 1.0
        for i in range(steps_for(sim, 8.0)):
            if i % steps_for(sim, COMMAND_PERIOD_S) == 0:
                sim.command(VelocityCommand(0.0, 0.8))
            sim.step()
            began += sim.new_contacts()
            least = min(least, sim.clearance(0.1))
            listed += [c[8] for c in pybullet.getContactPoints(bodyA=sim.robot_id, physicsClientId=sim.client)
                       if c[2] != sim.ground_id]
        assert listed
        if touches:
            assert began == ['post'] and least <= 0.001
        else:
            assert min(listed) > 0.001 and least > 0.001
            assert began == [] and sim.contact_count == 0
    finally:
        sim.close()


def test_reset_after_a_contact_clears_the_count(make_sim):
    sim = make_sim(world('wall'))
    drive_until_contact(sim)
    sim.command(VelocityCommand(DRIVE_SPEED_MPS, 0.0))
    sim.reset_world()
    assert sim.contact_count == 0
    assert sim.touching() == []
    assert contacts_over(sim, 0.3) == []
    position = sim.ground_truth()[0].position
    assert math.hypot(position[0], position[1]) < 0.01


def test_reset_puts_the_robot_back_at_rest_at_its_start(make_sim):
    start = {'x': 0.5, 'y': -0.3, 'yaw': 0.6}
    sim = make_sim(parse_world({'name': 'offset_start', 'robot': {'start': start}}))
    run(sim, 1.0, VelocityCommand(DRIVE_SPEED_MPS, 0.8))
    assert math.hypot(sim.odometry.x, sim.odometry.y) > 0.2
    # A command just before the reset must be forgotten, or the robot would drive off again.
    sim.command(VelocityCommand(DRIVE_SPEED_MPS, 0.8))
    sim.reset_world()
    assert (sim.odometry.x, sim.odometry.y, sim.odometry.yaw) == (0.0, 0.0, 0.0)
    run(sim, 0.3)
    pose = sim.ground_truth()[0]
    assert pose.position[:2] == pytest.approx((start['x'], start['y']), abs=0.01)
    assert pose.yaw == pytest.approx(start['yaw'], abs=0.01)
    assert sim.commanded_twist() == STOP
    assert max(abs(w) for w in sim.wheel_velocities()) < 0.05
    assert (sim.odometry.x, sim.odometry.y, sim.odometry.yaw) == pytest.approx((0.0, 0.0, 0.0), abs=1e-3)


# --- moving obstacles ---------------------------------------------------------------------------

SLIDER_HALF_DEPTH_M = 0.05


def slider_world():
    """A board across the robot's path that slides from x = 1 m to 2 m and back at 0.5 m/s."""
    return parse_world({'name': 'slider', 'obstacles': [
        {'name': 'slider', 'type': 'box', 'position': [1.0, 0.0],
         'size': [2 * SLIDER_HALF_DEPTH_M, 1.0, 1.0],
         'motion': {'waypoints': [[2.0, 0.0]], 'speed': 0.5, 'loop': False}}]})


def test_a_moving_obstacle_moves_between_steps(make_sim):
    sim = make_sim(slider_world())
    slider = sim.world.obstacles[0]

    def expected_front_m():
        # The robot settles on its casters with the LIDAR a millimetre or two off its start.
        sensor_x = sim.link_pose(robot_model.SCAN_FRAME).position[0]
        return moving_obstacle_xy(slider, sim.time_s)[0] - SLIDER_HALF_DEPTH_M - sensor_x

    readings = [sim.scan()[FRONT]]
    assert readings[0] == pytest.approx(0.95, abs=RAY_TOL_M)
    for seconds in (1.0, 1.5):   # to t = 1.0 s and 2.5 s: on the way out, then on the way back
        run(sim, seconds)
        readings.append(sim.scan()[FRONT])
        assert readings[-1] == pytest.approx(expected_front_m(), abs=RAY_TOL_M)
    assert readings == pytest.approx([0.95, 1.45, 1.7], abs=0.01)
    # One physics step moves it by speed * dt.
    sim.step()
    assert readings[-1] - sim.scan()[FRONT] == pytest.approx(0.5 * sim.dt_s, abs=2e-4)
    sim.reset_world()
    assert sim.scan()[FRONT] == pytest.approx(0.95, abs=0.01)


# --- camera -----------------------------------------------------------------------------------

def red_mask(image):
    channels = image.astype(int)
    return (channels[:, :, 0] > 150) & (channels[:, :, 1] < 80) & (channels[:, :, 2] < 80)


def test_camera_sees_the_red_box_ahead(make_sim):
    # Not square, so swapped width and height show up in the shape.
    sim = make_sim(world('red_box'), camera_width=160, camera_height=100)
    image = sim.render_camera()
    assert image.shape == (100, 160, 3)
    assert image.dtype == np.uint8
    red = red_mask(image)
    assert red[45:55, 72:88].all()
    assert not red[:10, :].any()                # sky above the box
    assert not red[:, :20].any() and not red[:, -20:].any()
    # The box's silhouette where a pinhole camera with the published intrinsics puts it.
    k = sim.intrinsics
    camera = sim.link_pose(robot_model.CAMERA_FRAME).position
    depth = 2.5 - camera[0]
    half_width = 0.25
    top_z = 0.5
    cols = np.where(red.any(axis=0))[0]
    rows = np.where(red.any(axis=1))[0]
    assert cols.min() == pytest.approx(k.cx - k.fx * half_width / depth, abs=PIXEL_TOL)
    assert cols.max() == pytest.approx(k.cx + k.fx * half_width / depth, abs=PIXEL_TOL)
    assert rows.min() == pytest.approx(k.cy - k.fy * (top_z - camera[2]) / depth, abs=PIXEL_TOL)


def test_camera_sees_no_red_where_there_is_none(make_sim):
    sim = make_sim(world('wall'), camera_width=160, camera_height=100)
    assert not red_mask(sim.render_camera()).any()


def test_robot_model_reads_its_dimensions_from_the_urdf():
    from closed_loop import robot_model
    model = robot_model.load_robot_model(robot_model.default_urdf_path())
    # urdf/closed_loop.urdf: wheels of radius 0.05 m at y = +-0.14 m; body box 0.30 m long, centred on the LIDAR.
    assert model.wheel_radius_m == pytest.approx(0.05)
    assert model.wheel_separation_m == pytest.approx(0.28)
    assert model.scan_to_front_m == pytest.approx(0.15)


# --- the world view (world_markers) -----------------------------------------------------------------

def test_world_view_sends_a_static_world_once_and_again_after_a_reset(make_sim):
    from closed_loop.sim.sensors.world_state import WorldState
    sim = make_sim(world('corridor'))
    view = sim.rig.sensors[WorldState]
    first = view.sample(sim.rig.sim)
    assert first.news
    assert [o.name for o, _ in first.obstacles] == [o.name for o in sim.world.obstacles]
    assert all(position == o.position for o, position in first.obstacles)
    run(sim, 0.5)
    assert not view.sample(sim.rig.sim).news
    assert view.sample(sim.rig.sim).obstacles == ()
    sim.reset_world()
    assert view.sample(sim.rig.sim).news


def test_world_view_follows_moving_obstacles(make_sim):
    from closed_loop.sim.sensors.world_state import WorldState
    sim = make_sim(slider_world())
    view = sim.rig.sensors[WorldState]
    slider = sim.world.obstacles[0]
    for seconds in (0.0, 1.0, 1.5):
        run(sim, seconds)
        reading = view.sample(sim.rig.sim)
        assert reading.news
        (obstacle, (x, y, z)), = reading.obstacles
        assert obstacle is slider
        assert (x, y) == pytest.approx(moving_obstacle_xy(slider, sim.time_s), abs=1e-6)
        assert z == pytest.approx(slider.position[2])


# --- ground-truth clearance -------------------------------------------------------------------------

def brute_force_clearance(sim, max_m):
    """The least distance to any obstacle, every one asked (what Robot.clearance prunes)."""
    import pybullet
    found = [c[8] for uid in sim.obstacle_uids
             for c in pybullet.getClosestPoints(sim.robot_id, uid, max_m, physicsClientId=sim._client)]
    return min(found, default=math.inf)


@pytest.mark.parametrize('name', ['posts', 'obstacle_course', 'corridor'])
def test_clearance_asks_only_the_near_obstacles_and_finds_the_same_least(make_sim, name):
    sim = make_sim(world(name))
    for seconds, twist in ((0.0, None), (1.0, VelocityCommand(0.4, 0.8)), (1.5, VelocityCommand(0.5, -0.6)),
                           (2.0, VelocityCommand(0.3, 0.0))):
        run(sim, seconds, twist)
        for lookout in (0.3, 1.0, 2.0):
            assert sim.clearance(lookout) == brute_force_clearance(sim, lookout)


def test_clearance_follows_a_moving_obstacle(make_sim):
    sim = make_sim(slider_world())
    values = []
    for _ in range(6):
        run(sim, 0.3)
        values.append(sim.clearance(5.0))
        assert values[-1] == brute_force_clearance(sim, 5.0)
    assert len(set(values)) > 1
