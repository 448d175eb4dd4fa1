#!/usr/bin/env python3
"""A map of a large building as a world: 4000 x 4000 cells at 0.05 m (200 m square), rooms of 4 m with 0.6 m
walls and doorways, and desks in the rooms (about 30% of the cells occupied), written as map_server's PGM and
YAML; how long it takes to load (the world file, the simulator's bodies, the LIDAR's planar caster), what a 720-ray scan
(30 m) costs in it against one among 300 scattered posts, and a physics step.

    python3 test/bench/bench_big_map.py

Targets (issue "your world"): loaded in under 2 s; a scan within twice the cost of one among 300 posts."""
import math
import os
import sys
import tempfile
import time

import numpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_rays import posts  # noqa: E402
from closed_loop.geometry import Pose2D  # noqa: E402
from closed_loop.sim.sensors.lidar import Lidar, LidarSettings  # noqa: E402
from closed_loop.sim.simulation import RobotSetup, SimSettings, Simulation  # noqa: E402
from closed_loop.sim.world import load_world  # noqa: E402

CELLS, RESOLUTION, ROOM_CELLS, WALL_CELLS, DOOR_CELLS = 4000, 0.05, 80, 12, 20
LOAD_TARGET_S, SCAN_RATIO_TARGET = 2.0, 2.0
SPECKLE_FRACTION = 0.006
RAYS, RANGE_M, REPEATS, BLOCKS = 720, 30.0, 200, 7


def building(seed=1):
    """The occupancy image (255 free, 0 occupied): a grid of rooms, walls with a doorway to each neighbour, and
    two desks in each room."""
    rng = numpy.random.default_rng(seed)
    image = numpy.full((CELLS, CELLS), 255, numpy.uint8)
    for k in range(0, CELLS + 1, ROOM_CELLS):
        image[max(0, k - WALL_CELLS // 2):k + WALL_CELLS // 2, :] = 0
        image[:, max(0, k - WALL_CELLS // 2):k + WALL_CELLS // 2] = 0
    for row in range(0, CELLS, ROOM_CELLS):
        for col in range(0, CELLS, ROOM_CELLS):
            mid_r, mid_c = row + ROOM_CELLS // 2, col + ROOM_CELLS // 2
            image[mid_r - DOOR_CELLS // 2:mid_r + DOOR_CELLS // 2, max(0, col - WALL_CELLS // 2):col + WALL_CELLS // 2] = 255
            image[max(0, row - WALL_CELLS // 2):row + WALL_CELLS // 2, mid_c - DOOR_CELLS // 2:mid_c + DOOR_CELLS // 2] = 255
            for _ in range(2):
                r = row + int(rng.integers(WALL_CELLS, ROOM_CELLS - WALL_CELLS - 16))
                c = col + int(rng.integers(WALL_CELLS, ROOM_CELLS - WALL_CELLS - 32))
                image[r:r + 16, c:c + 32] = 0
    return image


def write_map(folder, image):
    with open(os.path.join(folder, 'building.pgm'), 'wb') as f:
        f.write(b'P5\n%d %d\n255\n' % (image.shape[1], image.shape[0]))
        f.write(image.tobytes())
    path = os.path.join(folder, 'building.yaml')
    with open(path, 'w') as f:
        f.write('image: building.pgm\nresolution: %g\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n'
                'occupied_thresh: 0.65\nfree_thresh: 0.196\n' % RESOLUTION)
    return path


def scan_ms(pairs, repeats):
    """For each (lidar, view) of ``pairs``, the median over blocks of a scan's CPU time in ms (a block's mean
    over ``repeats``), the pairs' blocks taken in turn so that the machine's changing speed meets each alike."""
    blocks = [[] for _ in pairs]
    for lidar, view in pairs:
        lidar.sample(view)
    for _ in range(BLOCKS):
        for times, (lidar, view) in zip(blocks, pairs):
            started = time.process_time()
            for _ in range(repeats):
                lidar.sample(view)
            times.append((time.process_time() - started) / repeats * 1e3)
    return [float(numpy.median(times)) for times in blocks]


def main():
    image = building()
    print('building map: %d x %d cells at %g m, %.0f%% occupied' % (CELLS, CELLS, RESOLUTION,
                                                                    100.0 * (image == 0).mean()))
    settings = SimSettings()
    casters = ('planar', 'pybullet')            # (an episode's, and the simulator node's default)
    lidars = {c: LidarSettings(scan_samples=RAYS, range_max=RANGE_M, ray_caster=c) for c in casters}
    with tempfile.TemporaryDirectory() as folder:
        path = write_map(folder, image)
        started = time.monotonic()
        try:
            world = load_world(path, check_starts=False)
        except ValueError as error:
            print('  refused: %s' % error)
            return 1
        loaded = time.monotonic()
        start = Pose2D(ROOM_CELLS * RESOLUTION * 0.5, CELLS * RESOLUTION - ROOM_CELLS * RESOLUTION * 0.5, 0.0)
        sim = Simulation(world, settings, robots=[RobotSetup('', settings, None, start)])
        built = time.monotonic()
        view = sim.view(0)
        lidar = Lidar(lidars['planar'], view)
        ready = time.monotonic()
        stepped = time.process_time()
        for _ in range(200):
            sim.step()
        step_ms = (time.process_time() - stepped) / 200 * 1e3
        field = posts()
        among = Simulation(field, settings, robots=[RobotSetup('', settings, None, Pose2D(0.0, 0.0, 0.0))])
        big_ms, posts_ms = {}, {}
        for c in casters:
            pairs = [(lidar if c == 'planar' else Lidar(lidars[c], view), view),
                     (Lidar(lidars[c], among.view(0)), among.view(0))]
            big_ms[c], posts_ms[c] = scan_ms(pairs, REPEATS if c == 'planar' else 5)
        among.close()
        sim.close()
    total = ready - started
    print('  %d boxes; loaded in %.2f s: the world file %.2f s, the simulator %.2f s, the LIDAR %.2f s '
          '(target %.1f s: %.2fx)' % (len(world.obstacles), total, loaded - started, built - loaded, ready - built,
                                     LOAD_TARGET_S, total / LOAD_TARGET_S))
    for c in casters:
        print('  a %d-ray scan (%g m), %s caster: %.3f ms in the building, %.3f ms among %d posts: %.2fx (target '
              '%.1fx)' % (RAYS, RANGE_M, c, big_ms[c], posts_ms[c], len(field.obstacles), big_ms[c] / posts_ms[c],
                          SCAN_RATIO_TARGET))
    print('  a physics step in the building: %.3f ms' % step_ms)
    speckled(image, settings, lidars['planar'])
    return 0


def speckled(image, settings, lidar_settings, fraction=SPECKLE_FRACTION):
    """The same building as a scanning robot's map would have it: single occupied cells strewn over a fraction
    of the map (each its own box); its load, a planar scan and a step, in one line."""
    noisy = image.copy()
    noisy[numpy.random.default_rng(3).random(image.shape) < fraction] = 0
    with tempfile.TemporaryDirectory() as folder:
        path = write_map(folder, noisy)
        started = time.monotonic()
        world = load_world(path, check_starts=False)
        start = Pose2D(ROOM_CELLS * RESOLUTION * 0.5, CELLS * RESOLUTION - ROOM_CELLS * RESOLUTION * 0.5, 0.0)
        sim = Simulation(world, settings, robots=[RobotSetup('', settings, None, start)])
        lidar = Lidar(lidar_settings, sim.view(0))
        loaded = time.monotonic() - started
        scan = scan_ms([(lidar, sim.view(0))], REPEATS)[0]
        stepped = time.process_time()
        for _ in range(100):
            sim.step()
        step_ms = (time.process_time() - stepped) / 100 * 1e3
        sim.close()
    print('  speckled (%.1f%% of the cells besides): %d boxes, loaded in %.2f s; a planar scan %.3f ms, a step %.3f ms'
          % (100 * fraction, len(world.obstacles), loaded, scan, step_ms))


if __name__ == '__main__':
    sys.exit(main())
