"""The world as the simulator has it: every obstacle's shape, colour and current pose, for rviz.

Not a sensor of the robot but a view of the world that rides on the same schedule: a world without
moving obstacles is sampled as news once (and again after a reset); one with moving obstacles at
``~world_markers_rate_hz``.
"""
from dataclasses import dataclass

from closed_loop.sim.sensors import Sensor
from closed_loop.settings import MIN_RATE_HZ, param


@dataclass
class WorldStateSettings:
    """The world view's ``~parameters`` (the simulator node's)."""
    world_markers_rate_hz: float = param(5.0, 'Hz', 'how often world_markers is sent while obstacles move (a '
                                         'world without moving obstacles is sent once, latched)',
                                         minimum=MIN_RATE_HZ)


@dataclass(frozen=True)
class WorldReading:
    """``obstacles``: [(world.Obstacle, (x, y, z) of its centre now)]; ``news``: worth sending (the first
    sample, the first after a reset, or any sample while obstacles move); empty obstacles and no news
    otherwise."""
    news: bool
    obstacles: tuple


class WorldState(Sensor):
    settings_class = WorldStateSettings

    def __init__(self, settings, sim):
        Sensor.__init__(self, settings, sim)
        self.reset()

    @property
    def period_s(self):
        return 1.0 / self.settings.world_markers_rate_hz

    def reset(self):
        self._sent = False

    def sample(self, sim):
        if self._sent and not sim.has_moving_obstacles:
            return WorldReading(False, ())
        self._sent = True
        return WorldReading(True, tuple(sim.obstacle_positions()))
