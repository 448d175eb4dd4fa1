#!/usr/bin/env python3
"""The tutorial's exercise 2, typed as the page has it (test/system/test_tutorial.py, its test marked ``bench``):
``tune_thresholds --seeds 1`` (180 episodes), the shipped sweeps run by name and a renamed copy, 236 episodes
in four sweeps on a local cluster. A sweep of many scenarios, so make bench runs it, not make test; it prints
the wall time and how busy the machine was.

Run: ``python3 test/bench/bench_tutorial.py`` inside ``source env.sh`` (``make bench`` does that).
Figures: the exit status is non-zero when the exercise did not run as the page says.
"""
import os
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'tools'))
from run_tests import machine_busy_s  # noqa: E402  (how busy the machine was, as make test says it)


def main():
    started, busy = time.monotonic(), machine_busy_s()
    done = subprocess.run([sys.executable, '-m', 'pytest', '-q', '-p', 'no:cacheprovider', '-m', 'bench',
                           os.path.join(ROOT, 'test', 'system', 'test_tutorial.py')], cwd=ROOT,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    wall_s, cpu_s = time.monotonic() - started, machine_busy_s() - busy
    print(done.stdout[-3000:] if done.returncode else done.stdout.strip().splitlines()[-1])
    print('tutorial, exercise 2 as typed: %.0f s of wall time, the machine busy %.0f CPU-s (%.2f of its %d cores)'
          % (wall_s, cpu_s, cpu_s / wall_s, os.cpu_count() or 1))
    return done.returncode


if __name__ == '__main__':
    sys.exit(main())
