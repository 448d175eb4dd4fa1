#!/usr/bin/env python3
"""Episodes and sweeps: how fast the episode runner goes, and how many episodes a minute a sweep gets.

Run: ``python3 test/bench/bench_episodes.py`` inside ``source env.sh`` (``make bench`` does that).
Options: ``--episodes N`` for the long sweep (default 1000), ``--workers N`` (default: the cores).

1. Episode speed, in simulated seconds per CPU second (``time.process_time`` of this process around
   ``run_episode``, set-up included): state_machine_controller (it never rests, so every episode runs its
   60 s) with the LIDAR at 10 Hz (360 rays) and the camera off, in ``empty`` (open) and ``posts`` (208
   thin posts), with the planar LIDAR (what episodes use) and with pybullet's. Targets: 300x open, 100x
   dense.
2. One scan among the 208 posts, planar and pybullet (median of 200). Target: under 0.5 ms.
3. Sweep throughput: the same 200 stop_on_obstacle episodes (wall and red_box, stop distances, speeds, seeds,
   noise) one by one in this process, then as a sweep on a local Dask cluster of ``--workers`` processes:
   episodes per minute of wall time, and their ratio.
4. A long sweep of ``--episodes`` episodes (tune_thresholds' grid over speeds, stop distances, worlds,
   noise and seeds) on the local cluster: episodes per minute, errors, contacts.

Figures, not pass/fail: the exit status is non-zero only when something could not run.
"""
import argparse
import os
import statistics
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop.batch import sweep, sweep_file
from closed_loop.batch import tune_thresholds  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402
from closed_loop.sim.profiles import load_profile  # noqa: E402
from closed_loop.sim.rig import Rig  # noqa: E402
from closed_loop.sim.sensors.lidar import Lidar  # noqa: E402
from closed_loop.sim.world import load_world, resolve_world  # noqa: E402

TARGET_OPEN, TARGET_DENSE, TARGET_SCAN_MS = 300.0, 100.0, 0.5


def speed(world, caster, runs=3):
    spec = EpisodeSpec(world=world, controller='state_machine_controller', time_limit_s=60.0,
                       sim={'ray_caster': caster})
    run_episode(spec)        # imports and caches warm
    ratios = []
    for _ in range(runs):
        started = time.process_time()
        result = run_episode(spec)
        ratios.append(result.time_s / (time.process_time() - started))
    return statistics.median(ratios)


def scan_ms(world, caster):
    profile = load_profile('closed_loop')
    rig = Rig(load_world(resolve_world(world, os.path.join(ROOT, 'worlds')), footprint=profile.footprint),
              dict(camera=False, ray_caster=caster), profile.urdf)
    try:
        lidar = rig.sensors[Lidar]
        for _ in range(10):
            rig.sim.step()
        lidar.sample(rig.sim)
        times = []
        for _ in range(200):
            started = time.perf_counter()
            lidar.sample(rig.sim)
            times.append((time.perf_counter() - started) * 1e3)
        return statistics.median(times)
    finally:
        rig.close()


def throughput_sweep():
    grid = {'world': ['wall', 'red_box'], 'settings.stop_distance': [0.3, 0.5], 'settings.cruise_speed': [0.5, 1.0],
            'seed': list(range(25)), 'scan_noise': [0.01]}
    return sweep_file.build('throughput', {'controller': 'stop_on_obstacle', 'time_limit_s': 20.0}, grid)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--episodes', type=int, default=1000)
    parser.add_argument('--workers', type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()

    print('1. episode speed, simulated s per CPU s (state_machine_controller, 60 s, LIDAR 10 Hz, no camera)')
    for world, target in (('empty', TARGET_OPEN), ('posts', TARGET_DENSE)):
        planar, pybullet = speed(world, 'planar'), speed(world, 'pybullet')
        print('   %-6s planar LIDAR %5.0fx (target %.0fx, ratio %.2f); pybullet LIDAR %5.0fx'
              % (world, planar, target, planar / target, pybullet))

    print('2. one scan of 360 rays among the 208 posts (median of 200)')
    planar, pybullet = scan_ms('posts', 'planar'), scan_ms('posts', 'pybullet')
    print('   planar %.2f ms (target under %.1f ms, ratio %.2f); pybullet %.2f ms (%.0fx slower)'
          % (planar, TARGET_SCAN_MS, planar / TARGET_SCAN_MS, pybullet, pybullet / planar))

    built = throughput_sweep()
    n = len(built.specs)
    started = time.monotonic()
    for _, spec in built.specs:
        run_episode(spec)
        # (the one-by-one run keeps nothing: only its time matters)
    alone_s = time.monotonic() - started
    with tempfile.TemporaryDirectory() as out:
        started = time.monotonic()
        rows = list(sweep.run(built, out, workers=args.workers, stream=open(os.devnull, 'w')))
        cluster_s = time.monotonic() - started
    print('3. sweep throughput, %d episodes (stop_on_obstacle, wall and red_box, 20 s limit)' % n)
    print('   one by one in this process: %.0f episodes/min (%.1f s); local cluster of %d workers: %.0f episodes/min '
          '(%.1f s, start-up included): ratio %.2f; %d rows'
          % (60.0 * n / alone_s, alone_s, args.workers, 60.0 * n / cluster_s, cluster_s, alone_s / cluster_s,
             len(rows)))

    speeds = [0.3, 0.5, 0.8, 1.0]
    worlds = ['wall', 'red_box', 'obstacle_left', 'corridor', 'obstacle_right']
    seeds = max(1, -(-args.episodes // (len(speeds) * 10 * len(worlds) * 2)))     # at least --episodes
    long_sweep = tune_thresholds.build(speeds, [round(0.15 + 0.05 * i, 2) for i in range(10)], worlds,
                                       list(range(seeds)), [0.0, 0.01], 20.0, name='long')
    with tempfile.TemporaryDirectory() as out:
        started = time.monotonic()
        rows = list(sweep.run(long_sweep, out, workers=args.workers, stream=open(os.devnull, 'w')))
        wall_s = time.monotonic() - started
    errors = sum(r['outcome'] == 'error' for r in rows)
    contacts = sum(r['outcome'] != 'error' and int(r['contacts']) > 0 for r in rows)
    print('4. a long sweep: %d episodes (tune_thresholds grid: %d speeds x 10 stop distances x %d worlds x 2 noise '
          'levels x %d seeds) on %d workers: %.1f min, %.0f episodes/min; %d errors, %d with contact (the small '
          'stop distances)' % (len(rows), len(speeds), len(worlds), seeds, args.workers, wall_s / 60.0,
                               60.0 * len(rows) / wall_s, errors, contacts))
    return 1 if errors else 0


if __name__ == '__main__':
    sys.exit(main())
