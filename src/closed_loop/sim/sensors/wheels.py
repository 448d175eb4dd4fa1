"""Wheel encoders: every wheel joint's angle and speed (for /joint_states and robot_state_publisher)."""
from dataclasses import dataclass

from closed_loop.sim.sensors import Sensor
from closed_loop.settings import MIN_RATE_HZ, param


@dataclass
class WheelSettings:
    """The wheel encoders' ``~parameters`` (the simulator node's)."""
    joint_states_rate_hz: float = param(20.0, 'Hz', '/joint_states (the wheels, for robot_state_publisher '
                                        'and rviz)', minimum=MIN_RATE_HZ)


class WheelEncoders(Sensor):
    """``sample`` gives (joint names, positions rad, velocities rad/s), left wheels first."""
    settings_class = WheelSettings

    @property
    def period_s(self):
        return 1.0 / self.settings.joint_states_rate_hz

    def sample(self, sim):
        return sim.wheel_joint_states()
