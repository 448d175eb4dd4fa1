#!/usr/bin/env python3
"""The planar caster's scan among 300 posts (720 rays, as the Jackal's LIDAR), culled by angular window (found by
arithmetic for the LIDAR's fan, or by search in sorted bearings) against every ray on every post, from the middle
of 300 posts scattered over 20 x 20 m and from inside a BARN-method field (315 posts and two side walls); and how
fast a sweep file of a million combinations is checked and ready to start.

    python3 test/bench/bench_rays.py

Prints ms per scan for both casts and their ratio, with the target (0.15 ms culled), and the sweep file's
load time and peak memory against its targets (5 s, 200 MB)."""
import json
import math
import os
import subprocess
import sys
import tempfile
import textwrap
import time

import numpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
from closed_loop.sim.planar_rays import PlanarRays  # noqa: E402
from closed_loop.sim.world import parse_world  # noqa: E402

POSTS, RAYS, FIELD_RAD, RANGE_M = 300, 720, 4.71, 30.0
SCAN_TARGET_MS, CHECK_TARGET_S, CHECK_TARGET_MB = 0.15, 5.0, 200.0
MILLION = textwrap.dedent("""\
    import json, sys, time
    started = time.monotonic()
    from closed_loop.batch import sweep_file
    built = sweep_file.load(sys.argv[1])
    next(iter(built.specs))
    with open('/proc/self/status') as f:
        peak = next(int(line.split()[1]) for line in f if line.startswith('VmHWM:')) / 1024.0
    print(json.dumps([len(built.specs), time.monotonic() - started, peak]))
    """)


def posts(seed=1):
    rng = numpy.random.default_rng(seed)
    found = []
    while len(found) < POSTS:
        x, y = rng.uniform(-10, 10, 2)
        if math.hypot(x, y) > 1.0:
            found.append({'name': 'p%d' % len(found), 'type': 'cylinder', 'position': [float(x), float(y)],
                          'radius': 0.075, 'height': 1.0})
    return parse_world({'name': 'posts', 'robot': {'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}}, 'obstacles': found})


def per_scan_ms(caster, origin, dirs, repeats, **how):
    caster.cast(None, origin, dirs, RANGE_M, **how)
    started = time.process_time()
    for _ in range(repeats):
        caster.cast(None, origin, dirs, RANGE_M, **how)
    return (time.process_time() - started) / repeats * 1e3


def barn_field():
    from closed_loop.sim import generators
    from closed_loop.sim.profiles import load_profile
    profile = load_profile('jackal')
    settings = generators.settings_from({'method': 'barn', 'seed': 2, 'fill': 0.45, 'smoothing': 2}, 'jackal')
    return parse_world(generators.generate(settings, profile), 'barn', footprint=profile.footprint)


def main():
    angles = numpy.linspace(-FIELD_RAD / 2, FIELD_RAD / 2, RAYS)
    dirs = numpy.column_stack((numpy.cos(angles), numpy.sin(angles), numpy.zeros(RAYS)))
    fan = (angles[0], angles[1] - angles[0])
    print('planar caster, %d rays (CPU per scan):' % RAYS)
    for label, world, origin in (('%d posts over 20 x 20 m, from the middle' % POSTS, posts(), (0.0, 0.0, 0.2)),
                                 ('a BARN-method field, from inside it', barn_field(), (4.0, 0.3, 0.2))):
        caster = PlanarRays(world.obstacles)
        brute = per_scan_ms(caster, origin, dirs, 50, cull=False)
        searched = per_scan_ms(caster, origin, dirs, 2000)
        fanned = per_scan_ms(caster, origin, dirs, 2000, fan=fan)
        reference = caster.cast(None, origin, dirs, RANGE_M, cull=False)
        same = all(numpy.array_equal(caster.cast(None, origin, dirs, RANGE_M, **how), reference)
                   for how in ({}, {'fan': fan}))
        print('  %s (%d obstacles):' % (label, len(world.obstacles)))
        print('    every ray on every obstacle   %8.3f ms' % brute)
        print('    culled, windows by search     %8.3f ms' % searched)
        print('    culled, windows by the fan    %8.3f ms   %.0fx faster than every ray; target %.2f ms (%.2fx of '
              'it); all equal: %s' % (fanned, brute / fanned, SCAN_TARGET_MS, fanned / SCAN_TARGET_MS, same))
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, 'million.yaml')
        with open(path, 'w') as f:
            f.write('name: million\nbase: {world: wall}\ngrid:\n  seed: {from: 0, to: 999999, step: 1}\n')
        done = subprocess.run([sys.executable, '-c', MILLION, path], stdout=subprocess.PIPE, check=True,
                              universal_newlines=True, env=dict(os.environ, PYTHONPATH=os.path.join(ROOT, 'src')))
        count, wall_s, peak_mb = json.loads(done.stdout.strip().splitlines()[-1])
    print('sweep file of %d combinations, checked and its first episode made (a fresh interpreter):' % count)
    print('  %.2f s (target %.0f s: %.2fx), peak %.0f MB (target %.0f MB: %.2fx)'
          % (wall_s, CHECK_TARGET_S, wall_s / CHECK_TARGET_S, peak_mb, CHECK_TARGET_MB, peak_mb / CHECK_TARGET_MB))


if __name__ == '__main__':
    main()
