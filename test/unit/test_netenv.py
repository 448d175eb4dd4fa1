"""The loopback rule: set only when the user chose nothing (or chose a loopback master)."""
import io
import os
import socket
import threading
import time
from xmlrpc.server import SimpleXMLRPCServer

import pytest

from closed_loop import netenv


@pytest.mark.parametrize('environ, added', [
    ({}, {'ROS_IP': '127.0.0.1', 'ROS_MASTER_URI': 'http://127.0.0.1:11311'}),
    ({'ROS_MASTER_URI': ''}, {'ROS_IP': '127.0.0.1', 'ROS_MASTER_URI': 'http://127.0.0.1:11311'}),
    ({'ROS_MASTER_URI': 'http://localhost:11311'}, {'ROS_IP': '127.0.0.1'}),
    ({'ROS_MASTER_URI': 'http://127.0.0.5:1234/'}, {'ROS_IP': '127.0.0.1'}),
    ({'ROS_MASTER_URI': 'http://[::1]:11311'}, {'ROS_IP': '127.0.0.1'}),
    ({'ROS_MASTER_URI': 'http://192.168.1.20:11311'}, {}),
    ({'ROS_MASTER_URI': 'http://robot:11311'}, {}),
    ({'ROS_MASTER_URI': 'not a uri'}, {}),
    ({'ROS_IP': '192.168.1.5'}, {}),
    ({'ROS_HOSTNAME': 'robot.local'}, {}),
    ({'ROS_HOSTNAME': 'localhost'}, {}),
])
def test_loopback_defaults(environ, added):
    assert netenv.loopback_defaults(environ) == added


def test_apply_changes_only_what_it_adds():
    environ = {'ROS_MASTER_URI': 'http://localhost:11411', 'OTHER': 'x'}
    assert netenv.apply_loopback_defaults(environ) == {'ROS_IP': '127.0.0.1'}
    assert environ == {'ROS_MASTER_URI': 'http://localhost:11411', 'OTHER': 'x', 'ROS_IP': '127.0.0.1'}


def test_main_prints_fixed_export_lines_only():
    out = io.StringIO()
    netenv.main({}, out)
    assert out.getvalue() == 'export ROS_IP=127.0.0.1\nexport ROS_MASTER_URI=http://127.0.0.1:11311\n'
    out = io.StringIO()
    netenv.main({'ROS_HOSTNAME': '$(reboot)'}, out)
    assert out.getvalue() == ''


def test_a_free_loopback_port_is_below_the_ephemeral_range_and_free():
    with open('/proc/sys/net/ipv4/ip_local_port_range') as f:
        ephemeral_low = int(f.read().split()[0])
    for _ in range(20):
        port = netenv.free_loopback_port()
        assert 1024 <= port < ephemeral_low
        with socket.socket() as s:
            s.bind(('127.0.0.1', port))


def test_no_master_where_nothing_listens():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        port = s.getsockname()[1]       # bound, not listening: connections are refused
        assert netenv.master_pid('http://127.0.0.1:%d' % port) is None


def test_no_master_where_something_accepts_and_never_answers():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        s.listen(4)
        started = time.monotonic()
        assert netenv.master_pid('http://127.0.0.1:%d' % s.getsockname()[1], timeout_s=0.5) is None
        assert time.monotonic() - started < 5.0


class _NodeApi:
    """What a node's XML-RPC server answers: getPid, but not the master's getSystemState."""

    def getPid(self, caller_id):
        return 1, 'pid', os.getpid()


class _MasterApi(_NodeApi):
    def getSystemState(self, caller_id):
        return 1, 'state', [[], [], []]


@pytest.mark.parametrize('api, expected', [(_NodeApi(), None), (_MasterApi(), os.getpid())])
def test_only_a_master_counts_as_one(api, expected):
    server = SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False, allow_none=True)
    server.register_instance(api)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        assert netenv.master_pid('http://127.0.0.1:%d' % server.server_address[1]) == expected
    finally:
        server.shutdown()
        server.server_close()


def test_a_malformed_master_uri_is_no_master():
    assert netenv.master_pid('not a uri') is None
