"""A lockstepped graph can be watched with the stock tools, and being watched changes nothing: scenario.launch
(lockstep, its default) with the stop_on_obstacle node, run once alone and once with ``rostopic echo``,
``rostopic hz`` and ``rosbag record`` subscribed from outside the launch, gives the same verdict to the bit;
the watchers see what was published: every scan 0.1 s of simulated time apart, /clock with no gap, commands,
and ``rostopic hz`` reports the LIDAR's 10 Hz of simulated time. The watched run is also paused mid-way for three
times the controller's scan_timeout of wall time, and that changes nothing either: in lockstep no node stops the
robot for wall time that passed (the machine's load would then decide the run)."""
import json
import os
import re
import signal
import subprocess
import threading
import time

import rosbag
import rosgraph

from closed_loop.control.decisions import StopSettings
from conftest import roscore, stop, wait_for  # noqa: F401  (roscore: a fixture)

#: Long enough that the watched run lasts a few seconds of wall time however fast lockstep goes: ``rostopic hz``
#: prints once a wall second, and only once the messages it heard span a second since its last print.
TIME_LIMIT_S = 25.0
WATCHED = ('/scan', '/cmd_vel', '/clock')
#: Wall time the watched run is held paused mid-way: three times the controller's scan_timeout.
PAUSE_S = 3 * StopSettings().scan_timeout


def scenario(env, tmp_path, name):
    """scenario.launch with stop_on_obstacle in ``wall``, judged for TIME_LIMIT_S; its verdict (dict)."""
    verdict, log_path = tmp_path / (name + '.json'), tmp_path / (name + '.log')
    with open(str(log_path), 'w') as log:
        launch = subprocess.Popen(['roslaunch', 'closed_loop', 'scenario.launch', 'world:=wall',
                                   'controller_pkg:=closed_loop', 'controller_type:=stop_on_obstacle',
                                   'time_limit:=%g' % TIME_LIMIT_S, 'end_at_rest:=false', 'verdict_file:=%s' % verdict],
                                  env=env, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_for(verdict.exists, 120, 'the verdict of %s' % name, log=log_path)
    finally:
        stop(launch)
    return json.loads(verdict.read_text())


def subscribed(env, topics):
    master = rosgraph.Master('/test_lockstep', master_uri=env['ROS_MASTER_URI'])
    subscribers = dict(master.getSystemState()[1])
    return all(any(n.startswith(('/rostopic', '/record')) for n in subscribers.get(t, [])) for t in topics)


def pause_mid_way(env, tmp_path, paused):
    """Once the echo has shown the first commands (the robot under way), pause the simulator for PAUSE_S of wall
    time; ``paused`` gets whether that ended before the verdict (of the run named 'watched')."""
    def call(service):
        return subprocess.run(['rosservice', 'call', service], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, timeout=300).returncode == 0
    echo = tmp_path / 'echo.txt'
    try:
        wait_for(lambda: echo.read_text().count('linear:') >= 2, 300, 'the first commands echoed')
        held = call('/sim/pause_physics')
        time.sleep(PAUSE_S)
        paused.append(held and call('/sim/unpause_physics') and not (tmp_path / 'watched.json').exists())
    except (AssertionError, subprocess.TimeoutExpired) as error:       # (hang guards only)
        paused.append(str(error))


def test_echo_hz_and_a_bag_watch_a_lockstepped_scenario_and_change_nothing(roscore, tmp_path):
    env = roscore
    alone = scenario(env, tmp_path, 'alone')
    assert alone['outcome'] == 'timed_out' and alone['missed_ticks'] == 0 and alone['contacts'] == 0, alone
    # Watchers started as a user starts them, beside the launch (on simulated time, as the launch sets it).
    subprocess.run(['rosparam', 'set', '/use_sim_time', 'true'], env=env, check=True, timeout=30)
    bag = tmp_path / 'watched.bag'
    echo_out, hz_out = open(str(tmp_path / 'echo.txt'), 'w'), open(str(tmp_path / 'hz.txt'), 'w')
    # (Read while they run: their output unbuffered, as in a terminal; into a file Python holds it in a buffer.)
    shown = dict(env, PYTHONUNBUFFERED='1')
    watchers = [subprocess.Popen(['rostopic', 'echo', '-n', '5', '/cmd_vel'], env=shown, stdout=echo_out,
                                 stderr=subprocess.STDOUT, start_new_session=True),
                subprocess.Popen(['rostopic', 'hz', '/scan'], env=shown, stdout=hz_out, stderr=subprocess.STDOUT,
                                 start_new_session=True),
                subprocess.Popen(['rosbag', 'record', '-O', str(bag)] + list(WATCHED), env=env,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, start_new_session=True)]
    try:
        wait_for(lambda: subscribed(env, WATCHED), 60, 'rostopic and rosbag subscribed')
        paused = []
        pauser = threading.Thread(target=pause_mid_way, args=(env, tmp_path, paused))
        pauser.start()
        watched = scenario(env, tmp_path, 'watched')
        pauser.join(60)
        assert paused == [True], 'the watched run was not paused before its verdict: %s' % paused
        wait_for(lambda: re.search(r'average rate', (tmp_path / 'hz.txt').read_text()), 30, 'a rate from rostopic hz')
        # Ctrl-C to the recorder: its wrapper exits at once, the recorder itself once it has closed the bag.
        os.killpg(watchers[-1].pid, signal.SIGINT)
        wait_for(bag.exists, 60, 'the bag closed')
    finally:
        for process in watchers:
            stop(process)
    assert watched == alone, (watched, alone)
    echoed = (tmp_path / 'echo.txt').read_text()
    assert echoed.count('linear:') == 5 and 'x: 0.5' in echoed, echoed
    rates = [float(r) for r in re.findall(r'average rate: ([0-9.]+)', (tmp_path / 'hz.txt').read_text())]
    assert rates and all(9.5 < r < 10.5 for r in rates), (tmp_path / 'hz.txt').read_text()
    with rosbag.Bag(str(bag)) as b:
        scans = [m.header.stamp.to_sec() for _, m, _ in b.read_messages('/scan')]
        clock = [m.clock.to_sec() for _, m, _ in b.read_messages('/clock')]
        commands = b.get_message_count('/cmd_vel')
    assert scans[0] <= 0.11 and scans[-1] >= TIME_LIMIT_S, (scans[:3], scans[-3:])
    assert all(abs(b - a - 0.1) < 1e-6 for a, b in zip(scans, scans[1:])), scans[:20]
    gaps = [(a, b) for a, b in zip(clock, clock[1:]) if not 0 < b - a <= 0.1 + 1e-6]
    assert clock[-1] >= TIME_LIMIT_S and not gaps, gaps[:5]
    assert commands >= 10 * TIME_LIMIT_S * 0.9, commands
    assert os.path.getsize(str(bag)) > 0
