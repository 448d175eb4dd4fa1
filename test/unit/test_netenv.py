"""The loopback rule: set only when the user chose nothing (or chose a loopback master)."""
import io

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
