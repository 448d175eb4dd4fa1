"""The contact check skips pybullet's contact list only where the robot provably touches nothing
(closed_loop.sim.contact_room): the same contacts, at the same steps, as looking every step."""
import math
import types

import numpy
import pytest

from closed_loop.batch.episode import load_episode_world
from closed_loop.sim import contact_room
from closed_loop.sim.drive import VelocityCommand
from closed_loop.sim.profiles import load_profile
from closed_loop.sim.quiet import import_pybullet
from closed_loop.sim.rig import Rig
from closed_loop.sim.sensors.contacts import Contacts
from closed_loop.sim.world import parse_world

pybullet = import_pybullet()
COMMANDS = (VelocityCommand(0.8, 0.0), VelocityCommand(0.6, 0.5), VelocityCommand(0.8, -0.3), VelocityCommand(1.0, 0.2),
            VelocityCommand(-0.5, 0.0))


def contacts_while_driving(profile, world, steps=2500):
    """[(step, contacts begun)] for each step at which one began, and how many steps skipped pybullet's list."""
    rig = Rig(world, dict(profile.node_params('sim'), camera=False), profile.urdf)
    skipped = []
    try:
        sim = rig.sim
        room_clear = contact_room.ContactRoom.clear

        def counted(room, position, orientation):
            clear = room_clear(room, position, orientation)
            skipped.append(clear)
            return clear
        contact_room.ContactRoom.clear = counted
        log = []
        for k in range(steps):
            if k % 150 == 0:
                sim.command(COMMANDS[(k // 150) % len(COMMANDS)])
            sim.step()
            began = rig.sensors[Contacts].sample(sim)
            if began:
                log.append((k, tuple(began)))
        return log, sum(skipped)
    finally:
        contact_room.ContactRoom.clear = room_clear
        rig.close()


@pytest.mark.parametrize('robot', ['jackal', 'closed_loop'])
def test_the_same_contacts_at_the_same_steps_as_looking_every_step(robot, monkeypatch):
    profile = load_profile(robot)
    world = load_episode_world({'generator': {'method': 'barn', 'seed': 2, 'fill': 0.45, 'smoothing': 2}}, profile)
    skipping, skipped = contacts_while_driving(profile, world)
    monkeypatch.setattr(contact_room.ContactRoom, 'clear', lambda room, position, orientation: False)
    looking, _ = contacts_while_driving(profile, world)
    assert len(looking) >= 3                     # it drives into posts, backs off and hits others
    assert skipping == looking
    assert skipped > 300                         # and the list was skipped where the robot was clear


@pytest.mark.parametrize('robot', ['jackal', 'burger', 'closed_loop'])
def test_every_part_of_the_robot_stays_within_its_reach_and_extent_however_it_stands(robot):
    """Wheels turned to random angles, the robot tipped and turned: every point of its surface that rays from
    all round hit, within the reach of the base in 3-D and within the extent measured then across the ground."""
    profile = load_profile(robot)
    rig = Rig(parse_world({'name': 'empty', 'obstacles': []}), dict(profile.node_params('sim'), camera=False),
              profile.urdf)
    try:
        sim, robot_id = rig.sim, rig.sim.robot_id
        joints = sim._call(pybullet.getNumJoints, robot_id)
        body = contact_room.BodyExtent(sim._call, pybullet, robot_id, joints)
        rng = numpy.random.default_rng(1)
        farthest = across = 0.0
        for trial in range(20):
            for joint in range(joints):
                sim._call(pybullet.resetJointState, robot_id, joint, float(rng.uniform(-math.pi, math.pi)))
            tilt = 0.0 if trial < 10 else 0.3
            orientation = pybullet.getQuaternionFromEuler([float(v) for v in rng.uniform(-tilt, tilt, 2)] +
                                                          [float(rng.uniform(-math.pi, math.pi))])
            sim._call(pybullet.resetBasePositionAndOrientation, robot_id, [1.0, -2.0, 1.0], orientation)
            sim._call(pybullet.performCollisionDetection)
            base = numpy.array(sim._call(pybullet.getBasePositionAndOrientation, robot_id)[0])
            extent = body.extent_m(tuple(base))
            away = rng.normal(size=(2000, 3))
            starts = base + 2.0 * away / numpy.linalg.norm(away, axis=1)[:, None]
            ends = base + rng.uniform(-1.0, 1.0, (2000, 3)) * profile.footprint.radius_m
            hits = [hit[3] for hit in sim._call(pybullet.rayTestBatch, starts.tolist(), ends.tolist())
                    if hit[0] == robot_id]
            assert len(hits) > 200
            for point in hits:
                farthest = max(farthest, math.dist(point, base))
                across = max(across, math.dist(point[:2], base[:2]) / extent)
                assert math.dist(point, base) <= body.reach_m + 1e-9
                assert math.dist(point[:2], base[:2]) <= extent + 1e-9
        assert farthest > 0.5 * body.reach_m and across > 0.5          # bounds near the body, not the world
        assert body.reach_m < 2.0 * profile.footprint.radius_m + 0.3       # a bound, not the world
    finally:
        rig.close()


def test_a_point_moves_no_farther_than_the_base_and_the_turn_allow():
    rng = numpy.random.default_rng(0)
    for _ in range(200):
        q0, q1 = (tuple(q / numpy.linalg.norm(q)) for q in rng.normal(size=(2, 4)))
        t0, t1 = rng.normal(size=(2, 3))
        point = rng.normal(size=3)
        r0 = numpy.array(pybullet.getMatrixFromQuaternion(q0)).reshape(3, 3)
        r1 = numpy.array(pybullet.getMatrixFromQuaternion(q1)).reshape(3, 3)
        moved = numpy.linalg.norm((t1 + r1 @ point) - (t0 + r0 @ point))
        bound = numpy.linalg.norm(t1 - t0) + contact_room.turn_rad(q0, q1) * numpy.linalg.norm(point)
        assert moved <= bound + 1e-9
    assert contact_room.turn_rad((0, 0, 0, 1), (0, 0, math.sin(0.25), math.cos(0.25))) == pytest.approx(0.5)


def test_the_room_is_measured_again_once_the_robot_has_used_it_up():
    asked = []

    def nearest(x, y, within_m):                    # a wall at x = 3
        asked.append(x)
        return min(within_m, abs(3.0 - x))
    room = contact_room.ContactRoom(nearest, body(0.3))     # room 1.3 - 0.3 - 0.05 = 0.95 m where nothing is near
    level, turned = (0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 1.0, 0.0)
    assert room.clear((0.0, 0.0, 0.0), level) and asked == [0.0]
    assert room.clear((0.9, 0.0, 0.0), level) and asked == [0.0]          # within the room: not asked again
    assert room.clear((1.0, 0.0, 0.0), level) and asked == [0.0, 1.0]     # used up: measured again
    assert room.clear((2.0, 0.0, 0.0), level) and asked[-1] == 2.0        # 1.0 from the wall: 0.65 m of room
    assert not room.clear((2.7, 0.0, 0.0), level)                          # 0.3 from it: none; look at contacts
    assert not room.clear((2.71, 0.0, 0.0), level) and asked[-1] == 2.7   # and every step until it has moved
    room.forget()
    assert room.clear((0.0, 0.0, 0.0), level) and asked[-1] == 0.0
    spun = contact_room.ContactRoom(nearest, body(0.5))                  # room 0.75 m
    assert spun.clear((0.0, 0.0, 0.0), level)
    count = len(asked)
    assert spun.clear((0.0, 0.0, 0.0), turned) and len(asked) == count + 1   # a half turn sweeps 1.57 m: measured again


def body(reach_m):
    """A robot whose reach and extent are both ``reach_m``."""
    return types.SimpleNamespace(reach_m=reach_m, extent_m=lambda base: reach_m)
