"""Several robots in one world: the world file's robots list, and the simulation running them together."""
import math

import numpy as np
import pytest

from closed_loop import robot_model
from closed_loop.sim.drive import VelocityCommand
from closed_loop.sim.sensors.contacts import Contacts
from closed_loop.sim.sensors.lidar import Lidar, LidarSettings
from closed_loop.sim.simulation import RobotSetup, SimSettings, Simulation
from closed_loop.sim.world import WorldError, parse_world


def two_robots(**r2):
    spec = {'name': 'r2', 'profile': 'closed_loop', 'start': {'x': 2.0, 'y': 0.0, 'yaw': math.pi}}
    spec.update(r2)
    return {'name': 'two', 'robots': [{'name': 'r1', 'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}}, spec]}


def test_robots_are_parsed_with_names_profiles_and_starts():
    world = parse_world(two_robots(profile='burger'))
    assert [(r.name, r.profile) for r in world.robots] == [('r1', 'closed_loop'), ('r2', 'burger')]
    assert world.robots[1].start.x == 2.0 and world.robots[1].start.yaw == pytest.approx(math.pi)
    assert world.robot_start == world.robots[0].start


@pytest.mark.parametrize('change, field, expected', [
    ({'name': 'r1'}, 'robots[1].name', 'a name not already used by robots[0]'),
    ({'name': '2fast'}, 'robots[1].name', 'a name of letters, digits and _'),
    ({'name': 'a/b'}, 'robots[1].name', 'a name of letters, digits and _'),
    ({'profile': '../../etc/x'}, 'robots[1].profile', 'a robot profile name'),
    ({'start': {'x': 0.1, 'y': 0.0, 'yaw': 0.0}}, 'robots[1].start', "a pose clear of robots[0] 'r1'"),
    ({'colour': 'red'}, 'robots[1].colour', ''),
])
def test_bad_robots_are_refused_naming_the_field(change, field, expected):
    with pytest.raises(WorldError) as error:
        parse_world(two_robots(**change), 'w.yaml')
    assert 'w.yaml: %s: expected %s' % (field, expected) in str(error.value)


def test_one_robot_or_several_not_both():
    data = dict(two_robots(), robot={'start': {'x': 0, 'y': 0, 'yaw': 0}})
    with pytest.raises(WorldError, match='either robot'):
        parse_world(data)


def test_each_start_is_checked_against_obstacles_with_its_own_footprint():
    data = two_robots()
    data['obstacles'] = [{'name': 'post', 'type': 'cylinder', 'position': [2.3, 0.0], 'radius': 0.05, 'height': 1}]
    def footprint(profile):
        with open(robot_model.default_urdf_path().replace('closed_loop.urdf', profile + '.urdf')) as f:
            return robot_model.footprint(f.read())
    jackal, small = footprint('jackal'), footprint('closed_loop')
    parse_world(data, footprint={'r1': small, 'r2': small})   # 0.15 + margin clear of the post at 0.30
    with pytest.raises(WorldError, match=r"robots\[1\].start: expected a pose where the robot"):
        parse_world(data, footprint={'r1': small, 'r2': jackal})


@pytest.fixture
def pair():
    world = parse_world(two_robots())
    settings = SimSettings()
    sim = Simulation(world, settings, robots=[RobotSetup(spec.name, settings, None, spec.start)
                                              for spec in world.robots])
    yield sim
    sim.close()


def test_each_lidar_sees_the_other_robot_and_not_its_own_housing(pair):
    for index, other_x in ((0, 2.0), (1, 0.0)):
        view = pair.view(index)
        lidar = Lidar(LidarSettings(scan_samples=360, scan_angle_min=-math.pi, scan_angle_max=math.pi), view)
        ranges = lidar.sample(view)
        front = ranges[180]   # angle 0: straight ahead, toward the other robot
        # The other robot's LIDAR housing (radius 0.035 m) is 2 m away, centre to centre.
        assert front == pytest.approx(2.0 - 0.035, abs=0.01)
        behind = ranges[0]
        assert behind == np.inf   # nothing behind, and its own housing never shows


def test_robots_drive_independently_and_touching_counts_as_contact(pair):
    r1, r2 = pair.view(0), pair.view(1)
    contacts = Contacts(None, r1)
    touched = []
    for step in range(int(8.0 / pair.dt_s)):
        if step % 10 == 0 and not touched:
            r1.command(VelocityCommand(0.3, 0.0))   # until it touches r2; r2 gets no command at all
        pair.step()
        touched += contacts.sample(r1)
    assert touched == ['r2']
    x1 = r1.ground_truth()[0].position[0]
    x2 = r2.ground_truth()[0].position[0]
    assert x1 > 1.5 and x2 - x1 < 0.32   # bodies (0.30 m long) met
    assert r1.odometry.x > 1.5 and abs(r2.odometry.x) < 0.1
