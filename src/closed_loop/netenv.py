"""Where a local ROS graph listens: on loopback, unless the user has said otherwise.

ROS 1 binds every XML-RPC and TCPROS server socket to all interfaces (0.0.0.0) unless ``ROS_IP`` or
``ROS_HOSTNAME`` names a loopback address, and it names itself by the machine's host name, which
need not resolve. So, when the user has set none of ``ROS_IP``, ``ROS_HOSTNAME`` and
``ROS_MASTER_URI``, the package sets ``ROS_IP=127.0.0.1`` and a loopback ``ROS_MASTER_URI``; when
the user has set only a ``ROS_MASTER_URI`` on this machine's loopback, ``ROS_IP=127.0.0.1`` as well
(a graph whose master is reachable on loopback only cannot be joined from elsewhere anyway). Anything
else the user set is left alone: that is how a graph is opened to other machines (docs/safety.md).

``python3 -m closed_loop.netenv`` prints the ``export`` lines for a shell (``env.sh`` uses it).
"""
import random
import socket
import sys
import xmlrpc.client
from urllib.parse import urlsplit

LOOPBACK_IP = '127.0.0.1'
DEFAULT_MASTER_PORT = 11311
#: The variables by which a user chooses how the graph is reached; any of them set means "the user's".
USER_VARIABLES = ('ROS_IP', 'ROS_HOSTNAME', 'ROS_MASTER_URI')


def is_loopback_host(host):
    """True for ``localhost``, ``127.x.y.z`` and ``::1``."""
    host = (host or '').strip('[]').lower()
    return host == 'localhost' or host.startswith('127.') or host == '::1'


def loopback_defaults(environ):
    """The variables to add to ``environ`` (a mapping) so that the graph stays on loopback.

    Returns ``{}`` when the user has chosen where the graph listens (``ROS_IP`` or ``ROS_HOSTNAME``
    set, or a ``ROS_MASTER_URI`` on another host).
    """
    if environ.get('ROS_IP') or environ.get('ROS_HOSTNAME'):
        return {}
    uri = environ.get('ROS_MASTER_URI')
    if not uri:
        return {'ROS_IP': LOOPBACK_IP, 'ROS_MASTER_URI': 'http://%s:%d' % (LOOPBACK_IP, DEFAULT_MASTER_PORT)}
    try:
        host = urlsplit(uri).hostname
    except ValueError:
        host = None
    return {'ROS_IP': LOOPBACK_IP} if is_loopback_host(host) else {}


def apply_loopback_defaults(environ):
    """Add :func:`loopback_defaults` to ``environ`` in place (e.g. ``os.environ``); return what was added."""
    added = loopback_defaults(environ)
    environ.update(added)
    return added


def free_loopback_port():
    """A TCP port free on 127.0.0.1 now, for a master of our own, below the kernel's ephemeral range: every
    node binds its servers to ephemeral ports, so a node of a graph running beside could take a number
    from that range between this call and the master's bind."""
    with open('/proc/sys/net/ipv4/ip_local_port_range') as f:
        ephemeral_low = int(f.read().split()[0])
    low = min(20000, ephemeral_low // 2)
    while True:
        port = random.randrange(low, ephemeral_low)
        with socket.socket() as s:
            try:
                s.bind((LOOPBACK_IP, port))
            except OSError:
                continue
            return port


class _BoundedTransport(xmlrpc.client.Transport):
    """XML-RPC over HTTP that gives up after ``timeout_s`` (what listens may accept and never answer)."""

    def __init__(self, timeout_s):
        super().__init__()
        self.timeout_s = timeout_s

    def make_connection(self, host):
        connection = super().make_connection(host)
        connection.timeout = self.timeout_s
        return connection


def bounded_proxy(uri, timeout_s):
    """An XML-RPC proxy to ``uri`` (a master's or a node's API) whose calls give up after ``timeout_s`` s."""
    return xmlrpc.client.ServerProxy(uri, transport=_BoundedTransport(timeout_s))


def master_pid(uri, timeout_s=2.0):
    """The pid of the ROS master answering at ``uri``, or None where none does within ``timeout_s`` s: nothing
    listening, something that does not speak XML-RPC or never answers (rosgraph's own check then waits
    forever), or a node's API (it has no ``getSystemState``)."""
    try:
        proxy = bounded_proxy(uri, timeout_s)
        code, _, _ = proxy.getSystemState('/master_check')
        pid_code, _, pid = proxy.getPid('/master_check')
    except Exception:   # refused, timed out, not XML-RPC, no such method, a malformed URI
        return None
    return pid if code == 1 and pid_code == 1 and isinstance(pid, int) else None


def main(environ=None, out=sys.stdout):
    """Print ``export NAME=value`` lines for :func:`loopback_defaults` (values are fixed, never the user's)."""
    import os
    for name, value in sorted(loopback_defaults(os.environ if environ is None else environ).items()):
        out.write('export %s=%s\n' % (name, value))
    return 0


if __name__ == '__main__':
    sys.exit(main())
