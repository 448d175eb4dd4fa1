"""The tools' launches: a stopped master is named before anything starts, and a launch ends with everything
it started, even a master that roslaunch could not end."""
import os
import signal
import subprocess
import sys
import time

from conftest import ROOT, master_pid, ros_env, free_port, wait_master


def gone(pid, timeout_s=10.0):
    """Whether ``pid`` has ended (or is a zombie) within ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            with open('/proc/%d/stat' % pid) as f:
                if f.read().rsplit(')', 1)[1].split()[0] == 'Z':
                    return True
        except OSError:
            return True
        time.sleep(0.1)
    return False


def test_the_demo_names_a_stopped_master_and_starts_nothing(roscore, tmp_path):
    port = int(roscore['ROS_MASTER_URI'].rsplit(':', 1)[1])
    pid = master_pid(port)
    os.kill(pid, signal.SIGSTOP)          # a roscore stopped with Ctrl-Z: it accepts, and never answers
    try:
        done = subprocess.run([sys.executable, os.path.join(ROOT, 'tools', 'demo.py'), '--seconds', '10'],
                              env=roscore, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=90)
    finally:
        os.kill(pid, signal.SIGCONT)
    out = done.stdout.decode(errors='replace')
    assert done.returncode == 1, out
    assert 'does not answer as a ROS master' in out and roscore['ROS_MASTER_URI'] in out, out
    assert 'nothing started' in out and 'roslaunch' not in out, out


def test_a_launch_ends_the_master_roslaunch_could_not(tmp_path):
    from closed_loop import launcher
    port = free_port()
    env = ros_env(tmp_path, port)
    with open(str(tmp_path / 'launch.log'), 'w') as log:
        launch = launcher.Launch(['-p', str(port), '--core'], log, env)
        try:
            wait_master(port, launch.process)
            master = master_pid(port)
            # roslaunch killed outright: its master, in a session of its own, is left running.
            os.kill(launch.pid, signal.SIGKILL)
            launch.process.wait(10)
            assert not gone(master, 1.0), 'the master went with roslaunch; nothing left to test'
        finally:
            launch.end(wait_s=5.0)
    assert gone(master), 'pid %d (the master) outlived the launch' % master
    assert not launcher.marked_processes(launch.mark)
