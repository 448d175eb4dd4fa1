#!/usr/bin/env python3
"""The physics floor, and what an episode costs beside it.

Run: ``python3 test/bench/bench_floor.py`` inside ``source env.sh`` (``make bench`` does that).

The floor: CPU per simulated second of the simulator's step alone (``Simulation.step``: pybullet's
``stepSimulation`` and the drive's few lines around it, no sensor sampled, no controller), for each robot
profile in ``empty``, in ``posts`` (208 thin posts) and in a BARN-method field (``closed_loop.sim.barn``, 315
posts). Then an episode in the same world, as a sweep's worker runs it (the world loaded once): stop_on_obstacle
in ``empty`` and ``posts``, avoid_obstacles to the goal in the BARN field. For each: the world's set-up (the
simulation and its robot built), the episode's running cost per simulated second beside the floor (its CPU less
the set-up), the whole episode's (set-up included), and its speed (simulated s per CPU s). Targets: at most 1.5x
the floor with stop_on_obstacle in ``empty`` and ``posts``; set-up of the 300-post world under 20 ms; at least
40x real time for the Jackal with avoid_obstacles among about 300 posts. Figures, not pass/fail.
"""
import math
import os
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop.batch.episode import EpisodeSpec, load_episode_world, prepare, run_episode  # noqa: E402
from closed_loop.batch.lockstep import Tap, command_delay_steps  # noqa: E402
from closed_loop.sim.profiles import load_profile  # noqa: E402
from closed_loop.sim.rig import Rig  # noqa: E402

PROFILES = ('closed_loop', 'burger', 'jackal')
BARN = {'generator': {'method': 'barn', 'seed': 2, 'fill': 0.45, 'smoothing': 2}}
FLOOR_S, EPISODE_S, REPEATS = 10.0, 60.0, 3
TARGET_RATIO, TARGET_SETUP_MS, TARGET_CLUTTER_SPEED = 1.5, 20.0, 40.0


def sim_params(profile):
    return dict(profile.node_params('sim'), camera=False, ray_caster='planar')


def floor_cpu_per_s(world, profile):
    """CPU s per simulated s of stepping ``world`` (a World) with ``profile``'s robot at rest, nothing else
    (least of REPEATS runs of FLOOR_S: a shared machine's slow moments do not count)."""
    best = float('inf')
    for _ in range(REPEATS):
        rig = Rig(world, sim_params(profile), profile.urdf)
        try:
            steps = int(round(FLOOR_S / rig.sim.dt_s))
            for _ in range(50):
                rig.sim.step()
            started = time.process_time()
            for _ in range(steps):
                rig.sim.step()
            best = min(best, (time.process_time() - started) / (steps * rig.sim.dt_s))
        finally:
            rig.close()
    return best


class Commands(Tap):
    """Keeps the commands an episode sent, each with the physics step it reached the wheels at."""

    def begin(self, rig, controller, judge):
        self.dt_s, self.sent = rig.sim.dt_s, []

    def command(self, t_s, command):
        self.sent.append((int(round(t_s / self.dt_s)), command))


def driven_floor(spec, cache, commands, simulated_s):
    """(CPU s per simulated s of the step alone, least of REPEATS; metres between the replay's end and the
    episode's): the episode's physics again, its commands replayed open loop at the steps they reached the
    wheels, no sensor sampled and no controller. A moving robot's step costs more than a resting one's (the
    Jackal's wheels slip as it drives), so this is the floor the episode itself stands on."""
    prepared = prepare(spec, cache)
    best, moved = float('inf'), None
    for _ in range(REPEATS):
        rig = Rig(prepared.world, prepared.sim_params, prepared.profile.urdf)
        try:
            sim = rig.sim
            delay = command_delay_steps(spec, sim.dt_s)
            due = [(k + delay, command) for k, command in commands.sent]
            steps = int(round(simulated_s / sim.dt_s))
            started = time.process_time()
            for k in range(steps):
                while due and due[0][0] <= k:
                    sim.command(due.pop(0)[1])
                sim.step()
            best = min(best, (time.process_time() - started) / (steps * sim.dt_s))
            moved = sim.ground_truth()[0].position[:2]
        finally:
            rig.close()
    return best, moved


def setup_s(world, profile):
    """CPU s to build the simulation of ``world`` with the robot and its sensors, and to close it (least of
    REPEATS)."""
    best = float('inf')
    for _ in range(REPEATS + 1):
        started = time.process_time()
        Rig(world, sim_params(profile), profile.urdf).close()
        best = min(best, time.process_time() - started)
    return best


def episode_cpu(spec, cache, tap=None):
    """(CPU s of the whole episode, least of REPEATS, the world already loaded as a sweep's worker has it;
    the result); ``tap`` sees the first run."""
    run_episode(spec, cache, tap=tap)
    best, result = float('inf'), None
    for _ in range(REPEATS):
        started = time.process_time()
        result = run_episode(spec, cache)
        best = min(best, time.process_time() - started)
    return best, result


def main():
    print('CPU per simulated s: the floor (the step alone), an episode running beside it (set-up apart) and whole;')
    print('the ratios to the floor, the set-up, and the episode\'s speed (simulated s per CPU s)')
    for name in PROFILES:
        profile = load_profile(name)
        for world_name, spec_world, controller in (('empty', 'empty', 'stop_on_obstacle'),
                                                   ('posts', 'posts', 'stop_on_obstacle'),
                                                   ('BARN field', BARN, 'avoid_obstacles')):
            world = load_episode_world(spec_world, profile)
            floor = floor_cpu_per_s(world, profile)
            setup = setup_s(world, profile)
            spec = EpisodeSpec(world=spec_world, robot=name, controller=controller, time_limit_s=EPISODE_S)
            cache, commands = {}, Commands()
            whole, result = episode_cpu(spec, cache, commands)
            ran = max(result.simulated_s, 1e-9)          # the simulated time it ran (past time_s: the rest rule)
            driven, end = driven_floor(spec, cache, commands, ran)
            apart = math.hypot(end[0] - result.final_pose[0], end[1] - result.final_pose[1])
            running = (whole - setup) / ran
            target = ('target <= %.1fx' % TARGET_RATIO if controller == 'stop_on_obstacle' else
                      'target >= %.0fx real time' % TARGET_CLUTTER_SPEED if name == 'jackal' else '')
            print('  %-11s %-10s %3d obstacles  floor at rest %5.2f ms/s (%4.0fx), as driven %5.2f ms/s (replay %.0e m '
                  'off)  set-up %5.1f ms  %-16s running %6.2f ms/s = %5.2fx the floor as driven (%5.2fx at rest), '
                  'whole %5.2fx / %5.2fx  %4.0fx real time  (%s, %.1f s)  %s'
                  % (name, world_name, len(world.obstacles), floor * 1e3, 1.0 / floor, driven * 1e3, apart,
                     setup * 1e3, controller, running * 1e3, running / driven, running / floor, whole / ran / driven,
                     whole / ran / floor, ran / whole, result.outcome, ran, target))


if __name__ == '__main__':
    main()
