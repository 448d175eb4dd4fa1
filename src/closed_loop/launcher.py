"""A roslaunch that the package's tools (``make demo``, the screenshot) start and end, leaving nothing behind.

roslaunch starts the master it brings up in a session of its own, and when roslaunch itself is stuck (its
master does not answer) a signal to its group does not reach that master. So every process of the launch
carries a mark in its environment (:data:`MARK`, as a sweep's graph episodes do) and, once
roslaunch has had its time to end them, whatever still carries the mark is killed.

Before starting, :func:`master_problem` tells a master URI where something listens but does not answer as a
master (a roscore stopped with Ctrl-Z accepts connections and never answers; rosgraph's own check then
waits forever, and roslaunch with it). Free of ROS.
"""
import os
import re
import signal
import socket
import subprocess
import time
from urllib.parse import urlsplit

from closed_loop import netenv

#: The environment variable that marks every process of a launch (a sweep's graph episode: its folder).
MARK = 'CLOSED_LOOP_GRAPH'


def marked_processes(prefix):
    """Pids of the processes (this user's that can be read) whose ``CLOSED_LOOP_GRAPH`` starts with ``prefix``."""
    found, mark = [], (MARK + '=' + prefix).encode()
    for name in os.listdir('/proc'):
        if not name.isdigit() or int(name) == os.getpid():
            continue
        try:
            with open('/proc/%s/environ' % name, 'rb') as f:
                if any(item.startswith(mark) for item in f.read().split(b'\0')):
                    found.append(int(name))
        except OSError:
            continue            # gone, or not ours to read
    return found


#: How long kill_marked waits for the processes it killed to be gone (s): a killed process is listed until it
#: has exited, which on a loaded machine can be a moment after the signal.
KILL_WAIT_S = 5.0


def kill_marked(prefix, wait_s=KILL_WAIT_S):
    """SIGKILL every process marked with ``prefix`` (see :func:`marked_processes`), again while any is listed,
    until none is or ``wait_s`` has passed; returns the pids still listed (none, unless one cannot be killed)."""
    deadline = time.monotonic() + wait_s
    while True:
        left = marked_processes(prefix)
        if not left or time.monotonic() > deadline:
            return left
        for pid in left:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        time.sleep(0.05)


#: How long roslaunch gets after SIGINT to end its nodes and its master (s).
END_WAIT_S = 15.0
#: How long a master gets to answer (s).
ANSWER_WAIT_S = 3.0


def master_problem(uri):
    """None when the master at ``uri`` answers, or nothing listens there (roslaunch will start one); else one
    line that says what is wrong."""
    try:
        parts = urlsplit(uri)
        address = (parts.hostname, parts.port)
    except ValueError:
        return 'ROS_MASTER_URI %r is not a URI of the form http://HOST:PORT' % uri[:200]
    if not address[0] or not address[1]:
        return 'ROS_MASTER_URI %r is not a URI of the form http://HOST:PORT' % uri[:200]
    try:
        with socket.create_connection(address, timeout=ANSWER_WAIT_S):
            pass
    except OSError:
        return None
    if netenv.master_pid(uri, ANSWER_WAIT_S) is not None:
        return None
    return ('something listens at %s (ROS_MASTER_URI) but does not answer as a ROS master within %g s: a '
            'roscore stopped with Ctrl-Z (resume it with fg, or end it), or another program on that port'
            % (uri[:200], ANSWER_WAIT_S))


class Launch:
    """``roslaunch`` with ``args`` (a list; never through a shell), its output to ``log`` (a file), in a
    session of its own; :meth:`end` (or leaving a ``with`` block) ends it and everything it started."""

    def __init__(self, args, log, env=None):
        self.mark = 'launch-%d-%d%s' % (os.getpid(), time.monotonic_ns(), os.sep)
        env = dict(os.environ if env is None else env, **{MARK: self.mark})
        self.process = subprocess.Popen(['roslaunch'] + list(args), stdout=log, stderr=subprocess.STDOUT,
                                        env=env, start_new_session=True)
        self.pid = self.process.pid

    def poll(self):
        return self.process.poll()

    def wait(self, timeout=None):
        return self.process.wait(timeout)

    @property
    def returncode(self):
        return self.process.returncode

    def end(self, wait_s=END_WAIT_S):
        """SIGINT to roslaunch's group; after ``wait_s`` SIGKILL to it; then SIGKILL to whatever of the launch
        is left in any session (a master roslaunch could not end)."""
        try:
            os.killpg(self.process.pid, signal.SIGINT)
            self.process.wait(timeout=wait_s)
        except (ProcessLookupError, subprocess.TimeoutExpired):
            pass
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        if self.process.poll() is None:
            self.process.wait()
        kill_marked(self.mark)

    def __enter__(self):
        return self

    def __exit__(self, *_):
        self.end()


#: roslaunch colours its own lines (ANSI escapes), which a report quotes without.
ANSI_COLOUR = re.compile(r'\x1b\[[0-9;]*m')


def failure_lines(log_path, most=8):
    """The lines of a launch's log that say why it ended: FATAL and ERROR lines, and roslaunch's word that a
    required process died (roslaunch itself then exits 0, as ROS 1 does); the last ``most`` of them."""
    try:
        with open(log_path, errors='replace') as log:
            lines = [ANSI_COLOUR.sub('', line).rstrip() for line in log if 'FATAL' in line or '[ERROR]' in line
                     or 'REQUIRED process' in line or 'has died' in line]
    except OSError:
        return []
    return lines[-most:]


def early_end_report(tool, launch, log_path):
    """What ``tool`` says when ``launch`` ended before its run did: the exit code, the log, and the log's
    lines that say why."""
    first = '%s: the launch ended early (roslaunch exit code %s); see %s' % (tool, launch.returncode, log_path)
    return '\n'.join([first] + ['  ' + line for line in failure_lines(log_path)])
