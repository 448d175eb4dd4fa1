"""Contacts: which obstacles the robot starts touching, checked every physics step."""
from closed_loop.sim.sensors import Sensor

#: A contact ends only when the robot is this far from the obstacle: pressing against a wall, pybullet's
#: contact list empties for a step now and then, which must not count as a new contact.
CONTACT_RELEASE_M = 0.005


class Contacts(Sensor):
    """``sample`` gives the names of obstacles the robot has started touching since the last sample (the
    ground excluded); ``count`` is how many contacts began since start or the last reset."""

    def __init__(self, settings, sim):
        Sensor.__init__(self, settings, sim)
        self.reset()

    def reset(self):
        self._touching = set()
        self.count = 0

    def sample(self, sim):
        touching = sim.contacts_with_obstacles()
        if not touching and not self._touching:       # the usual step: nothing touched, nothing was
            return []
        touching = set(touching)
        for name in self._touching:
            if sim.within(name, CONTACT_RELEASE_M):
                touching.add(name)
        began = touching - self._touching
        self._touching = touching
        self.count += len(began)
        return sorted(began)

    def touching(self, sim):
        return sorted(self._touching)
