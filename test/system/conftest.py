"""Fixtures of the system tests: real ROS processes (a master, nodes, roslaunch) on loopback, each test on
its own free port, with logs in the test's temporary folder."""
import os
import signal
import socket
import subprocess
import sys
import time

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))
sys.path.insert(0, os.path.join(ROOT, 'test'))      # machine: what this machine lets a test do
from closed_loop import netenv  # noqa: E402
# Bounds that only catch hangs.
MASTER_WAIT_S = 20.0


def pytest_configure(config):
    config.addinivalue_line('markers', 'bench: a sweep of many scenarios, run by make bench (test/bench/bench_tutorial.py), '
                                       'not by make test')


def free_port():
    """A loopback port for a test's own master (below the ephemeral range: a test's watcher once waited 120 s
    on a port a node's server had taken)."""
    return netenv.free_loopback_port()


def ros_env(tmp_path, port, **extra):
    """The environment of a graph on loopback with its master on ``port`` and its logs under ``tmp_path``."""
    env = dict(os.environ, ROS_IP='127.0.0.1', ROS_MASTER_URI='http://127.0.0.1:%d' % port,
               ROS_HOME=str(tmp_path / 'ros_home'), ROS_LOG_DIR=str(tmp_path / 'ros_log'))
    env.pop('ROS_HOSTNAME', None)
    env.update(extra)
    return env


def master_up(port):
    with socket.socket() as s:
        s.settimeout(0.2)
        return s.connect_ex(('127.0.0.1', port)) == 0


def master_pid(port):
    """The pid of the ROS master answering on ``port``, or None where none does: not just anything listening
    there, since once a graph has let its port go, another test's node may take the same number for its own
    server."""
    return netenv.master_pid('http://127.0.0.1:%d' % port) if master_up(port) else None


def wait_master(port, process=None, timeout_s=MASTER_WAIT_S):
    """Wait for a master on ``port``: one that answers as a master, and, given ``process``, its own."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if process is not None and process.poll() is not None:
            raise AssertionError('the launch ended before its master came up (exit %s)' % process.returncode)
        pid = master_pid(port)
        if pid is not None:
            if process is not None and not _descends(pid, process.pid):
                raise AssertionError('port %d: the master answering there (pid %d) is not this launch\'s'
                                     % (port, pid))
            return
        time.sleep(0.1)
    raise AssertionError('no master on port %d within %g s' % (port, timeout_s))


def _descends(pid, ancestor):
    """Whether process ``pid`` is ``ancestor`` or a child of its children (roslaunch starts the master as its
    own child, in a session of its own)."""
    while pid and pid > 1:
        if pid == ancestor:
            return True
        try:
            with open('/proc/%d/stat' % pid) as f:
                pid = int(f.read().rsplit(')', 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            return False
    return False


def _logging_under(folder):
    """The pids of the processes whose arguments name a log under ``folder`` (a graph's ROS_LOG_DIR: its
    master's and its nodes' ``__log:=``)."""
    mark = ('__log:=' + folder + os.sep).encode()
    found = []
    for name in os.listdir('/proc'):
        if name.isdigit():
            try:
                with open('/proc/%s/cmdline' % name, 'rb') as f:
                    if any(arg.startswith(mark) for arg in f.read().split(b'\0')):
                        found.append(int(name))
            except OSError:
                pass
    return found


def stop(process, sig=signal.SIGINT, timeout_s=20.0):
    """End a process group started with start_new_session=True: ``sig``, then SIGKILL, and SIGKILL to whatever
    of the group outlived its leader."""
    if process.poll() is None:
        try:
            os.killpg(process.pid, sig)
            process.wait(timeout_s)
        except subprocess.TimeoutExpired:
            pass
        except ProcessLookupError:
            pass
    kill_group(process)


def kill_group(process):
    """SIGKILL whatever is left of the process group a process started with start_new_session=True led,
    even after the leader itself has ended (a background child of a shell that exited early)."""
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    if process.poll() is None:
        process.wait(5)


def wait_for(predicate, timeout_s, what, poll_s=0.1, log=None):
    """``predicate()``'s value once it is true, polled every ``poll_s``; AssertionError naming ``what`` after
    ``timeout_s`` (a bound that only catches hangs), with the end of the file ``log`` where one is given (it lies in
    the test's own folder, which pytest removes a few runs later)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        found = predicate()
        if found:
            return found
        time.sleep(poll_s)
    tail = ''
    if log is not None:
        try:
            with open(str(log), errors='replace') as f:
                tail = '\n--- the end of %s ---\n%s' % (log, f.read()[-LOG_TAIL_CHARS:])
        except OSError as error:
            tail = '\n(%s)' % error
    raise AssertionError('%s: not within %g s%s' % (what, timeout_s, tail))


#: How much of a log's end a failed wait shows.
LOG_TAIL_CHARS = 6000


@pytest.fixture
def roscore(tmp_path):
    """A master (roscore) on a free loopback port; yields its environment."""
    port = free_port()
    env = ros_env(tmp_path, port)
    process = subprocess.Popen(['roscore', '-p', str(port)], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_master(port, process)
        yield env
    finally:
        stop(process)
        # roslaunch runs the master and rosout in sessions of their own: where roslaunch did not end them in
        # time (a test stopped the master a while; a loaded machine), they would outlive the group's SIGKILL.
        # Each was started with its log under this graph's ROS_LOG_DIR.
        for pid in _logging_under(env['ROS_LOG_DIR']):
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass


def doc_code(page, after):
    """The first fenced code block of ``docs/page`` after the line ``after`` (a heading or a marker): the
    docs' examples are run as they stand, so they cannot rot."""
    lines = open(os.path.join(ROOT, 'docs', page)).read().split('\n')
    start = lines.index(after)
    begin = next(i for i in range(start, len(lines)) if lines[i].startswith('```'))
    end = next(i for i in range(begin + 1, len(lines)) if lines[i].startswith('```'))
    return '\n'.join(lines[begin + 1:end]) + '\n'


def drive_in_sim(env, tmp_path, controller_argv, watch_script, world='wall', timeout_s=120):
    """``sim.launch`` in ``world`` (camera off) and a controller process beside it, while ``watch_script``
    (Python, run in a process of its own) watches the graph and prints one JSON line as its last; returns
    that line's value. The controller's output is in ``tmp_path/controller.log``."""
    import json
    sim = subprocess.Popen(['roslaunch', 'closed_loop', 'sim.launch', 'world:=' + world, 'camera:=false'],
                           env=env, stdout=open(str(tmp_path / 'sim.log'), 'w'), stderr=subprocess.STDOUT,
                           start_new_session=True)
    controller = subprocess.Popen(controller_argv, env=env, stdout=open(str(tmp_path / 'controller.log'), 'w'),
                                  stderr=subprocess.STDOUT, start_new_session=True)
    try:
        watched = subprocess.run([sys.executable, '-c', watch_script], env=env, stdout=subprocess.PIPE,
                                 universal_newlines=True, timeout=timeout_s)
    finally:
        stop(controller)
        stop(sim)
    return json.loads(watched.stdout.strip().splitlines()[-1])


def fixture_workspace(tmp_path):
    """test/fixtures/fixture_controllers (and the robot description package it tests with) built as a user builds
    packages of their own: copied into the src/
    of a catkin workspace of its own, over this package's (the environment's), with catkin_make; returns
    the environment with that workspace's setup.bash sourced."""
    import shutil
    workspace = tmp_path / 'fixture_ws'
    for package in ('fixture_controllers', 'fixture_robot_description'):
        shutil.copytree(os.path.join(ROOT, 'test', 'fixtures', package), str(workspace / 'src' / package))
    build = subprocess.run(['catkin_make', '-C', str(workspace), '-DPYTHON_EXECUTABLE=' + sys.executable],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=600)
    assert build.returncode == 0, build.stdout[-4000:]
    sourced = subprocess.run(['bash', '-c', 'source "$1" && env -0', 'bash', str(workspace / 'devel' / 'setup.bash')],
                             stdout=subprocess.PIPE, check=True, timeout=60).stdout.decode()
    return dict(item.split('=', 1) for item in sourced.split('\0') if '=' in item)


def graph_leftovers(root):
    """What is left of the graph episodes whose folders are under ``root``: the processes that carry their
    mark (running ones: a zombie has no environment left) and their masters still answering on their ports
    (a master there that does not carry the mark is another test's, which took the number once it was free)."""
    import glob
    from closed_loop import launcher
    ports = [int(open(path).read()) for path in glob.glob(os.path.join(str(root), '**', 'port'), recursive=True)]
    marked = launcher.marked_processes(str(root))
    return {'processes': marked, 'listening': [p for p in ports if master_pid(p) in marked]}


def run_sweep(env, sweep_path, output, *extra, timeout_s=600):
    """``python3 -m closed_loop.sweep SWEEP --output OUTPUT ...``; returns (the process, its rows by index)."""
    import csv
    done = subprocess.run([sys.executable, '-m', 'closed_loop.sweep', str(sweep_path), '--output', str(output)]
                          + list(extra), env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=timeout_s)
    with open(os.path.join(str(output), 'rows.csv'), newline='') as f:
        rows = {int(row['index']): row for row in csv.DictReader(f)}
    return done, rows


#: How many busy processes the tests that say a result does not depend on the load run beside it: one, as the rest
#: of a test run loads the machine too (bench_graph holds graph episodes to it with two, ten times each).
LOAD = 1


class busy:
    """``with busy(2):`` two processes that only compute, at the test's own priority, for as long as the block runs
    (a loaded machine, for the tests that say a result does not depend on the load)."""

    def __init__(self, count):
        self.count, self.processes = count, []

    def __enter__(self):
        self.processes = [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(self.count)]
        return self

    def __exit__(self, *_):
        for process in self.processes:
            process.kill()
            process.wait()


def same_rows(rows, again, columns=('outcome', 'time_s', 'final_x', 'final_y', 'missed_ticks')):
    """The rows of two runs of one sweep that differ in ``columns``, by index: [] when every row is the same."""
    return [(index, {c: (row[c], again[index][c]) for c in columns if row[c] != again[index][c]})
            for index, row in sorted(rows.items()) if any(row[c] != again[index][c] for c in columns)]


class HandCluster:
    """A Dask cluster started by hand as a user starts one: ``dask scheduler`` on 127.0.0.1 (with TLS where
    ``certs`` names a folder that ``closed_loop.batch.certificates`` wrote), and ``worker()``s added at will, their
    output in ``log_path``. ``with HandCluster(...) as cluster:`` ends every process it started."""

    def __init__(self, log_path, certs=None):
        self.dask = os.path.join(os.path.dirname(sys.executable), 'dask')
        self.certs, self.log_path = certs, log_path
        port = free_port()
        self.address = '%s://127.0.0.1:%d' % ('tls' if certs else 'tcp', port)
        self.log = open(str(log_path), 'w')
        self.procs = []
        self._start([self.dask, 'scheduler', '--host', '127.0.0.1', '--port', str(port), '--no-dashboard']
                    + (['--protocol', 'tls'] + self.tls('scheduler') if certs else []))

    def tls(self, role):
        return ['--tls-ca-file', os.path.join(str(self.certs), 'ca.pem'),
                '--tls-cert', os.path.join(str(self.certs), role + '.pem'),
                '--tls-key', os.path.join(str(self.certs), role + '.key')] if self.certs else []

    def worker(self, name, env=None, prefix=()):
        """A one-thread worker named ``name``, with ``env`` (default: this process's), its command after
        ``prefix`` (a namespace of its own, say)."""
        return self._start(list(prefix) + [self.dask, 'worker', self.address, '--nworkers', '1', '--nthreads', '1',
                                           '--host', '127.0.0.1', '--no-dashboard', '--name', name]
                           + self.tls('worker'), env)

    def _start(self, argv, env=None):
        process = subprocess.Popen(argv, env=env, stdout=self.log, stderr=self.log)
        self.procs.append(process)
        return process

    def __enter__(self):
        return self

    def __exit__(self, *_):
        for p in reversed(self.procs):
            p.terminate()
        for p in self.procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()
        self.log.close()
