"""Unit tests import closed_loop from the source tree; no ROS master is needed or started."""
import os
import sys

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
if SRC not in sys.path:
    sys.path.insert(0, SRC)
# test/machine.py: what this machine lets a test do.
TEST = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
if TEST not in sys.path:
    sys.path.insert(0, TEST)


class SimWithSensors:
    """A :class:`closed_loop.sim.rig.Rig` read the way these tests read it: ``scan()``, ``render_camera()``,
    ``new_contacts()`` and the simulation's own attributes; ``settings`` holds every settings field."""

    def __init__(self, rig):
        from closed_loop.sim.sensors.camera import Camera
        from closed_loop.sim.sensors.contacts import Contacts
        from closed_loop.sim.sensors.lidar import Lidar
        self.rig = rig
        self._lidar, self._camera, self._contacts = Lidar, Camera, Contacts
        self.settings = rig.all_settings

    def __getattr__(self, name):
        return getattr(self.rig.sim, name)

    def scan(self):
        return self.rig.sample(self._lidar)

    def render_camera(self):
        return self.rig.sample(self._camera)

    def new_contacts(self):
        return self.rig.sample(self._contacts)

    @property
    def contact_count(self):
        return self.rig.sensors[self._contacts].count

    def touching(self):
        return self.rig.sensors[self._contacts].touching(self.rig.sim)

    @property
    def layout(self):
        return self.rig.sensors[self._lidar].layout

    @property
    def intrinsics(self):
        return self.rig.sensors[self._camera].intrinsics

    def reset_world(self):
        self.rig.reset_world()

    def close(self):
        self.rig.close()
