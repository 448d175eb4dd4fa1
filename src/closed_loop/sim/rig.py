"""A simulated robot with all its sensors, built from flat ``~parameter`` values as the simulator node
has them: the ROS-free way to run the simulation (tests, benchmarks, batch episodes)."""
import dataclasses
import types

from closed_loop.sim.sensors import all_sensor_classes
from closed_loop.settings import SettingsError, from_params
from closed_loop.sim.simulation import SimSettings, Simulation


class Rig:
    """``sim``: the :class:`Simulation`; ``sensors``: {sensor class: sensor} for those the robot has.

    ``params``: {parameter name (no ``~``): value}, any of SimSettings' and the sensors' settings'
    fields; an unknown name is a :class:`SettingsError`. ``urdf``: URDF text or a path (default robot).
    """

    def __init__(self, world, params=None, urdf=None):
        self.settings, sensor_settings = self.check_params(params)
        render = any(cls.renders(settings) for cls, settings in sensor_settings.items() if settings is not None)
        self.sim = Simulation(world, self.settings, urdf, render=render)
        self.sensors = {}
        for cls, settings in sensor_settings.items():
            sensor = cls(settings, self.sim)
            if sensor.available:
                self.sensors[cls] = sensor

    @staticmethod
    def check_params(params):
        """(SimSettings, {sensor class: its settings or None}) from ``params``, checked without building
        anything; an unknown name or a bad value is a :class:`SettingsError`."""
        params = dict(params or {})
        classes = all_sensor_classes()
        known = {f.name for f in dataclasses.fields(SimSettings)}
        for cls in classes:
            if cls.settings_class is not None:
                known |= {f.name for f in dataclasses.fields(cls.settings_class)}
        unknown = sorted(set(params) - known)
        if unknown:
            raise SettingsError('~%s: not a parameter of the simulator or its sensors' % unknown[0])

        def get(name, default):
            return params.get(name[1:], default)
        return from_params(SimSettings, get), {
            cls: from_params(cls.settings_class, get) if cls.settings_class else None for cls in classes}

    @property
    def all_settings(self):
        """Every settings field of the simulation and its sensors, in one namespace (for reports)."""
        merged = dict(vars(self.settings))
        for sensor in self.sensors.values():
            if sensor.settings is not None:
                merged.update(vars(sensor.settings))
        return types.SimpleNamespace(**merged)

    def sample(self, sensor_class):
        """One reading of the sensor of that class (KeyError if the robot lacks it)."""
        return self.sensors[sensor_class].sample(self.sim)

    def reset_world(self):
        self.sim.reset_world()
        for sensor in self.sensors.values():
            sensor.reset()

    def close(self):
        self.sim.close()
