#!/usr/bin/env python3
"""What it costs to send a graph episode's folder back from a worker that does not see the client's files
(``closed_loop.batch.logs_back``): a graph episode is run (its node, lockstepped), then its folder is packed as such a
worker packs it and unpacked as the client does, REPEATS times; bytes before and after packing, and the median
milliseconds of each.

    python3 test/bench/bench_logs_back.py

It reports figures; it does not pass or fail on time."""
import os
import statistics
import sys
import tempfile
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
from closed_loop.batch import logs_back  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402

REPEATS = 20
EPISODES = (('stop_on_obstacle at the wall', dict(world='wall', controller={'node': 'stop_on_obstacle'},
                                                   time_limit_s=15)),
            ('avoid_obstacles through obstacle_course (18.6 simulated s)',
             dict(world='obstacle_course', goal=(7.0, 0.0), controller={'node': 'avoid_obstacles'}, time_limit_s=40)))


def main():
    with tempfile.TemporaryDirectory() as root:
        for n, (name, fields) in enumerate(EPISODES):
            folder = os.path.join(root, 'episode-%d' % n)
            result = run_episode(EpisodeSpec(**fields), None, folder)
            raw = sum(os.path.getsize(os.path.join(t, f)) for t, _, names in os.walk(folder) for f in names)
            packs, unpacks = [], []
            for k in range(REPEATS):
                started = time.perf_counter()
                data, left = logs_back.pack(folder)
                packed = time.perf_counter()
                logs_back.unpack(data, os.path.join(root, 'client-%d-%d' % (n, k)))
                packs.append(packed - started)
                unpacks.append(time.perf_counter() - packed)
            print('%s (%s): %d files, %.0f kB -> %.1f kB packed; pack %.1f ms, unpack %.1f ms (medians of %d)%s'
                  % (name, result.outcome, sum(len(f) for _, _, f in os.walk(folder)), raw / 1024, len(data) / 1024,
                     1e3 * statistics.median(packs), 1e3 * statistics.median(unpacks), REPEATS,
                     '; left on the worker: %s' % left if left else ''), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
