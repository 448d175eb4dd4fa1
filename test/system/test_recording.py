"""Recording that cannot lie: the folder and name reach rosbag as plain arguments (spaces, quotes and backticks
are just characters), and a recorder that cannot write ends the run with a message naming the folder."""
import glob
import os
import signal
import subprocess
import sys
import time

import rosbag

import machine
from conftest import ROOT, free_port, ros_env, stop, wait_master

RECORD_S = 6.0


def test_a_folder_name_with_space_quotes_and_backticks_gets_the_bag(tmp_path):
    canary = tmp_path / 'ran'
    folder = tmp_path / ('bags with space \'single\' "double" `touch %s`' % canary)
    port = free_port()
    env = ros_env(tmp_path, port)
    launch = subprocess.Popen(['roslaunch', '-p', str(port), 'closed_loop', 'record.launch',
                               'bag_dir:=%s' % folder, 'bag_name:=it\'s a "run"', 'images:=false'],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    talker = None
    try:
        wait_master(port, launch)
        talker = subprocess.Popen(['rostopic', 'pub', '-r', '20', '/cmd_vel', 'geometry_msgs/Twist',
                                   '{linear: {x: 0.25}}'], env=env, stdout=subprocess.DEVNULL,
                                  stderr=subprocess.STDOUT, start_new_session=True)
        time.sleep(RECORD_S)
        assert launch.poll() is None, 'the launch ended: %s' % launch.stdout.read().decode(errors='replace')
    finally:
        if talker is not None:
            stop(talker)
        stop(launch)
    out = launch.stdout.read().decode(errors='replace')
    assert not canary.exists(), 'a backtick in bag_dir ran a command'
    bags = glob.glob(os.path.join(glob.escape(str(folder)), 'it\'s a "run"_*.bag'))
    assert len(bags) == 1, 'bags in %r: %s\n%s' % (str(folder), os.listdir(folder) if folder.exists() else None, out)
    with rosbag.Bag(bags[0]) as bag:
        speeds = [m.linear.x for _, m, _ in bag.read_messages(topics=['/cmd_vel'])]
    assert speeds and all(v == 0.25 for v in speeds), speeds[:5]


def run_demo(tmp_path, *launch_args, seconds=30):
    port = free_port()
    env = ros_env(tmp_path, port)
    try:
        done = subprocess.run([sys.executable, os.path.join(ROOT, 'tools', 'demo.py'), '--seconds', str(seconds)]
                              + list(launch_args), env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              timeout=seconds + 60)
    except subprocess.TimeoutExpired as hung:
        log = open(os.path.join(ROOT, 'test_output', 'demo.log'), errors='replace').read()
        raise AssertionError('the demo hung; it printed:\n%s\nits launch log ends:\n%s'
                             % ((hung.output or b'').decode(errors='replace'), log[-3000:])) from None
    return done.returncode, done.stdout.decode(errors='replace')


@machine.needs_mount()
def test_a_read_only_bag_folder_fails_the_run(tmp_path):
    read_only = tmp_path / 'ro'
    read_only.mkdir()
    # Root writes through permission bits, so the folder is a read-only mount, as on a real locked disk.
    subprocess.run(['mount', '-t', 'tmpfs', '-o', 'ro,size=1m', 'closed_loop_test', str(read_only)], check=True)
    try:
        code, out = run_demo(tmp_path, 'record:=true', 'bag_dir:=%s' % (read_only / 'bags'), 'camera:=false')
    finally:
        subprocess.run(['umount', str(read_only)], check=True)
    assert code != 0, out
    assert 'recording failed' in out and str(read_only / 'bags') in out, out
    assert 'REQUIRED process' in out, out


def test_a_bag_folder_that_is_a_file_fails_the_run(tmp_path):
    a_file = tmp_path / 'file'
    a_file.write_text('x')
    code, out = run_demo(tmp_path, 'record:=true', 'bag_dir:=%s' % (a_file / 'bags'), 'camera:=false')
    assert code != 0 and 'recording failed' in out and str(a_file) in out, out


def test_too_little_free_space_ends_the_launch(tmp_path):
    port = free_port()
    done = subprocess.run(['roslaunch', '-p', str(port), 'closed_loop', 'record.launch',
                           'bag_dir:=%s' % (tmp_path / 'bags'), 'min_free_mb:=%d' % (2 ** 31 - 1)],
                          env=ros_env(tmp_path, port), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
    out = done.stdout.decode(errors='replace')
    # roslaunch's own status stays 0 when a required node dies (ROS 1); the launch ends, and says why.
    assert 'recording failed' in out and 'MiB free' in out and str(tmp_path / 'bags') in out, out
    assert 'REQUIRED process [record' in out, out


def test_demo_recording_holds_the_mode_and_the_stop_is_logged_once(tmp_path):
    code, out = run_demo(tmp_path, 'record:=true', 'bag_dir:=%s' % (tmp_path / 'bags'), 'bag_name:=demo',
                         'camera:=false', seconds=25)
    assert code == 0, out
    bags = glob.glob(str(tmp_path / 'bags' / 'demo_*.bag'))
    assert len(bags) == 1, os.listdir(tmp_path / 'bags')
    with rosbag.Bag(bags[0]) as bag:
        modes = [m.data for _, m, _ in bag.read_messages(topics=['/stop_on_obstacle/mode'])]
        counts = [m.data for _, m, _ in bag.read_messages(topics=['/contact_count'])]
    assert modes and modes[-1] == 'STOP', modes
    assert counts and counts[-1] == 0, counts
    # Standing at the wall is the normal end state: one line on entry, none repeated every 2 s. (Under load
    # the controller may also start in STOP, waiting for the simulator's first scan: another reason, logged
    # before the simulator's first line, not at the wall.)
    log = open(os.path.join(ROOT, 'test_output', 'demo.log')).read()
    assert log.count('-> STOP: obstacle') == 1, [line for line in log.splitlines() if 'STOP' in line]
    at_wall = log[log.index('-> STOP: obstacle'):]
    assert 'stopped:' not in at_wall, [line for line in at_wall.splitlines() if 'stopped:' in line]


def node_pid(env, name, deadline_s=60.0):
    """The pid of a node of the graph, asked of the node itself (its XML-RPC API, on loopback)."""
    import rosgraph
    import xmlrpc.client
    master = rosgraph.Master('/test_recording', master_uri=env['ROS_MASTER_URI'])
    end = time.monotonic() + deadline_s
    while True:
        try:
            return xmlrpc.client.ServerProxy(master.lookupNode(name)).getPid('/test_recording')[2]
        except (rosgraph.MasterException, OSError):
            if time.monotonic() > end:
                raise
            time.sleep(0.2)


def test_a_scenario_recorder_held_back_keeps_every_clock_message(tmp_path):
    # A loaded machine makes the recorder read several /clock messages at once; rospy's own subscription to
    # /clock (simulated time) asks for the last one only. Holding the recorder still does the same.
    bag_path, verdict = tmp_path / 'scenario.bag', tmp_path / 'verdict.json'
    port = free_port()
    env = ros_env(tmp_path, port)
    launch = subprocess.Popen(['roslaunch', '-p', str(port), 'closed_loop', 'scenario.launch', 'world:=wall',
                               'controller_pkg:=closed_loop', 'controller_type:=stop_on_obstacle',
                               'controller_name:=stop_on_obstacle', 'time_limit:=8', 'end_at_rest:=false',
                               'verdict_file:=%s' % verdict, 'bag:=%s' % bag_path],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_master(port, launch)
        pid = node_pid(env, '/scenario_recorder')
        deadline = time.monotonic() + 90
        while not (tmp_path / 'scenario.bag.part').exists() or os.path.getsize(tmp_path / 'scenario.bag.part') < 50000:
            assert time.monotonic() < deadline and launch.poll() is None, 'the scenario did not start'
            time.sleep(0.1)
        os.kill(pid, signal.SIGSTOP)
        time.sleep(1.5)
        os.kill(pid, signal.SIGCONT)
        while not verdict.exists():
            assert time.monotonic() < deadline + 60 and launch.poll() is None, 'no verdict'
            time.sleep(0.2)
    finally:
        stop(launch)
    out = launch.stdout.read().decode(errors='replace')
    assert bag_path.is_file(), out[-3000:]
    with rosbag.Bag(str(bag_path)) as bag:
        clock = [m.clock.to_sec() for _, m, _ in bag.read_messages('/clock')]
    # The simulator sends every step's clock at real time; after a stall of its own it catches up without a
    # burst, but always sends the clock before a scan (10 Hz). Held back 1.5 s, the recorder kept only the last.
    gaps = [(a, b) for a, b in zip(clock, clock[1:]) if b - a > 0.15]
    assert clock[0] <= 0.1 and clock[-1] >= 8.0 and not gaps, (clock[:3], clock[-3:], gaps[:5])
