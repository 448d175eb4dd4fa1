"""When a robot cannot be touching anything: the room it had to the nearest obstacle, less how far it has moved
since. Lets the contact check, which runs every physics step, skip pybullet's contact list (the wheels' points
on the ground among it) while the robot is provably clear of every obstacle. Free of ROS.

The robot's *extent* is how far from its base's position, across the ground, any part of it is now: for a part
rigid with the base, the farthest corner of its bounding box; for a part that turns on a joint (a wheel), the
distance to its joint's origin and the farthest corner from that origin (a revolute joint turns a part about
its origin). Its *reach* is the same in three dimensions, and bounds how far a part can be from the base in any
pose. Between two poses of the base, a part moves by at most the base's displacement plus the reach times the
angle between the two orientations. Obstacles are vertical prisms, their exact footprints measured across the
ground. So while the base has moved less than (distance to the nearest footprint, less the extent, less
:data:`CONTACT_LOOK_M`), nothing can touch.
"""
import math

#: The robot is looked at for contacts wherever it may be this close to an obstacle (m): pybullet lists a
#: contact a little before touching (its contact breaking threshold is 0.02 m).
CONTACT_LOOK_M = 0.05
#: How far beyond its extent (m) the nearest obstacle is looked for when the room is measured.
ROOM_LOOK_M = 1.0
#: Where the room is gone (an obstacle within reach), the robot is looked at every step, and the room measured
#: again once its base has moved this far (m).
REMEASURE_M = 0.05


class BodyExtent:
    """A robot's reach and, for its pose now, its extent (m; see the module's doc), from pybullet's bounding
    boxes of its links; ``call`` makes a pybullet call on the robot's client."""

    def __init__(self, call, pybullet, robot_id, joint_count):
        self._call, self._pybullet, self._robot_id = call, pybullet, robot_id
        base = call(pybullet.getBasePositionAndOrientation, robot_id)[0]
        rigid = {-1: True}
        origins, chain = {-1: base}, {-1: 0.0}
        #: (link, farthest corner from its joint's origin m) for the parts that turn on a joint whose parent
        #: is rigid with the base; the parts rigid with it; the reach.
        self._turning, self._rigid = [], [-1]
        self.reach_m = _farthest(call(pybullet.getAABB, robot_id, -1), base)
        for link in range(joint_count):       # pybullet numbers links so that a parent comes before its children
            info = call(pybullet.getJointInfo, robot_id, link)
            parent = info[16]
            origin = call(pybullet.getLinkState, robot_id, link, computeForwardKinematics=True)[4]
            origins[link] = origin
            box = call(pybullet.getAABB, robot_id, link)
            rigid[link] = rigid[parent] and info[2] == pybullet.JOINT_FIXED
            if rigid[link]:
                self._rigid.append(link)
                self.reach_m = max(self.reach_m, _farthest(box, base))
                continue
            chain[link] = (math.dist(origin, base) if rigid[parent]
                           else chain[parent] + math.dist(origin, origins[parent]))
            self.reach_m = max(self.reach_m, chain[link] + _farthest(box, origin))
            self._turning.append((link, _farthest(box, origin) if rigid[parent] else None))

    def extent_m(self, base):
        """How far any part of the robot is from ``base`` (its base's position now) across the ground (m)."""
        call, p, robot_id = self._call, self._pybullet, self._robot_id
        extent = max(_farthest(call(p.getAABB, robot_id, link), base, 2) for link in self._rigid)
        for link, radius in self._turning:
            if radius is None:                     # on a joint that itself turns: its reach is all that is known
                return self.reach_m
            origin = call(p.getLinkState, robot_id, link, computeForwardKinematics=True)[4]
            extent = max(extent, math.dist(origin[:2], base[:2]) + radius)
        return extent


def _farthest(box, point, axes=3):
    """The distance from ``point`` to the farthest corner of the box (low, high), over its first ``axes`` axes."""
    low, high = box
    return math.sqrt(sum(max(abs(lo - p), abs(hi - p)) ** 2 for lo, hi, p in list(zip(low, high, point))[:axes]))


def turn_rad(q0, q1):
    """The angle (rad) of the rotation between two orientations (quaternions x, y, z, w)."""
    dot = abs(q0[0] * q1[0] + q0[1] * q1[1] + q0[2] * q1[2] + q0[3] * q1[3])
    return 2.0 * math.acos(min(1.0, dot))


class ContactRoom:
    """``clear(position, orientation)``: True when the robot, its base there now, cannot be within
    :data:`CONTACT_LOOK_M` of any obstacle. ``nearest(x, y, within_m)``: a lower bound (m) on the distance
    across the ground from (x, y) to every obstacle, or ``within_m`` if none is nearer; ``body``: the robot's
    :class:`BodyExtent` (or anything with ``reach_m`` and ``extent_m(base)``)."""

    def __init__(self, nearest, body):
        self._nearest = nearest
        self._body = body
        self._reach_m = body.reach_m
        self._anchor = None          # (position, orientation, room m) where the room was last measured

    def forget(self):
        """The robot was put somewhere (a reset): measure again."""
        self._anchor = None

    def clear(self, position, orientation):
        if self._anchor is not None:
            at, q0, room = self._anchor
            # turn_rad inline: this runs at every physics step.
            dot = abs(q0[0] * orientation[0] + q0[1] * orientation[1] + q0[2] * orientation[2] + q0[3] * orientation[3])
            moved = math.dist(position, at) + 2.0 * math.acos(min(1.0, dot)) * self._reach_m
            if moved < room:
                return True
            if room <= 0.0 and moved < REMEASURE_M:
                return False
        extent = self._body.extent_m(position)
        room = self._nearest(position[0], position[1], extent + ROOM_LOOK_M) - extent - CONTACT_LOOK_M
        self._anchor = (position, orientation, room)
        return room > 0.0
