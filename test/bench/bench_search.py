#!/usr/bin/env python3
"""The search for failures (``closed_loop.batch.search``) against uniform random sampling, on controllers with a
known weakness (CASES): stop_on_obstacle with too short a stop distance (0.2 m) runs into the wall when it comes
fast and starts slowing late (a corner of the space: the speed it cruises at, where it starts slowing); and
avoid_obstacles is run into by a walker that comes fast from the side at the wrong moment (the generator
``crossing``: the walker's speed, where it starts, where it crosses). A failure is a collision. For each seed, the
same budget for TPE (the search's default sampler) and for the uniform sampler: how many failures each found,
how many distinct ones (their parameters on a grid of DISTINCT_CELLS a side), and at which episode the first
came.

    python3 test/bench/bench_search.py

Target (issue "find the failure"): at least 3 times as many distinct failures as chance, or the first failure in
at most a third of the episodes chance needs."""
import os
import sys
import tempfile

import numpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
from closed_loop.batch import search  # noqa: E402

BATCH, DISTINCT_CELLS = 4, 20
#: The controllers with a known weakness: (name, base, space {key: (low, high)}, seeds, budget).
CASES = (
    ('stop_on_obstacle with a 0.2 m stop distance, fast and slowing late',
     '{world: wall, controller: stop_on_obstacle, time_limit_s: 12, settings: {stop_distance: 0.2}}',
     {'settings.cruise_speed': (0.25, 1.0), 'settings.slow_distance': (0.21, 1.0)}, tuple(range(6)), 40),
    ('avoid_obstacles met by a walker from the side (generator crossing)',
     '{world: {generator: {method: crossing}}, controller: avoid_obstacles, time_limit_s: 25}',
     {'world.generator.walker_speed': (0.3, 2.0), 'world.generator.walker_start': (1.0, 3.5),
      'world.generator.crossing_x': (1.5, 5.0)}, tuple(range(4)), 30),
    ('stop_on_obstacle with a blind sector (its front sector 0.1 rad each side) at a box off its line',
     '{world: red_box, controller: stop_on_obstacle, time_limit_s: 12, settings: {front_half_angle: 0.1}, '
     'sim: {start: "0 0 0"}}',
     {'start.y': (-1.0, 1.0), 'start.yaw': (-0.3, 0.3)}, tuple(range(6)), 40),
)
TEXT = """name: bench_search
base: %s
space:
%s
budget: %d
batch: %d
seed: %d
sampler: %s
failure: {outcomes: [collided]}
report: {pictures: none}
"""


def one(folder, case, sampler, seed):
    """(failures, distinct failures, the first failure's episode or None) of one search."""
    _, base, space, _, budget = case
    path = os.path.join(folder, '%s-%d.yaml' % (sampler, seed))
    with open(path, 'w') as f:
        f.write(TEXT % (base, '\n'.join('  %s: {from: %g, to: %g}' % (k, lo, hi) for k, (lo, hi) in space.items()),
                        budget, BATCH, seed, sampler))
    rows = search.run(search.load(path), os.path.join(folder, '%s-%d' % (sampler, seed)), workers=2,
                      stream=open(os.devnull, 'w'))
    failing = [r for r in rows if r['failing'] == 'True']
    cells = {tuple(min(int((float(r[k]) - lo) / (hi - lo) * DISTINCT_CELLS), DISTINCT_CELLS - 1)
                   for k, (lo, hi) in space.items()) for r in failing}
    return len(failing), len(cells), min((int(r['index']) for r in failing), default=None)


def main(argv=None):
    """Every case, or those whose numbers (from 1) are given."""
    chosen = [int(a) for a in (sys.argv[1:] if argv is None else argv)] or range(1, len(CASES) + 1)
    for case in [CASES[i - 1] for i in chosen]:
        name, _, _, seeds, budget = case
        print(name)
        figures = {s: [] for s in os.environ.get('BENCH_SAMPLERS', 'tpe random').split()}
        with tempfile.TemporaryDirectory() as folder:
            for seed in seeds:
                for sampler in os.environ.get('BENCH_SAMPLERS', 'tpe random').split():
                    figures[sampler].append(one(folder, case, sampler, seed))
                    found, distinct, first = figures[sampler][-1]
                    print('  seed %d, %-6s: %2d failures, %2d distinct, the first at episode %s'
                          % (seed, sampler, found, distinct, '-' if first is None else first), flush=True)
        mean = {s: numpy.mean([d for _, d, _ in figures[s]]) for s in figures}
        total = {s: sum(f for f, _, _ in figures[s]) for s in figures}
        first = {s: numpy.mean([budget if f is None else f + 1 for _, _, f in figures[s]]) for s in figures}
        print('  search (TPE) against chance, %d seeds x %d episodes: distinct failures %.1f against %.1f (%.1fx; '
              'target 3x), failing episodes %d against %d, the first failure at episode %.1f against %.1f (%.2f of '
              'chance; target 1/3 or less)'
              % (len(seeds), budget, mean['tpe'], mean['random'], mean['tpe'] / max(mean['random'], 1e-9),
                 total['tpe'], total['random'], first['tpe'], first['random'], first['tpe'] / first['random']))
    return 0


if __name__ == '__main__':
    sys.exit(main())
