"""A scenario's clock starts once the controller's connections are made (``closed_loop.nodes.graph_ready``),
not when it has merely registered with the master: real nodes (stock ``rostopic``) on a real master, and a
node that registers and never connects (a 'ghost', its API on a port where nothing listens)."""
import json
import socket
import subprocess
import time
import xmlrpc.client

import rosgraph

from conftest import stop, wait_for
from closed_loop.nodes import graph_ready

WAIT_S = 60.0     # bounds that only catch hangs
CALLER = '/graph_ready_test'


def dead_api():
    """The URI of a port on loopback where nothing listens (taken and let go)."""
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        port = s.getsockname()[1]
    return 'http://127.0.0.1:%d/' % port


def register_ghost(env, kind, topic, msg_type, name='/ghost'):
    """Register ``name`` as a subscriber or publisher (``kind``) of ``topic`` with the master, as a node would,
    without ever connecting."""
    master = xmlrpc.client.ServerProxy(env['ROS_MASTER_URI'])
    call = master.registerSubscriber if kind == 'subscriber' else master.registerPublisher
    code, status, _ = call(name, topic, msg_type, dead_api())
    assert code == 1, status


def test_a_connection_counts_as_made_once_its_publisher_lists_it(roscore, tmp_path):
    master = rosgraph.Master(CALLER, master_uri=roscore['ROS_MASTER_URI'])
    log = open(str(tmp_path / 'nodes.log'), 'w')
    talker = subprocess.Popen(['rostopic', 'pub', '-r', '20', '/probe', 'std_msgs/Empty', '__name:=talker'],
                              env=roscore, stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
    listener = None
    try:
        wait_for(lambda: '/talker' in dict(master.getSystemState()[0]).get('/probe', []), WAIT_S, 'talker up')
        assert graph_ready.missing(master, '/talker', CALLER) == []          # nobody reads /probe yet
        register_ghost(roscore, 'subscriber', '/probe', 'std_msgs/Empty')
        # Registered, and never connected: missing for as long as it lasts.
        assert graph_ready.missing(master, '/talker', CALLER) == ['/talker -> /probe -> /ghost']
        assert graph_ready.missing(master, '/talker', CALLER, {'/other'}) == []   # only the topics asked about
        listener = subprocess.Popen(['rostopic', 'echo', '/probe', '__name:=listener'], env=roscore, stdout=log,
                                    stderr=subprocess.STDOUT, start_new_session=True)
        wait_for(lambda: '/listener' in dict(master.getSystemState()[1]).get('/probe', []), WAIT_S,
                 'listener registered')
        wait_for(lambda: graph_ready.missing(master, '/listener', CALLER) == [], WAIT_S, 'the listener connected')
        assert graph_ready.missing(master, '/talker', CALLER) == ['/talker -> /probe -> /ghost']
        # The ghost's own inbound connection is as missing, seen from its side.
        assert graph_ready.missing(master, '/ghost', CALLER) == ['/talker -> /probe -> /ghost']
        # A publisher that cannot be asked (gone, or never was) lists nothing: its connections are missing.
        register_ghost(roscore, 'publisher', '/probe', 'std_msgs/Empty', name='/ghost_talker')
        wait_for(lambda: graph_ready.missing(master, '/listener', CALLER) == ['/ghost_talker -> /probe -> /listener'],
                 WAIT_S, 'the ghost publisher missing')
    finally:
        for process in (listener, talker):
            if process is not None:
                stop(process)


def test_the_judge_holds_the_clock_until_the_controllers_connections_are_made(roscore, tmp_path):
    """A ghost reader of /cmd_vel: the controller's connection to it is never made, so the judge waits its
    ready_timeout, says which connection was missing, and only then starts the simulation."""
    register_ghost(roscore, 'subscriber', '/cmd_vel', 'geometry_msgs/Twist')
    ready_timeout = 5.0
    subprocess.run(['rosparam', 'set', '/scenario_judge/ready_timeout', str(ready_timeout)], env=roscore, check=True)
    verdict_file = tmp_path / 'verdict.json'
    out = tmp_path / 'launch.log'
    began = time.monotonic()
    launch = subprocess.Popen(['roslaunch', 'closed_loop', 'scenario.launch', 'world:=wall', 'controller_pkg:=closed_loop',
                               'controller_type:=stop_on_obstacle', 'controller_name:=stop_on_obstacle', 'time_limit:=30',
                               'verdict_file:=%s' % verdict_file],
                              env=roscore, stdout=open(str(out), 'w'), stderr=subprocess.STDOUT, start_new_session=True)
    try:
        wait_for(lambda: verdict_file.exists() or launch.poll() is not None, 120, 'a verdict')
    finally:
        stop(launch)
    took_s = time.monotonic() - began
    text = out.read_text()
    assert verdict_file.exists(), text[-3000:]
    verdict = json.loads(verdict_file.read_text())
    assert verdict['outcome'] == 'stopped' and verdict['contacts'] == 0, verdict
    warning = [line for line in text.splitlines() if 'not made after' in line]
    assert len(warning) == 1 and '/stop_on_obstacle -> /cmd_vel -> /ghost' in warning[0], text[-3000:]
    assert '1 connection of the graph not made after 5 s' in warning[0], warning
    assert took_s > ready_timeout, took_s
    assert warning[0].endswith('starting the simulation anyway') and 'the controller is up' not in text, warning
