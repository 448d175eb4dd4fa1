#!/usr/bin/env python3
"""Run every benchmark of closed_loop -- each ``test/bench/bench_*.py`` in turn -- and print their figures.

Usage (inside ``source env.sh``; ``make bench`` does that):
    python3 tools/bench.py [-k NAME]

Each benchmark is a script run as a child process with this Python; its output is shown as it comes.
Benchmarks report figures and are not pass/fail on time: the exit status is non-zero only if a benchmark
could not measure (it exited non-zero or ran past its time limit) or none was found.
"""
import argparse
import glob
import os
import signal
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
from closed_loop import netenv  # noqa: E402  (the graphs these start stay on loopback)
BENCH_GLOB = os.path.join(ROOT, 'test', 'bench', 'bench_*.py')
# A benchmark still running after this long is stopped and counted as failed.
BENCH_TIME_LIMIT_S = 3600     # bench_report, the longest (a sweep of 100,000 episodes), about 40 minutes
# After SIGTERM a benchmark gets this long to stop what it started (a ROS master, nodes) before SIGKILL.
BENCH_STOP_GRACE_S = 45


def run_bench(path):
    """Run one benchmark script; returns (exit status or 'timeout', wall s)."""
    started = time.monotonic()
    child = subprocess.Popen([sys.executable, path], cwd=ROOT)
    try:
        code = child.wait(BENCH_TIME_LIMIT_S)
    except subprocess.TimeoutExpired:
        child.terminate()
        try:
            child.wait(BENCH_STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
        code = 'timeout'
    except KeyboardInterrupt:
        # Ctrl-C reached the child too; let it finish stopping what it started.
        try:
            child.wait(BENCH_STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
        raise
    return code, time.monotonic() - started


def main():
    netenv.apply_loopback_defaults(os.environ)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('-k', help='only benchmarks whose file name contains this')
    args = parser.parse_args()
    paths = sorted(glob.glob(BENCH_GLOB))
    if args.k:
        paths = [p for p in paths if args.k in os.path.basename(p)]
    if not paths:
        print('no benchmark matches %s%s' % (os.path.relpath(BENCH_GLOB, ROOT),
                                               ' and -k %s' % args.k if args.k else ''))
        return 1
    failed = []
    for path in paths:
        name = os.path.relpath(path, ROOT)
        print('== %s' % name, flush=True)
        code, wall_s = run_bench(path)
        print('== %s: %s in %.0f s\n' % (name, 'done' if code == 0 else 'FAILED (exit %s)' % code, wall_s),
              flush=True)
        if code != 0:
            failed.append(name)
    for name in failed:
        print('FAILED: %s' % name)
    print('benchmarks: %d run, %d failed' % (len(paths), len(failed)))
    return 1 if failed else 0


if __name__ == '__main__':
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        sys.exit(128 + signal.SIGINT)
