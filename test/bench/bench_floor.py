#!/usr/bin/env python3
"""The physics floor, and what an episode costs beside it.

Run: ``python3 test/bench/bench_floor.py`` inside ``source env.sh`` (``make bench`` does that).

The floor: CPU per simulated second of the simulator's step alone (``Simulation.step``: pybullet's
``stepSimulation`` and the drive's few lines around it, no sensor sampled, no controller), for each robot
profile in ``empty``, in ``posts`` (208 thin posts) and in a generated world of its class at fill 1.0
(``closed_loop.sim.clutter``). Then an episode of ``stop_on_obstacle`` (``empty``, ``posts``) and of
``avoid_obstacles`` (the generated world, to its goal 10 m ahead) in the same world: its CPU per simulated second as a
multiple of the floor, and its speed (simulated s per CPU s). Targets: at most 1.5x the floor with
stop_on_obstacle in ``empty`` and ``posts``; at least 40x real time for the Jackal with avoid_obstacles among
about 300 posts. Figures, not pass/fail.
"""
import os
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402
from closed_loop.sim.clutter import ClutterSettings, generate  # noqa: E402
from closed_loop.sim.profiles import load_profile  # noqa: E402
from closed_loop.sim.rig import Rig  # noqa: E402
from closed_loop.sim.world import load_world, parse_world, resolve_world  # noqa: E402

PROFILES = ('closed_loop', 'burger', 'jackal')
FLOOR_S, EPISODE_S = 20.0, 30.0
TARGET_RATIO, TARGET_CLUTTER_SPEED = 1.5, 40.0


def floor_cpu_per_s(world, profile):
    """CPU s per simulated s of stepping ``world`` (a World) with ``profile``'s robot, nothing else."""
    rig = Rig(world, dict(profile.node_params('sim'), camera=False), profile.urdf)
    try:
        steps = int(round(FLOOR_S / rig.sim.dt_s))
        for _ in range(50):
            rig.sim.step()
        started = time.process_time()
        for _ in range(steps):
            rig.sim.step()
        return (time.process_time() - started) / (steps * rig.sim.dt_s)
    finally:
        rig.close()


def episode_cpu_per_s(spec):
    run_episode(spec, {})
    started = time.process_time()
    result = run_episode(spec, {})
    return (time.process_time() - started) / max(result.time_s, 1e-9), result


def main():
    print('CPU per simulated s: the floor (step alone) and an episode; the ratio; the episode\'s speed')
    for name in PROFILES:
        profile = load_profile(name)
        generated = generate(ClutterSettings(profile=name, fill_ratio=1.0, seed=0).check(), profile)
        cases = [('empty', 'stop_on_obstacle', None), ('posts', 'stop_on_obstacle', None),
                 ('clutter', 'avoid_obstacles', generated)]
        for world_name, controller, data in cases:
            if data is None:
                world = load_world(resolve_world(world_name, os.path.join(ROOT, 'worlds')),
                                   footprint=profile.footprint)
                spec_world = world_name
            else:
                world = parse_world(data, footprint=profile.footprint)
                spec_world = {'generator': {'fill_ratio': 1.0, 'seed': 0}}
            floor = floor_cpu_per_s(world, profile)
            spec = EpisodeSpec(world=spec_world, robot=name, controller=controller, time_limit_s=EPISODE_S)
            cost, result = episode_cpu_per_s(spec)
            target = ('target <= %.1fx' % TARGET_RATIO if controller == 'stop_on_obstacle' else
                      'target >= %.0fx real time' % TARGET_CLUTTER_SPEED if name == 'jackal' else '')
            print('  %-11s %-8s %3d obstacles  floor %6.2f ms/s (%5.0fx)  %-16s %6.2f ms/s  %5.2fx floor  %5.0fx '
                  'real time  (%s, %.1f s)  %s'
                  % (name, world_name, len(world.obstacles), floor * 1e3, 1.0 / floor, controller, cost * 1e3,
                     cost / floor, 1.0 / cost, result.outcome, result.time_s, target))


if __name__ == '__main__':
    main()
