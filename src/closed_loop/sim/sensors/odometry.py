"""Odometry: the wheel-odometry pose and twist in the odom frame, with the ground truth beside it."""
from dataclasses import dataclass

from closed_loop.sim.sensors import Sensor
from closed_loop.settings import MIN_RATE_HZ, param


@dataclass
class OdometrySettings:
    """The odometry's ``~parameters`` (the simulator node's)."""
    odom_rate_hz: float = param(50.0, 'Hz', '/odom, /base_pose_ground_truth and the odom TF',
                                minimum=MIN_RATE_HZ)


@dataclass(frozen=True)
class OdometryReading:
    """Dead-reckoned pose (x, y m, yaw rad) and twist in odom, and the true pose and velocity in world."""
    x: float
    y: float
    yaw: float
    twist: object   # commands.VelocityCommand
    truth_pose: object   # robot_body.BodyPose
    truth_velocity: tuple  # ((vx, vy, vz), (wx, wy, wz)) m/s, rad/s in world


class Odometry(Sensor):
    settings_class = OdometrySettings

    @property
    def period_s(self):
        return 1.0 / self.settings.odom_rate_hz

    def sample(self, sim):
        odo = sim.odometry
        pose, velocity = sim.ground_truth()
        return OdometryReading(odo.x, odo.y, odo.yaw, odo.twist, pose, velocity)
