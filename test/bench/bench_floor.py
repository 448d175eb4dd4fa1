#!/usr/bin/env python3
"""The physics floor, and what an episode costs beside it.

Run: ``python3 test/bench/bench_floor.py`` inside ``source env.sh`` (``make bench`` does that).

The floor: CPU per simulated second of the simulator's step alone (``Simulation.step``: pybullet's
``stepSimulation`` and the drive's few lines around it, no sensor sampled, no controller), for each robot
profile in ``empty``, in ``posts`` (208 thin posts) and in a BARN-method field (``closed_loop.sim.barn``, 315
posts). Then an episode in the same world, as a sweep's worker runs it (the world loaded once): stop_on_obstacle
in ``empty`` and ``posts``, avoid_obstacles to the goal in the BARN field. For each: the world's set-up (the
simulation and its robot built), the episode's running cost per simulated second beside the floor (its CPU less
the set-up), the whole episode's (set-up included), and its speed (simulated s per CPU s); and the episode's loop
timed against its own physics steps, side by side (``Clocked``), the ratio that holds when the host's speed
drifts between one measurement and the next; and, in runs of their own, where the loop's CPU beside its steps
goes (``Parts``: the LIDAR, the controller, the judge, the contact check, the rest). Targets: at most 1.5x
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
from closed_loop.batch.lockstep import Tap  # noqa: E402
from closed_loop.sim.scheduler import command_delay_steps  # noqa: E402
from closed_loop.sim.profiles import load_profile  # noqa: E402
from closed_loop.sim.rig import Rig  # noqa: E402
from closed_loop.sim.sensors.contacts import Contacts  # noqa: E402
from closed_loop.sim.sensors.lidar import Lidar  # noqa: E402

PROFILES = ('closed_loop', 'burger', 'jackal')
BARN = {'generator': {'method': 'barn', 'seed': 2, 'fill': 0.45, 'smoothing': 2}}
FLOOR_S, EPISODE_S, REPEATS = 10.0, 60.0, 5
#: A short episode (one that stops within seconds) and its replay are each run this many times in a repeat, so
#: that a repeat's figures each span at least about this much CPU (s).
LEAST_CPU_S = 0.25
TARGET_RATIO, TARGET_SETUP_MS, TARGET_CLUTTER_SPEED = 1.5, 20.0, 40.0


def sim_params(profile):
    return dict(profile.node_params('sim'), camera=False, ray_caster='planar')


def floor_cpu_per_s(world, profile):
    """CPU s per simulated s of stepping ``world`` (a World) with ``profile``'s robot at rest, nothing else
    (one run of FLOOR_S)."""
    rig = Rig(world, sim_params(profile), profile.urdf)
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


class Commands(Tap):
    """Keeps the commands an episode sent, each with the physics step it reached the wheels at."""

    def begin(self, rig, controller, judge):
        self.dt_s, self.sent = rig.sim.dt_s, []

    def command(self, t_s, command):
        self.sent.append((int(round(t_s / self.dt_s)), command))


class Clocked(Tap):
    """Times an episode's loop, and the physics steps within it apart: the two are taken side by side, step by
    step, so their ratio holds however the machine's speed drifts."""

    def begin(self, rig, controller, judge):
        sim, step, clock = rig.sim, rig.sim.step, time.process_time
        self.step_s, self.started, self.last = 0.0, clock(), None

        def timed():
            started = clock()
            try:
                return step()
            finally:
                self.step_s += clock() - started
        sim.step = timed

    def stepped(self, t_s, began):
        self.last = time.process_time()

    def ratio(self):
        """The loop's CPU over its steps' (the clock's own cost counted beside the steps)."""
        return (self.last - self.started) / self.step_s


class Parts(Clocked):
    """As :class:`Clocked`, and where the rest goes: the LIDAR's scans, the controller's calls, the judge's look at
    ground truth (its pose, speeds and clearance) and the contact check after each step, each timed where it is
    called (their clock reads, four a step more than :class:`Clocked`'s, fall in "the rest"). Run apart from the
    ratio's own runs, which have no such reads."""

    PARTS = ('LIDAR', 'controller', 'judge', 'contacts')

    def begin(self, rig, controller, judge):
        Clocked.begin(self, rig, controller, judge)
        self.spent = dict.fromkeys(self.PARTS, 0.0)
        robot = rig.sim.robots[0]
        for part, owner, names in (('LIDAR', rig.sensors[Lidar], ('sample',)),
                                   ('controller', controller, ('on_scan', 'on_tick', 'on_detection')),
                                   ('judge', robot, ('ground_truth', 'clearance')), ('judge', judge, ('observe',)),
                                   ('contacts', rig.sensors[Contacts], ('sample',))):
            for name in names:
                setattr(owner, name, self._timed(part, getattr(owner, name)))

    def _timed(self, part, call):
        clock, spent = time.process_time, self.spent

        def timed(*args, **kwargs):
            started = clock()
            try:
                return call(*args, **kwargs)
            finally:
                spent[part] += clock() - started
        return timed

    def shares(self):
        """{part: its CPU over the steps'}, and 'the rest' (the loop's own lines and the clock's reads)."""
        shares = {part: spent / self.step_s for part, spent in self.spent.items()}
        shares['the rest'] = self.ratio() - 1.0 - sum(shares.values())
        return shares


def driven_floor(spec, cache, commands, simulated_s):
    """(CPU s per simulated s of the step alone; metres between the replay's end and the episode's): the
    episode's physics again, its commands replayed open loop at the steps they reached the wheels, no sensor
    sampled and no controller. A moving robot's step costs more than a resting one's (the Jackal's wheels slip
    as it drives), so this is the floor the episode itself stands on."""
    prepared = prepare(spec, cache)
    rig = Rig(prepared.world, prepared.sim_params, prepared.profile.urdf)
    try:
        sim = rig.sim
        delay = command_delay_steps(spec.command_delay_s, sim.dt_s)
        due = [(k + delay, command) for k, command in commands.sent]
        steps = int(round(simulated_s / sim.dt_s))
        started = time.process_time()
        for k in range(steps):
            while due and due[0][0] <= k:
                sim.command(due.pop(0)[1])
            sim.step()
        cpu = (time.process_time() - started) / (steps * sim.dt_s)
        return cpu, sim.ground_truth()[0].position[:2]
    finally:
        rig.close()


def setup_s(world, profile):
    """CPU s to build the simulation of ``world`` with the robot and its sensors, and to close it."""
    started = time.process_time()
    Rig(world, sim_params(profile), profile.urdf).close()
    return time.process_time() - started


def episode_cpu(spec, cache):
    """(CPU s of the whole episode, the world already loaded as a sweep's worker has it; the result)."""
    started = time.process_time()
    result = run_episode(spec, cache)
    return time.process_time() - started, result


def measure(spec, world, profile):
    """Each figure REPEATS times, the floors, the set-up and the episode in turn, so that each repeat's ratios
    are taken on the machine as it was then (its speed drifts on a shared host): {figure: [one per repeat]},
    the episode's result, and the replay's distance from the episode's end (m)."""
    cache, commands = {}, Commands()
    started = time.process_time()
    result = run_episode(spec, cache, tap=commands)
    times = max(1, int(math.ceil(LEAST_CPU_S / (time.process_time() - started))))
    ran = max(result.simulated_s, 1e-9)          # the simulated time it ran (past time_s: the rest rule)
    figures = {name: [] for name in ('floor', 'driven', 'setup', 'whole', 'in place')}
    for _ in range(REPEATS):
        figures['floor'].append(floor_cpu_per_s(world, profile))
        replays = [driven_floor(spec, cache, commands, ran) for _ in range(times)]
        end = replays[-1][1]
        figures['driven'].append(sum(cpu for cpu, _ in replays) / times)
        figures['setup'].append(sum(setup_s(world, profile) for _ in range(times)) / times)
        figures['whole'].append(sum(episode_cpu(spec, cache)[0] for _ in range(times)) / times)
        clocked = [Clocked() for _ in range(times)]
        for tap in clocked:
            run_episode(spec, cache, tap=tap)
        figures['in place'].append(median([tap.ratio() for tap in clocked]))
    parts = [Parts() for _ in range(times)]
    for tap in parts:
        run_episode(spec, cache, tap=tap)
    figures['parts runs'] = times
    figures['parts'] = {name: median([tap.shares()[name] for tap in parts]) for name in parts[0].shares()}
    apart = math.hypot(end[0] - result.final_pose[0], end[1] - result.final_pose[1])
    return figures, result, ran, apart


def median(values):
    ordered = sorted(values)
    middle = len(ordered) // 2
    return ordered[middle] if len(ordered) % 2 else 0.5 * (ordered[middle - 1] + ordered[middle])


def main():
    print('CPU per simulated s: the floor (the step alone), an episode running beside it (set-up apart) and whole;')
    print('the ratios to the floor, the set-up, and the episode\'s speed (simulated s per CPU s). Each figure is')
    print('the median of %d repeats, each repeat\'s ratios taken within it (the range of the first in brackets)'
          % REPEATS)
    for name in PROFILES:
        profile = load_profile(name)
        for world_name, spec_world, controller in (('empty', 'empty', 'stop_on_obstacle'),
                                                   ('posts', 'posts', 'stop_on_obstacle'),
                                                   ('BARN field', BARN, 'avoid_obstacles')):
            world = load_episode_world(spec_world, profile)
            spec = EpisodeSpec(world=spec_world, robot=name, controller=controller, time_limit_s=EPISODE_S)
            f, result, ran, apart = measure(spec, world, profile)
            running = [(whole - setup) / ran for whole, setup in zip(f['whole'], f['setup'])]
            driven_ratio = [r / d for r, d in zip(running, f['driven'])]
            target = ('target <= %.1fx' % TARGET_RATIO if controller == 'stop_on_obstacle' else
                      'target >= %.0fx real time' % TARGET_CLUTTER_SPEED if name == 'jackal' else '')
            print('  %-11s %-10s %3d obstacles  floor at rest %5.2f ms/s (%4.0fx), as driven %5.2f ms/s (replay %.0e m '
                  'off)  set-up %5.1f ms  %-16s running %6.2f ms/s = %5.2fx the floor as driven [%.2f-%.2f] (%5.2fx at '
                  'rest), whole %5.2fx / %5.2fx; the loop %5.2fx its own steps [%.2f-%.2f]  %4.0fx real time  '
                  '(%s, %.1f s)  %s'
                  % (name, world_name, len(world.obstacles), median(f['floor']) * 1e3, 1.0 / median(f['floor']),
                     median(f['driven']) * 1e3, apart, median(f['setup']) * 1e3, controller, median(running) * 1e3,
                     median(driven_ratio), min(driven_ratio), max(driven_ratio),
                     median([r / d for r, d in zip(running, f['floor'])]),
                     median([w / ran / d for w, d in zip(f['whole'], f['driven'])]),
                     median([w / ran / d for w, d in zip(f['whole'], f['floor'])]),
                     median(f['in place']), min(f['in place']), max(f['in place']),
                     median([ran / w for w in f['whole']]), result.outcome, ran, target))
            print('  %-11s %-10s where the loop goes, in its steps\' CPU (the median of %d runs): steps 1, %s'
                  % ('', '', f['parts runs'], ', '.join('%s %.3f' % kv for kv in f['parts'].items())))


if __name__ == '__main__':
    main()
