"""The graph stays on loopback unless the user opens it: the demo, started with none of ROS_IP, ROS_HOSTNAME
and ROS_MASTER_URI set (env.sh's default), in a network namespace of its own whose host name resolves nowhere.
Its listening sockets are read with ss; a peer in a second namespace, joined by a veth pair (this test's own
hosts, nothing outside the machine), tries every port."""
import os
import re
import secrets
import subprocess
import time

import pytest

import machine
from conftest import ROOT, stop

from closed_loop import netenv

UP_LIMIT_S = 90.0
GRAPH_SCRIPT = r'''
set -e
ip link set lo up
hostname "$CL_HOSTNAME"
unset ROS_IP ROS_HOSTNAME ROS_MASTER_URI
source "$CL_ROOT/env.sh"
env | grep -E '^ROS_(IP|HOSTNAME|MASTER_URI)=' | sort > "$CL_OUT/env.txt"
roslaunch closed_loop demo.launch guard:=true > "$CL_OUT/launch.log" 2>&1 &
launch=$!
for _ in $(seq 300); do rostopic list > /dev/null 2>&1 && break; sleep 0.2; done
timeout 60 rostopic echo -n 1 /cmd_vel > "$CL_OUT/cmd_vel.txt"
sleep 2
ss -ltnpH > "$CL_OUT/sockets.txt"
touch "$CL_OUT/ready"
for _ in $(seq 600); do [ -e "$CL_OUT/done" ] && break; sleep 0.1; done
kill -INT $launch
wait $launch || true
'''
LISTEN = re.compile(r'^LISTEN\s+\d+\s+\d+\s+(\S+):(\d+)\s+\S+\s+users:\(\("([^"]*)",pid=(\d+)')


def sh(*argv):
    done = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
    assert done.returncode == 0, '%s: exit %d: %s' % (' '.join(argv), done.returncode, done.stdout.strip())


def listeners(text):
    """(address, port, command, pid) of each listening TCP socket in ``ss -ltnpH`` output."""
    found = []
    for line in text.splitlines():
        m = LISTEN.match(line.strip())
        if m:
            found.append((m.group(1), int(m.group(2)), m.group(3), int(m.group(4))))
    return found


def is_python(pid):
    try:
        return 'python' in os.path.basename(os.readlink('/proc/%d/exe' % pid))
    except OSError:
        return False


@pytest.mark.parametrize('environ, expected', [
    ({}, {'ROS_IP': '127.0.0.1', 'ROS_MASTER_URI': 'http://127.0.0.1:11311'}),
    ({'ROS_MASTER_URI': 'http://localhost:11411'}, {'ROS_IP': '127.0.0.1'}),
    ({'ROS_MASTER_URI': 'http://robot.lab:11311'}, {}),
    ({'ROS_IP': '10.0.0.7'}, {}),
    ({'ROS_HOSTNAME': 'robot.lab'}, {}),
])
def test_env_sh_sets_loopback_only_when_the_user_chose_nothing(environ, expected):
    env = {k: v for k, v in os.environ.items() if k not in netenv.USER_VARIABLES}
    env.update(environ)
    out = subprocess.run(['bash', '-c', 'source "$0/env.sh" && env', ROOT], env=env, check=True,
                         stdout=subprocess.PIPE).stdout.decode()
    got = dict(line.split('=', 1) for line in out.splitlines() if line.split('=', 1)[0] in netenv.USER_VARIABLES)
    want = dict(environ, **expected)
    if 'ROS_MASTER_URI' not in want:
        want['ROS_MASTER_URI'] = got.get('ROS_MASTER_URI')  # the workspace's own default, untouched
    assert got == want


@machine.needs_network_namespace()
def test_demo_graph_listens_on_loopback_and_comes_up_where_the_host_name_does_not_resolve(tmp_path):
    tag = secrets.token_hex(3)
    peer_ns, graph_end, peer_end = 'clpeer%s' % tag, 'clg%s' % tag, 'clp%s' % tag
    graph_ip, peer_ip = '10.213.%d.1' % (int(tag[:2], 16) % 250), '10.213.%d.2' % (int(tag[:2], 16) % 250)
    env = dict(os.environ, CL_ROOT=ROOT, CL_OUT=str(tmp_path), CL_HOSTNAME='closed-loop-%s.invalid' % tag,
               ROS_HOME=str(tmp_path / 'ros_home'), ROS_LOG_DIR=str(tmp_path / 'ros_log'))
    graph = subprocess.Popen(['unshare', '--net', '--uts', '--fork', 'bash', '-c', GRAPH_SCRIPT], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    accepted = []
    try:
        deadline = time.monotonic() + UP_LIMIT_S
        while not (tmp_path / 'ready').exists():
            assert graph.poll() is None and time.monotonic() < deadline, (
                'the graph did not come up: %s\n%s' % (graph.stdout.read().decode(errors='replace'),
                                                      (tmp_path / 'launch.log').read_text(errors='replace')
                                                      if (tmp_path / 'launch.log').exists() else ''))
            time.sleep(0.2)
        ns_pid = int(subprocess.run(['pgrep', '-P', str(graph.pid)], stdout=subprocess.PIPE).stdout.split()[0])
        sockets = listeners((tmp_path / 'sockets.txt').read_text())
        python_pids = {pid for _, _, _, pid in sockets if is_python(pid)}
        # A peer host: its own namespace, joined to the graph's by a veth pair.
        sh('ip', 'netns', 'add', peer_ns)
        sh('ip', 'link', 'add', graph_end, 'type', 'veth', 'peer', 'name', peer_end)
        sh('ip', 'link', 'set', graph_end, 'netns', str(ns_pid))
        sh('ip', 'link', 'set', peer_end, 'netns', peer_ns)
        sh('nsenter', '--net=/proc/%d/ns/net' % ns_pid, 'ip', 'addr', 'add', graph_ip + '/30', 'dev', graph_end)
        sh('nsenter', '--net=/proc/%d/ns/net' % ns_pid, 'ip', 'link', 'set', graph_end, 'up')
        sh('ip', 'netns', 'exec', peer_ns, 'ip', 'addr', 'add', peer_ip + '/30', 'dev', peer_end)
        sh('ip', 'netns', 'exec', peer_ns, 'ip', 'link', 'set', peer_end, 'up')
        probe = ('import socket, sys\n'
                 'for port in map(int, sys.argv[2:]):\n'
                 '    s = socket.socket(); s.settimeout(1.0)\n'
                 '    print(port, s.connect_ex((sys.argv[1], port))); s.close()\n')
        out = subprocess.run(['ip', 'netns', 'exec', peer_ns, '/usr/bin/python3', '-c', probe, graph_ip]
                             + [str(port) for _, port, _, _ in sockets], stdout=subprocess.PIPE,
                             check=True).stdout.decode()
        accepted = [int(port) for port, code in (line.split() for line in out.splitlines()) if code == '0']
    finally:
        (tmp_path / 'done').touch()
        try:
            graph.wait(30)
        except subprocess.TimeoutExpired:
            pass
        stop(graph)             # and the launch, had the script ended early (set -e)
        subprocess.run(['ip', 'netns', 'del', peer_ns], stderr=subprocess.DEVNULL)

    env_seen = (tmp_path / 'env.txt').read_text()
    assert 'ROS_IP=127.0.0.1' in env_seen and 'ROS_MASTER_URI=http://127.0.0.1:11311' in env_seen, env_seen
    assert 'linear' in (tmp_path / 'cmd_vel.txt').read_text(), 'no /cmd_vel: the graph did not run'
    python = [s for s in sockets if s[3] in python_pids]
    others = [s for s in sockets if s[3] not in python_pids]
    # master, roslaunch, sim, controller, guard, detector, vision: XML-RPC and TCPROS each
    assert len({s[3] for s in python}) >= 7, sockets
    assert all(address == '127.0.0.1' for address, _, _, _ in python), python
    # roscpp (rosout, robot_state_publisher) binds its data ports to loopback under a loopback ROS_IP, but its
    # XML-RPC server to every address, whatever ROS_IP says: one such socket per roscpp process, no more.
    wildcard = [s for s in others if s[0] != '127.0.0.1']
    assert {s[2] for s in others} <= {'rosout', 'robot_state_pub'}, others
    assert len(wildcard) == len({s[3] for s in others}), others
    # From the peer, every Python port and every roscpp data port refuses; only those XML-RPC ports answer.
    assert set(accepted) == {port for _, port, _, _ in wildcard}, (accepted, sockets)
