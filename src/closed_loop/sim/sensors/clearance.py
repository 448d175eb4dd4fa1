"""Clearance: the least distance between the robot's collision shapes and any obstacle or other robot, by
pybullet's closest points (ground truth, for judging a scenario; no real robot has it)."""
from dataclasses import dataclass

from closed_loop.settings import MIN_RATE_HZ, param
from closed_loop.sim.sensors import Sensor


@dataclass
class ClearanceSettings:
    """The ground-truth clearance's ``~parameters`` (the simulator node's)."""
    clearance_rate_hz: float = param(10.0, 'Hz', 'the ground-truth clearance (clearance), while someone listens',
                                     minimum=MIN_RATE_HZ)
    clearance_lookout: float = param(2.0, 'm', 'clearance is looked for up to this far; beyond, it reads +inf',
                                     minimum=0.0, exclusive_minimum=True, maximum=30.0)


class Clearance(Sensor):
    """``sample`` gives the least distance (m): +inf beyond the lookout, 0 or less in contact."""
    settings_class = ClearanceSettings

    @property
    def period_s(self):
        return 1.0 / self.settings.clearance_rate_hz

    def sample(self, sim):
        return sim.clearance(self.settings.clearance_lookout)
