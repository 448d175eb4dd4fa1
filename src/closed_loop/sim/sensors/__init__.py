"""The simulated robot's sensors, one small class per file, each with its own settings and period.

A sensor samples a :class:`closed_loop.sim.simulation.Simulation` (which owns the world, the robot and
``step()``, and nothing else) and returns plain values; it knows nothing of ROS. The simulator node
keeps one table that maps each sensor to its message conversion and publishers, and one scheduler that
drives them all at their periods on simulated time.

The contract of a sensor class:

- ``settings_class``: a settings dataclass (its fields are the node's ``~parameters``), or None;
- ``__init__(settings, sim)``; ``available`` False when the robot lacks it (no camera link);
- ``period_s`` (None: every physics step) and ``offset_s`` (when in the period it samples);
- ``sample(sim)``: one reading; ``reset()``: forget state when the world is reset;
- ``renders(settings)``: True when, with these settings, it looks at the world's visual shapes (a camera):
  without any such sensor the simulation builds none.

Adding a sensor: a file here with such a class, a conversion to its message in
``closed_loop.nodes.sim_node``, and one line in that node's ``SENSORS`` table (docs/development.md, "Adding a sensor").
"""


import functools
import importlib
import pkgutil


def all_sensor_classes():
    """Every sensor class of this package (a :class:`Sensor` subclass in one of its modules), by name."""
    _import_modules()
    return sorted(Sensor.__subclasses__(), key=lambda cls: cls.__name__)


@functools.lru_cache(maxsize=None)
def _import_modules():
    """Import every module of this package, once."""
    for module in pkgutil.iter_modules(__path__):
        importlib.import_module('%s.%s' % (__name__, module.name))


class Sensor:
    """Defaults of the sensor contract (see the package docstring)."""
    settings_class = None
    offset_s = 0.0

    def __init__(self, settings, sim):
        self.settings = settings

    @property
    def available(self):
        return True

    @staticmethod
    def renders(settings):
        """True if a sensor of these settings renders the world (the obstacles then need their looks)."""
        return False

    @property
    def period_s(self):
        return None

    def sample(self, sim):
        raise NotImplementedError

    def reset(self):
        """Forget what was sensed before a world reset (most sensors keep nothing)."""
