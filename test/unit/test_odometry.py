"""Odometry against ground truth, for the robot profiles whose odometry takes its heading from the gyro."""
import math

import pytest

from closed_loop.geometry import quaternion_yaw
from closed_loop.sim.drive import VelocityCommand
from closed_loop.sim.profiles import load_profile
from closed_loop.sim.rig import Rig
from test_simulation import run, world


@pytest.mark.parametrize('robot', ['burger', 'jackal'])
def test_a_robot_whose_odometry_heading_is_the_gyros_keeps_it_through_turns(robot):
    """The Burger's firmware and the Jackal's EKF take odometry's heading from the IMU: after arcs and turns in
    place its yaw is ground truth's, however the wheels slipped."""
    profile = load_profile(robot)
    assert profile.node_params('sim')['odom_yaw_rate'] == 'gyro'
    rig = Rig(world('empty'), dict(profile.node_params('sim'), camera=False), profile.urdf)
    try:
        sim = rig.sim
        start = sim.robots[0].start
        for twist in (VelocityCommand(0.0, 1.5), VelocityCommand(0.2, -1.0), VelocityCommand(0.0, -2.0)):
            run(sim, 2.0, twist)
        run(sim, 1.0)
        turned = quaternion_yaw(sim.ground_truth()[0].orientation) - start.yaw
        error = math.atan2(math.sin(sim.odometry.yaw - turned), math.cos(sim.odometry.yaw - turned))
        assert abs(error) < math.radians(0.2)
    finally:
        rig.close()
