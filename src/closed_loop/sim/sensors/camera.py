"""The camera: an RGB image rendered from its link, looking along the link's +x axis."""
import math
from dataclasses import dataclass

import numpy as np

from closed_loop.sim.sensors import Sensor
from closed_loop.settings import MIN_RATE_HZ, SettingsError, param


@dataclass
class CameraSettings:
    """The camera's ``~parameters`` (the simulator node's)."""
    camera: bool = param(True, '', 'render and publish the camera')
    camera_rate_hz: float = param(10.0, 'Hz', 'camera frames per simulated second', minimum=MIN_RATE_HZ)
    camera_width: int = param(320, 'px', 'image width', minimum=8, maximum=4096)
    camera_height: int = param(240, 'px', 'image height', minimum=8, maximum=4096)
    camera_fov: float = param(1.085, 'rad', 'horizontal field of view', minimum=0.1, maximum=3.0)
    camera_near: float = param(0.02, 'm', 'nearest rendered distance', minimum=0.001)
    camera_far: float = param(30.0, 'm', 'farthest rendered distance', minimum=0.1)

    def check_together(self):
        if not self.camera_far > self.camera_near:
            raise SettingsError('~camera_far: expected more than ~camera_near (%g m), got %r'
                                % (self.camera_near, self.camera_far))


@dataclass(frozen=True)
class CameraIntrinsics:
    """Pinhole intrinsics of the rendered image, OpenCV/ROS convention (pixel centres at integers)."""
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float


def camera_intrinsics(width, height, horizontal_fov_rad):
    """Square pixels; the principal point at the image centre, which is where OpenGL puts the axis."""
    fx = 0.5 * width / math.tan(0.5 * horizontal_fov_rad)
    return CameraIntrinsics(width, height, fx, fx, 0.5 * (width - 1), 0.5 * (height - 1))


class Camera(Sensor):
    """(height, width, 3) uint8 RGB frames from ``~camera_frame``; absent when the robot has no camera
    link or ``~camera`` is false. It samples half a period after the LIDAR, so a frame never delays the
    scan that follows it."""
    settings_class = CameraSettings

    def __init__(self, settings, sim):
        Sensor.__init__(self, settings, sim)
        self.intrinsics = camera_intrinsics(settings.camera_width, settings.camera_height, settings.camera_fov)
        self.frame = sim.model.names.camera_frame
        self._available = bool(settings.camera and sim.model.has_camera)

    @property
    def available(self):
        return self._available

    @staticmethod
    def renders(settings):
        return bool(settings.camera)

    @property
    def period_s(self):
        return 1.0 / self.settings.camera_rate_hz

    @property
    def offset_s(self):
        return 0.5 * self.period_s

    def sample(self, sim):
        s = self.settings
        pose = sim.link_pose(self.frame)
        rotation = sim.rotation_matrix(pose.orientation)
        eye = np.asarray(pose.position)
        vertical_fov = 2.0 * math.atan(math.tan(0.5 * s.camera_fov) * s.camera_height / s.camera_width)
        rgba = sim.render(s.camera_width, s.camera_height, eye, eye + rotation[:, 0], rotation[:, 2],
                          math.degrees(vertical_fov), s.camera_near, s.camera_far)
        return np.ascontiguousarray(rgba[:, :, :3])
