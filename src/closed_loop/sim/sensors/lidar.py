"""The LIDAR: a planar sweep of rays cast from its link, REP 117 ranges."""
import math
from dataclasses import dataclass

import numpy as np

from closed_loop.sim.planar_rays import PlanarRays
from closed_loop.sim.sensors import Sensor
from closed_loop.settings import MIN_RATE_HZ, SettingsError, param


@dataclass
class LidarSettings:
    """The LIDAR's ``~parameters`` (the simulator node's)."""
    scan_rate_hz: float = param(10.0, 'Hz', 'LIDAR scans per simulated second', minimum=MIN_RATE_HZ)
    scan_samples: int = param(360, '', 'rays per scan', minimum=1, maximum=8192)
    scan_angle_min: float = param(-math.pi, 'rad', 'angle of the first ray (0 = straight ahead)',
                                  minimum=-2 * math.pi, maximum=2 * math.pi)
    scan_angle_max: float = param(math.pi, 'rad', 'end of the sweep; a full turn is [min, min + 2 pi)',
                                  minimum=-2 * math.pi, maximum=2 * math.pi)
    range_min: float = param(0.12, 'm', 'closer returns are reported as -inf (REP 117)', minimum=0.0)
    range_max: float = param(3.5, 'm', 'no return within this is +inf (REP 117)', minimum=0.0,
                             exclusive_minimum=True)
    scan_noise_stddev: float = param(0.0, 'm', 'Gaussian noise added to each finite range', minimum=0.0)
    noise_seed: int = param(0, '', 'seed of the noise generator (same seed, same noise)', minimum=0)
    ray_caster: str = param('pybullet', '', "how the rays are cast: 'pybullet' (any body), or 'planar' (exact "
                            "for obstacles as vertical prisms, many times faster in clutter; not in a world with "
                            "other robots)", choices=('pybullet', 'planar'))

    def check_together(self):
        if not self.range_max > self.range_min:
            raise SettingsError('~range_max: expected more than ~range_min (%g m), got %r'
                                % (self.range_min, self.range_max))
        if not self.scan_angle_max > self.scan_angle_min:
            raise SettingsError('~scan_angle_max: expected more than ~scan_angle_min (%g rad), got %r'
                                % (self.scan_angle_min, self.scan_angle_max))
        if self.scan_angle_max - self.scan_angle_min > 2 * math.pi + 1e-9:
            raise SettingsError('~scan_angle_max: the sweep may be at most 2 pi rad, got %g rad'
                                % (self.scan_angle_max - self.scan_angle_min))


@dataclass(frozen=True)
class ScanLayout:
    """The angle fields of the scans, as a LaserScan carries them (angle_max is the last ray's angle)."""
    angle_min: float
    angle_max: float
    angle_increment: float
    samples: int


def scan_layout(angle_min, angle_max, samples):
    """Ray angles for a sweep: a full turn gives ``samples`` rays over [min, min + 2 pi); a partial sweep
    puts the first ray at ``angle_min`` and the last at ``angle_max``."""
    span = angle_max - angle_min
    if samples == 1:
        return ScanLayout(angle_min, angle_min, 0.0, 1)
    if abs(span - 2 * math.pi) < 1e-9:
        increment = span / samples
    else:
        increment = span / (samples - 1)
    return ScanLayout(angle_min, angle_min + increment * (samples - 1), increment, samples)


#: How much farther than the footprint's diagonal (m) the rays that look for the robot's own body reach.
OWN_BODY_SLACK_M = 0.1
#: The planar caster is used while the scan plane is this level (the sine of its tilt; the package's robot
#: rests pitched by 0.009); beyond, pybullet's caster (a robot tipping over a bump).
PLANAR_TILT_LIMIT = 0.05
#: The rays the robot's own body stops, by (URDF text, LIDAR frame, ray layout, reach): the same for every
#: simulation of that robot, so a worker running many episodes finds them once.
_OWN_BODY = {}


class Lidar(Sensor):
    """One sweep per period from the robot's LIDAR link (``~scan_frame``): float32 ranges in m."""
    settings_class = LidarSettings

    def __init__(self, settings, sim):
        Sensor.__init__(self, settings, sim)
        self.layout = scan_layout(settings.scan_angle_min, settings.scan_angle_max, settings.scan_samples)
        angles = self.layout.angle_min + self.layout.angle_increment * np.arange(self.layout.samples)
        # The rays' directions in the LIDAR's frame, a row for each axis (so that each axis of them turned is a
        # contiguous row, which the planar caster reads faster).
        self._ray_axes = np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)])
        self._rng = np.random.default_rng(settings.noise_seed)
        self.frame = sim.model.names.scan_frame
        self._planar = None
        if settings.ray_caster == 'planar':
            if len(sim.robots) > 1:
                raise SettingsError("~ray_caster: 'planar' does not see other robots, and this world has %d: "
                                    "expected 'pybullet'" % len(sim.robots))
            self._planar = PlanarRays(sim.world.obstacles)
            self._own_body = None        # the rays the robot's own body stops (in its frame), found once

    @property
    def period_s(self):
        return 1.0 / self.settings.scan_rate_hz

    def sample(self, sim):
        """Each ray is cast from the sensor origin to ``range_max`` (a ray cast from inside the LIDAR's
        housing does not hit it, and hits on the robot's own body are dropped), so a hit's distance is its
        fraction of ``range_max``. Other robots are hit like obstacles. A hit closer than ``range_min``
        is reported as -inf (too close to measure); no return is +inf. With ``~ray_caster`` 'planar', the
        same in the scan's plane (``closed_loop.sim.planar_rays``), the rays the robot's own body stops found
        once with pybullet; pybullet's caster whenever the scan plane tilts."""
        s = self.settings
        pose = sim.link_pose(self.frame)
        rotation = sim.rotation_matrix(pose.orientation)
        dirs = (rotation @ self._ray_axes).T
        origin = np.asarray(pose.position)
        if self._planar is not None and self._own_body is None:
            self._own_body = self._own_body_rays(sim, origin, dirs)
            self._own_body_any = bool(self._own_body.any())
        if self._planar is not None and max(abs(rotation[2, 0]), abs(rotation[2, 1])) <= PLANAR_TILT_LIMIT:
            centres = None if not sim.has_moving_obstacles else [position for _, position in sim.obstacle_positions()]
            fan = (math.atan2(dirs[0, 1], dirs[0, 0]), self.layout.angle_increment) \
                if self.layout.angle_increment > 0 else None
            ranges = self._planar.cast(centres, pose.position, dirs, s.range_max, fan=fan)
            if self._own_body_any:
                ranges[self._own_body] = np.inf
            ranges[ranges < s.range_min] = -np.inf
        else:
            uids, fractions = sim.cast_rays(np.repeat(origin[None, :], len(dirs), axis=0),
                                            origin + dirs * s.range_max)
            is_hit = (uids >= 0) & (uids != sim.robot_id)
            ranges = np.where(is_hit, fractions * s.range_max, np.inf)
            ranges[is_hit & (ranges < s.range_min)] = -np.inf
        if s.scan_noise_stddev > 0:
            finite = np.isfinite(ranges)
            noisy = ranges[finite] + self._rng.normal(0.0, s.scan_noise_stddev, int(finite.sum()))
            ranges[finite] = np.clip(noisy, s.range_min, s.range_max)
        return ranges.astype(np.float32)

    def _own_body_rays(self, sim, origin, dirs):
        """Which rays the robot's own body stops (the robot as it stands, its LIDAR at ``origin``, its rays
        ``dirs``), found with pybullet's caster once per robot and layout in a process."""
        s = self.settings
        # The robot's own body is within its footprint's diagonal of the LIDAR: no need to cast farther; and
        # none of it where no ray can be within that reach (a LIDAR above the body): no need to cast at all.
        fp = sim.model.footprint
        reach = min(s.range_max, math.hypot(fp.length_m, fp.width_m) + OWN_BODY_SLACK_M)
        key = (sim.model.urdf_text, self.frame, self.layout, reach)
        if key not in _OWN_BODY:
            rise = reach * float(np.abs(dirs[:, 2]).max())
            if sim.reaches_height(origin[2] - rise, origin[2] + rise):
                uids, _ = sim.cast_rays(np.repeat(origin[None, :], len(dirs), axis=0), origin + dirs * reach)
                own = uids == sim.robot_id
            else:
                own = np.zeros(len(dirs), bool)
            own.setflags(write=False)
            _OWN_BODY[key] = own
        return _OWN_BODY[key]
