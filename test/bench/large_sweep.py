#!/usr/bin/env python3
"""The sweep command, whole (its episodes, then its report), on COUNT episodes that all fail (0.2 s in an empty
world: every one times out), on a local cluster of 2 workers, into OUTPUT; prints its figures as one line of
JSON: exit status, rows, wall time, pictures, bytes of trajectories sent back, the page's size and this
process's own peak memory. Used by bench_report (1,000 to 100,000) and test_failure_report (100).

Run: ``python3 test/bench/large_sweep.py COUNT OUTPUT [MAX_PICTURES]`` inside ``source env.sh``.
"""
import argparse
import io
import json
import os
import sys
import time
from contextlib import redirect_stdout

from closed_loop.batch import sweep, sweep_file


def peak_mb():
    """This process's own peak memory (VmHWM: since its exec; ru_maxrss would count the process it was forked
    from)."""
    with open('/proc/self/status') as f:
        return next(int(line.split()[1]) for line in f if line.startswith('VmHWM:')) / 1024.0


def main(count, output, max_pictures=100):
    built = sweep_file.build('large', {'world': 'empty', 'time_limit_s': 0.2},
                             {'seed': {'from': 0, 'to': count - 1, 'step': 1}}, report={'max_pictures': max_pictures})
    args = argparse.Namespace(verbose=False, scheduler=None, tls=None, workers=2, resume=False)
    started = time.monotonic()
    with redirect_stdout(io.StringIO()):
        status, _, rows = sweep.run_command('sweep', lambda: built, output, args)
    print(json.dumps({'status': status, 'rows': len(rows), 'wall_s': time.monotonic() - started,
                      'pictures': len(os.listdir(os.path.join(output, 'pictures'))),
                      'trajectory_bytes': os.path.getsize(os.path.join(output, 'trajectories.jsonl')),
                      'page_bytes': os.path.getsize(os.path.join(output, 'report.html')), 'peak_mb': peak_mb()}))
    return status


if __name__ == '__main__':              # (a local cluster's workers import this file again: the guard is needed)
    sys.exit(main(int(sys.argv[1]), sys.argv[2], *[int(a) for a in sys.argv[3:4]]))
