"""The keeper of one graph episode's ROS graph: a small process that owns a master on a free loopback port and
the roslaunch of the episode, and leaves nothing behind.

    python3 -m closed_loop.batch.graph_keeper FOLDER LAUNCH_FILE

It starts ``rosmaster`` on a port it has checked is its own (the master answers with its pid), writes the
port to FOLDER/port, runs ``roslaunch`` of LAUNCH_FILE on it (output in FOLDER/graph.log), and shuts the
graph down when its standard input closes (the episode's runner is done, or has died: the pipe closes with
its process), on SIGTERM or SIGINT, or when roslaunch ends. Shutting down: SIGINT to roslaunch (which gives
each node SIGINT, then SIGTERM, then SIGKILL), a grace period, then SIGKILL to everything left of the graph:
the keeper's process group (roslaunch, the master) and every process that carries the graph's mark in its
environment (``CLOSED_LOOP_GRAPH``, which each node inherits; roslaunch starts each node in a session of its
own, so a process group does not hold them). Only the standard library: it runs beside whatever Python a
worker has.
"""
import os
import signal
import subprocess
import sys
import threading
import time

from closed_loop import netenv
from closed_loop.launcher import MARK, kill_marked

#: roslaunch waits this long after SIGINT (s) before SIGTERM, and this long after SIGTERM before SIGKILL.
NODE_SIGINT_S, NODE_SIGTERM_S = 3.0, 2.0
#: How long roslaunch gets to bring its nodes down before everything is killed (s).
GRACE_S = NODE_SIGINT_S + NODE_SIGTERM_S + 3.0
MASTER_WAIT_S = 15.0
MASTER_TRIES = 5


def start_master(folder, env):
    """(port, process) of a master of our own on a free loopback port."""
    log = open(os.path.join(folder, 'master.log'), 'ab')
    for _ in range(MASTER_TRIES):
        port = netenv.free_loopback_port()
        master = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], stdout=log, stderr=subprocess.STDOUT,
                                  env=env)
        deadline = time.monotonic() + MASTER_WAIT_S
        while time.monotonic() < deadline and master.poll() is None:
            pid = netenv.master_pid('http://127.0.0.1:%d' % port)
            if pid == master.pid:
                return port, master
            if pid is not None:
                break                       # another master answers there: try another port
            time.sleep(0.05)
        if master.poll() is None:
            master.kill()
            master.wait()
    raise RuntimeError('could not start a master on a free port in %d tries (see %s)' % (MASTER_TRIES, log.name))


def main(argv=None):
    folder, launch_file = (sys.argv[1:] if argv is None else argv)[:2]
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())

    def watch_stdin():
        try:
            while sys.stdin.buffer.read(4096):
                pass
        finally:
            stop.set()
    threading.Thread(target=watch_stdin, daemon=True).start()
    env = dict(os.environ)
    env.setdefault(MARK, os.path.abspath(folder) + os.sep)      # the runner sets it, for the keeper too
    env.pop('ROS_HOSTNAME', None)
    env['ROS_IP'] = '127.0.0.1'
    launch = None
    try:
        port, _master = start_master(folder, env)
        env['ROS_MASTER_URI'] = 'http://127.0.0.1:%d' % port
        with open(os.path.join(folder, 'port'), 'w') as f:
            f.write('%d\n' % port)
        with open(os.path.join(folder, 'graph.log'), 'ab') as log:
            launch = subprocess.Popen(['roslaunch', '--skip-log-check', '--sigint-timeout', str(NODE_SIGINT_S), '--sigterm-timeout',
                                       str(NODE_SIGTERM_S), '-p', str(port), launch_file],
                                      stdout=log, stderr=subprocess.STDOUT, env=env)
        while not stop.is_set() and launch.poll() is None:
            stop.wait(0.1)
    except (OSError, RuntimeError) as error:    # said where the runner looks, before the group goes
        with open(os.path.join(folder, 'keeper_error'), 'w') as f:
            f.write('%s\n' % error)
    finally:
        if launch is not None and launch.poll() is None:
            launch.send_signal(signal.SIGINT)
            try:
                launch.wait(GRACE_S)
            except subprocess.TimeoutExpired:
                pass
        sys.stdout.flush()
        kill_marked(env[MARK])                         # every node left, in whatever session
        os.killpg(os.getpgid(0), signal.SIGKILL)      # the master, roslaunch, and the keeper


if __name__ == '__main__':
    main()
