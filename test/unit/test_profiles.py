"""Robot profiles: urdf/<name>.urdf plus config/robots/<name>.yaml, read the way the launch files read them;
the simulator core drives each robot and lays out its LIDAR as the profile says."""
import dataclasses
import math
import os

import pytest
import yaml

from closed_loop import robot_model
from closed_loop.control.scan import DetectorSettings, Scan, sector_readings
from closed_loop.settings import check
from closed_loop.sim.rig import Rig
from closed_loop.sim.simulation import SimSettings
from conftest import SimWithSensors
from closed_loop.sim.obstacles import footprint_overlaps
from closed_loop.sim.world import Pose2D, load_world, parse_world

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
PROFILES = ('closed_loop', 'burger', 'jackal')


def profile(name):
    """(URDF text, the profile's sim_node overrides as SimSettings, the overrides as given)."""
    with open(os.path.join(ROOT, 'config', 'robots', name + '.yaml')) as stream:
        overrides = dict((yaml.safe_load(stream) or {}).get('sim', {}), camera=False)
    with open(os.path.join(ROOT, 'urdf', name + '.urdf')) as stream:
        urdf = stream.read()
    sim_fields = {f.name for f in dataclasses.fields(SimSettings)}
    settings = check(dataclasses.replace(SimSettings(), **{k: v for k, v in overrides.items() if k in sim_fields}))
    return urdf, settings, overrides


def rig(name):
    urdf, _settings, overrides = profile(name)
    return SimWithSensors(Rig(load_world(os.path.join(ROOT, 'worlds', 'wall.yaml')), overrides, urdf))


@pytest.mark.parametrize('name', PROFILES)
def test_every_profile_has_its_urdf_and_only_known_parameters(name):
    urdf, settings, overrides = profile(name)
    Rig(load_world(os.path.join(ROOT, 'worlds', 'wall.yaml')), overrides, urdf).close()  # no unknown parameter
    model = robot_model.load_robot_model(urdf, settings.names)
    assert model.footprint.length_m > 0 and model.footprint.width_m > 0
    assert model.scan_to_front_m > 0


@pytest.mark.parametrize('name, length, width', [('burger', 0.140, 0.178), ('jackal', 0.508, 0.430)])
def test_footprints_are_the_published_sizes(name, length, width):
    urdf, settings, _ = profile(name)
    fp = robot_model.load_robot_model(urdf, settings.names).footprint
    assert (fp.length_m, fp.width_m) == pytest.approx((length, width), abs=0.002)


@pytest.mark.parametrize('name', PROFILES)
def test_each_robot_drives_straight_and_turns_in_the_core(name):
    sim = rig(name)
    try:
        from closed_loop.sim.drive import VelocityCommand
        speed = min(0.2, sim.settings.max_linear_speed)
        for i in range(int(2.0 / sim.dt_s)):
            if i % 10 == 0:
                sim.command(VelocityCommand(speed, 0.0))
            sim.step()
        pose, _ = sim.ground_truth()
        assert pose.position[0] == pytest.approx(speed * 2.0, abs=0.12)
        assert abs(pose.position[1]) < 0.05 and abs(pose.yaw) < 0.1
        for i in range(int(1.5 / sim.dt_s)):
            if i % 10 == 0:
                sim.command(VelocityCommand(0.0, 1.0))
            sim.step()
        assert abs(sim.ground_truth()[0].yaw) > 0.5, 'did not turn'
        ranges = sim.scan()
        assert len(ranges) == sim.settings.scan_samples
    finally:
        sim.close()


def test_burger_scan_starts_straight_ahead():
    sim = rig('burger')
    try:
        sim.step()
        ranges = sim.scan()
        assert sim.layout.angle_min == 0.0 and len(ranges) == 360
        assert ranges[0] == pytest.approx(3.0 + 0.032, abs=0.01)  # the LDS-01 sits 0.032 m behind the base
        assert math.isinf(ranges[180])
    finally:
        sim.close()


def test_start_check_uses_the_robots_footprint():
    data = {'name': 'w', 'obstacles': [{'name': 'post', 'type': 'cylinder', 'position': [0.3, 0.0],
                                        'radius': 0.05, 'height': 1.0}]}
    burger_fp = robot_model.footprint(profile('burger')[0])
    jackal_fp = robot_model.footprint(profile('jackal')[0])
    # 0.3 m ahead: clear of the Burger's 0.038 m nose (with the 0.05 m margin), inside the Jackal's.
    assert parse_world(data, footprint=burger_fp).name == 'w'
    with pytest.raises(Exception, match='robot.start'):
        parse_world(data, footprint=jackal_fp)


def test_footprint_overlap_of_a_turned_robot_and_box():
    fp = robot_model.Footprint(-0.25, 0.25, -0.1, 0.1)
    box = parse_world({'name': 'b', 'robot': {'start': {'x': 9.0, 'y': 9.0, 'yaw': 0.0}}, 'obstacles': [{'name': 'b', 'type': 'box', 'position': [0.0, 0.33],
                                                   'size': [0.2, 0.2, 0.2]}]}).obstacles[0]
    assert not footprint_overlaps(box, Pose2D(0, 0, 0), fp)
    assert footprint_overlaps(box, Pose2D(0, 0, math.pi / 2), fp)


def test_sectors_turn_with_the_laser_mounting():
    import numpy
    ranges = numpy.full(360, numpy.inf)
    ranges[260] = 1.0  # at -100 degrees in the laser frame (angle_min 0)
    scan = Scan(stamp_s=0.0, frame_id='l', angle_min=0.0, angle_max=2 * math.pi * 359 / 360,
                angle_increment=2 * math.pi / 360, time_increment=0.0, scan_time=0.1, range_min=0.1,
                range_max=5.0, ranges=ranges)
    settings = check(DetectorSettings())
    assert sector_readings(scan, settings)['right'].distance_m == 1.0
    assert math.isinf(sector_readings(scan, settings)['front'].distance_m)
    # A laser mounted turned +90 degrees on the robot: robot-forward is -90 degrees in its frame.
    assert sector_readings(scan, settings, forward_rad=-math.pi / 2)['front'].distance_m == 1.0
