#!/usr/bin/env python3
"""Run every test of closed_loop -- the unit tests, the system tests and every rostest -- and print one closing line.

Usage (inside ``source env.sh``; ``make test`` does that):
    python3 tools/run_tests.py [--unit-only] [--rostest-only] [-k NAME]

Unit tests (test/unit) need no master. System tests (test/system) start real ROS processes outside
rostest -- a master per test on a free loopback port, roslaunch, rosbag, network namespaces and mounts (where
this machine allows no namespace or mount, the tests that need one skip: test/machine.py).
Rostest files each get the master rostest starts on a free port. roslaunch-check on every launch file, beside
two things at once: the files that measure rates or wall time or change a node while it runs, and the one that
follows the tutorial in real time (ALONE), one at a time, at the normal CPU priority, and beside them the unit
tests, every other system test file and every other rostest file, SIDE_BY_SIDE at a time, at the lowest CPU
priority (nice BESIDE_NICENESS), so that they take only the CPU the ALONE file leaves (the system test files that
sweep graph episodes first, and never two of them at once). Each has its own output in test_output/
(printed when it fails).

Results (JUnit XML and logs) go to ``test_output/``. The closing line is ``tests: N passed, M failed, K skipped``
(pytest and rostest counted together), after a line for each test skipped (only where this machine cannot give what
it needs: test/machine.py) and each failed; the exit status is non-zero if anything failed or nothing ran.
"""
import argparse
import functools
import glob
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
from closed_loop import netenv  # noqa: E402  (the graphs these start stay on loopback)
from job_cgroup import LEFT, JobCgroup  # noqa: E402  (tools/: a job's CPU, all its processes)
OUT = os.path.join(ROOT, 'test_output')
# A rostest file that hangs past this is killed and counted failed; each file also has its own time-limit.
ROSTEST_HANG_LIMIT_S = 300


def count_junit(path):
    """(passed, failed, skipped, failed test names) from one JUnit XML file; skipped is a list of 'name: why'."""
    passed = failed = 0
    names, skipped = [], []
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as error:
        # (rosunit opens its file when the test node starts and writes it at the end: one killed at its
        # time-limit leaves it empty; rostest's own file says so.)
        return 0, 1, [], ['%s: unreadable (%s)' % (path, error)]
    for case in root.iter('testcase'):
        name = '%s.%s' % (case.get('classname', ''), case.get('name', ''))
        if case.find('failure') is not None or case.find('error') is not None:
            failed += 1
            names.append(name)
        elif case.find('skipped') is not None:
            why = case.find('skipped').get('message') or case.find('skipped').text or ''
            skipped.append('%s: %s' % (name, why.strip().splitlines()[0] if why.strip() else 'no reason given'))
        else:
            passed += 1
    return passed, failed, skipped, names


def skip_note(skipped):
    return ', %d skipped' % len(skipped) if skipped else ''


def run_launch_checks(args):
    """roslaunch-check on every launch file (what roslaunch_add_file_check registers for catkin)."""
    script = '/usr/share/roslaunch/scripts/roslaunch-check'
    files = sorted(glob.glob(os.path.join(ROOT, 'launch', '*.launch')))
    if args.k:
        files = [f for f in files if args.k in os.path.basename(f)]
    results_dir = os.path.join(OUT, 'roslaunch-check')
    os.makedirs(results_dir, exist_ok=True)
    passed = failed = 0
    names = []
    print('== roslaunch-check %s' % ' '.join(os.path.basename(f) for f in files), flush=True)

    def check(path):
        xml = os.path.join(results_dir, os.path.splitext(os.path.basename(path))[0] + '.xml')
        return xml, subprocess.run([script, '-o', xml, '-t', path], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                   cwd=ROOT)
    # One after another: no thread pool here (concurrent.futures' submit holds a lock of the module's that another
    # thread's fork, with preexec_fn, once left released under it: "RuntimeError: release unlocked lock").
    checked = [check(path) for path in files]
    for path, (xml, out) in zip(files, checked):
        name = os.path.splitext(os.path.basename(path))[0]
        p, f, _, _ = count_junit(xml) if os.path.exists(xml) else (0, 0, [], [])
        if out.returncode != 0 or f or not p:
            failed += 1
            names.append('roslaunch-check %s: %s' % (name, out.stdout.decode(errors='replace').strip()))
        else:
            passed += 1
    return passed, failed, [], names


#: Jobs that measure rates or wall time, or change a node while it runs, or whose verdict turns on how soon a node
#: answers in wall time (episode_agreement, at half real time: at 1 m/s, a stop 70 ms late in wall time rests
#: 3.5 cm farther, beyond its 3 cm), run one at a time at the normal CPU priority; every other job (a system test file,
#: a rostest judged on simulated time and ground truth) runs SIDE_BY_SIDE at a time beside them, at niceness
#: BESIDE_NICENESS, each rostest with the master rostest starts on a free port and its own ROS_HOME and logs,
#: each system test on its own free ports.
#: (guard_reckless_*: cmd_vel_guard stops the robot where its scan or command is older than half a second of wall
#: time, as it must: starved beside the others, it stopped a reckless robot at 7 cm, not at the obstacle.)
#: (rviz_display: rviz drawing in software beside a lockstepped graph that starts, both starved at niceness 19, twice
#: stood at t = 0.12 s until the test's bound, 60 s and then 120 s of wall time; the cause is not found.)
#: (test_tutorial: the page's launch files run in real time, as a learner runs them; starved beside the others,
#: fusion.launch's robot once reached its goal without waiting for the walker: the camera's frames came late.)
ALONE = ('test_tutorial', 'sim_wall', 'loop_wall', 'loop_fast', 'kill_controller', 'kill_sim', 'reconfigure',
         'episode_agreement', 'guard_reckless_wall', 'guard_reckless_obstacle_course', 'rviz_display')
SIDE_BY_SIDE = 3
#: The jobs beside the ALONE ones take mostly the CPU those leave: a process at niceness 10 weighs 110 against the
#: 1024 of one at 0 (Linux's CFS), so an ALONE file's nodes run when they wake nearly as on an idle machine.
#: Not 19 (weight 15): where an ALONE file kept both cores busy, a lockstepped graph beside it, which needs each of
#: its nodes to run in turn at every instant, stood still (the CI's avoid_goal_topic: 1.2 s of simulated time in
#: 111 s of wall time, past its time-limit). Measured: avoid_goal_topic beside two busy processes at niceness 0 and
#: three at its own, 220 s and failed at niceness 19, 34 s at 10 (14 s idle); each ALONE rostest passed at 0 beside
#: three busy processes at niceness 10.
BESIDE_NICENESS = 10
#: System test files that run sweeps of graph episodes (two graphs at once each): they start first, and never
#: two of them at the same time, so that the machine is not asked for six graphs at once.
GRAPH_SWEEPS = ('test_graph_cleanup', 'test_own_controller', 'test_graph_agreement', 'test_failure_report')


def call(cmd, out, name, timeout=None, niceness=0, **kwargs):
    """Run ``cmd`` (the job ``name``) with its output to ``out`` at ``niceness``; returns (exit status or 'timeout',
    CPU seconds its processes used: all of them where a cgroup can count them, else it and the descendants it waited
    for), killed after ``timeout`` s if given."""
    group = JobCgroup(name)

    def first():
        if niceness:
            os.nice(niceness)
        group.enter()
    process = subprocess.Popen(cmd, stdout=out, stderr=subprocess.STDOUT, preexec_fn=first, **kwargs)
    killed = threading.Event()

    def kill():
        killed.set()
        process.kill()
    timer = threading.Timer(timeout, kill) if timeout else None
    if timer:
        timer.start()
    try:
        _, status, usage = os.wait4(process.pid, 0)
    finally:
        if timer:
            timer.cancel()
    process.returncode = os.waitstatus_to_exitcode(status)
    counted = group.seconds()
    group.close()
    own = usage.ru_utime + usage.ru_stime
    return 'timeout' if killed.is_set() else process.returncode, own if counted is None else max(counted, own)


def run_rostest_file(path, results_dir, niceness=0):
    """Run one rostest file (at ``niceness``); returns (passed, failed, skipped, failed names, what to print)."""
    name = os.path.splitext(os.path.basename(path))[0]
    log = os.path.join(results_dir, name + '.log')
    # Each file gets a results folder of its own: rosunit names its files after test-name only.
    file_results = os.path.join(results_dir, name)
    env = dict(os.environ, ROS_HOME=os.path.join(OUT, 'ros_home', name), ROS_LOG_DIR=os.path.join(OUT, 'ros_log', name),
               CLOSED_LOOP_TEST_OUTPUT=os.path.join(OUT, name))
    os.makedirs(env['CLOSED_LOOP_TEST_OUTPUT'], exist_ok=True)
    cmd = ['rostest', '--results-base-dir', file_results, 'closed_loop', os.path.basename(path)]
    started = time.monotonic()
    with open(log, 'w') as out:
        code, cpu_s = call(cmd, out, name, ROSTEST_HANG_LIMIT_S, niceness, env=env, cwd=ROOT)
    p = f = 0
    s, names = [], []
    # rosunit-<test-name>.xml: one testcase per test method (hztest, our unittest nodes).
    for xml in sorted(glob.glob(os.path.join(file_results, '**', 'rosunit-*.xml'), recursive=True)):
        dp, df, ds, dn = count_junit(xml)
        p, f, s, names = p + dp, f + df, s + ds, names + dn
    # rostest-<file>.xml: one testcase per <test>; a test node that crashed or hit its time-limit
    # only shows here.
    for xml in glob.glob(os.path.join(file_results, '**', 'rostest-*.xml'), recursive=True):
        _, whole_failed, _, whole_names = count_junit(xml)
        if whole_failed > f:
            names += ['%s: %s' % (name, n) for n in whole_names]
            f = whole_failed
    if code != 0 and f == 0:
        f, names = f + 1, names + ['%s (rostest exit %s, see %s)' % (name, code, log)]
    if p + f == 0:
        f, names = 1, ['%s (no test ran, see %s)' % (name, log)]
    text = '== rostest %s ... %d passed, %d failed%s (%.0f s, %.0f CPU-s)' % (name, p, f, skip_note(s),
                                                                           time.monotonic() - started, cpu_s)
    if f:
        with open(log) as out:
            text += '\n   --- tail of %s ---\n%s' % (log, out.read()[-3000:])
    return p, f, s, names, text


def run_pytest(path, results_dir, select=None, niceness=0):
    """pytest on a file of test/system or on test/unit (``select``: its -k), at ``niceness``; returns (passed,
    failed, skipped, failed names, what to print)."""
    name = os.path.splitext(os.path.basename(path))[0]
    xml = os.path.join(results_dir, name + '.xml')
    log = os.path.join(results_dir, name + '.log')
    started = time.monotonic()
    with open(log, 'w') as out:
        # (A test marked bench, a sweep of many scenarios, is make bench's: test/bench/bench_tutorial.py.)
        code, cpu_s = call([sys.executable, '-m', 'pytest', path, '-q', '-p', 'no:cacheprovider', '--junitxml', xml,
                            '-m', 'not bench'] + (['-k', select] if select else []), out, name, niceness=niceness,
                           cwd=ROOT)
    p, f, s, names = count_junit(xml) if os.path.exists(xml) else (0, 0, [], [])
    if code not in (0, 5) and f == 0:
        f, names = 1, ['%s (pytest exit %d, see %s)' % (name, code, log)]
    text = '== pytest %s ... %d passed, %d failed%s (%.0f s, %.0f CPU-s)' % (name, p, f, skip_note(s),
                                                                          time.monotonic() - started, cpu_s)
    if f:
        with open(log) as out:
            text += '\n   --- tail of %s ---\n%s' % (log, out.read()[-3000:])
    return p, f, s, names, text


def run_all(args):
    """The unit tests, the system test files and the rostest files: the ones in ALONE one at a time, and beside
    them the rest SIDE_BY_SIDE at a time at niceness BESIDE_NICENESS."""
    jobs = []
    if not args.rostest_only:
        unit = functools.partial(run_pytest, select=args.k)
        jobs.append((os.path.join(ROOT, 'test', 'unit'), unit, OUT))
    if not args.rostest_only and not args.unit_only:
        for path in sorted(glob.glob(os.path.join(ROOT, 'test', 'system', 'test_*.py'))):
            if not args.k or args.k in os.path.basename(path):
                jobs.append((path, run_pytest, os.path.join(OUT, 'system')))
    if not args.unit_only:
        for path in sorted(glob.glob(os.path.join(ROOT, 'test', 'rostest', '*.test'))):
            if not args.k or args.k in os.path.basename(path):
                jobs.append((path, run_rostest_file, os.path.join(OUT, 'rostest')))
    for _, _, folder in jobs:
        os.makedirs(folder, exist_ok=True)
    totals = [0, 0, [], []]
    lock = threading.Lock()

    def count(result):
        p, f, s, names, text = result
        with lock:
            print(text, flush=True)
            totals[0] += p
            totals[1] += f
            totals[2] += s
            totals[3] += names
    alone = [j for j in jobs if os.path.splitext(os.path.basename(j[0]))[0] in ALONE]
    beside = [j for j in jobs if j not in alone]
    print('== %d jobs one at a time, and beside them %d jobs (unit tests, system test files, rostest files) %d at '
          'a time at niceness %d' % (len(alone), len(beside), SIDE_BY_SIDE, BESIDE_NICENESS), flush=True)

    def alone_lane():
        for path, run, folder in alone:
            count(run(path, folder))
    lanes = [threading.Thread(target=alone_lane)]
    lanes += side_by_side_lanes(beside, count, BESIDE_NICENESS)
    for thread in lanes:
        thread.start()
    for thread in lanes:
        thread.join()
    return tuple(totals)


def side_by_side_lanes(jobs, count, niceness):
    """SIDE_BY_SIDE threads (not started) that run ``jobs`` at ``niceness``, handing each result to ``count``:
    the GRAPH_SWEEPS files first and one at a time (a lane that would start a second one takes the next other
    job instead)."""
    def name(job):
        return os.path.splitext(os.path.basename(job[0]))[0]

    def heavy(job):
        return name(job) in GRAPH_SWEEPS
    waiting = sorted(jobs, key=lambda job: not heavy(job))
    lock = threading.Lock()
    running_heavy = [False]

    def lane():
        while True:
            with lock:
                job = next((j for j in waiting if not (heavy(j) and running_heavy[0])), None)
                if job is None:
                    return
                waiting.remove(job)
                running_heavy[0] = running_heavy[0] or heavy(job)
            path, run, folder = job
            try:
                result = run(path, folder, niceness=niceness)
            finally:
                with lock:
                    running_heavy[0] = running_heavy[0] and not heavy(job)
            count(result)
    return [threading.Thread(target=lane) for _ in range(SIDE_BY_SIDE)]


def machine_busy_s():
    """CPU seconds every core of this machine has been busy since it started (``/proc/stat``: user, nice, system,
    irq, softirq), or None where it cannot be read. A job's own figure counts only the processes it waited for
    (not, for one, the workers that Dask's forkserver forks for a sweep); this counts everything."""
    try:
        with open('/proc/stat') as f:
            fields = f.readline().split()
        return sum(int(fields[i]) for i in (1, 2, 3, 6, 7)) / os.sysconf('SC_CLK_TCK')
    except (OSError, ValueError, IndexError):
        return None


def main():
    netenv.apply_loopback_defaults(os.environ)
    started, busy_before = time.monotonic(), machine_busy_s()
    # Started from a background job (`make test &`), SIGINT is ignored and every process started here would
    # inherit that: the tests that stop a node, a launch or a sweep as Ctrl-C does need it back.
    signal.signal(signal.SIGINT, signal.default_int_handler)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--unit-only', action='store_true')
    parser.add_argument('--rostest-only', action='store_true')
    parser.add_argument('-k', help='only unit tests matching it (pytest -k), and system test and rostest files '
                        'whose name contains it')
    args = parser.parse_args()
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    passed = failed = 0
    skipped, failures = [], []
    parts = []
    if not args.unit_only:
        parts.append(run_launch_checks)
    parts.append(run_all)
    # The launch checks (one process at a time, about 15 s) run beside the tests rather than before them.
    results = [None] * len(parts)

    def run_part(i, part):
        try:
            results[i] = part(args)
        except Exception as error:      # (the runner's own failure: counted and named, the other part's kept)
            results[i] = (0, 1, [], ['%s: the runner failed: %s: %s' % (part.__name__, type(error).__name__, error)])
            raise
    threads = [threading.Thread(target=run_part, args=(i, part)) for i, part in enumerate(parts)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for p, f, s, names in results:
        passed, failed, skipped = passed + p, failed + f, skipped + s
        failures += names
    # A test skips only where this machine cannot give what it needs (test/machine.py), saying what in one line.
    for name in skipped:
        print('SKIPPED: %s' % name)
    for name in failures:
        print('FAILED: %s' % name)
    busy_after, wall_s = machine_busy_s(), time.monotonic() - started
    for group in [LEFT.pop() for _ in range(len(LEFT))]:
        group.close(tries=10)
    if busy_before is not None and busy_after is not None:
        print('== the machine was busy %.0f CPU-s in the %d min %02d s of the tests (%.2f of its %d cores)'
              % (busy_after - busy_before, wall_s // 60, wall_s % 60, (busy_after - busy_before) / wall_s,
                 os.cpu_count() or 1))
    print('tests: %d passed, %d failed, %d skipped' % (passed, failed, len(skipped)))
    return 1 if failed or passed == 0 else 0


if __name__ == '__main__':
    sys.exit(main())
