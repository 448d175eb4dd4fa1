"""Where a sweep's episodes run: a local Dask cluster of this machine's cores (the default), or a cluster of yours
named with ``--scheduler``. Shared by every sweep command (sweep, search, compare, tune_thresholds).

    --scheduler tcp://127.0.0.1:8786                    a cluster on this machine
    --scheduler tls://lab-1:8786 --tls ~/.closed_loop/tls  a cluster of several machines, only you

A scheduler takes work from anyone who reaches its port, and a worker runs whatever it is given: on a network,
use Dask's TLS with mutual authentication (``closed_loop.batch.certificates`` makes a CA and a certificate and key
for the scheduler, the workers and the client; ``--tls DIR`` is the folder holding ``ca.pem``, ``client.pem`` and
``client.key``). A plain ``tcp://`` scheduler not on loopback gets a warning naming the risk, once per process.
"""
import dataclasses
import ipaddress
import logging
import os
import sys
from typing import Optional
from urllib.parse import urlsplit

from closed_loop.batch.sweep_file import SweepError
from closed_loop.sim import quiet

#: The files of ``--tls DIR`` a client uses (``closed_loop.batch.certificates`` writes them).
CA_FILE, CLIENT_CERT, CLIENT_KEY = 'ca.pem', 'client.pem', 'client.key'
CONNECT_TIMEOUT = '20s'
_warned = set()


class ClusterError(SweepError):
    """A scheduler or its certificates named wrongly (the message says which and why)."""


@dataclasses.dataclass(frozen=True)
class Scheduler:
    """A running Dask scheduler: its address (``tcp://`` or ``tls://``) and, for TLS, the client's folder of
    certificates."""
    address: str
    tls: Optional[str] = None

    def security(self):
        """Dask's ``Security`` for this scheduler (None for tcp://): the CA, and the client's certificate and key,
        encryption required."""
        if self.tls is None:
            return None
        from distributed.security import Security
        return Security(tls_ca_file=os.path.join(self.tls, CA_FILE), tls_client_cert=os.path.join(self.tls, CLIENT_CERT),
                        tls_client_key=os.path.join(self.tls, CLIENT_KEY), require_encryption=True)


def scheduler_of(address, tls=None):
    """The Scheduler named by ``--scheduler`` and ``--tls`` (None: a local cluster); raises ClusterError naming
    what is wrong: an address that is neither tcp:// nor tls://, tls:// without its certificates, or certificates
    for a tcp:// scheduler."""
    if not address:
        if tls:
            raise ClusterError('--tls: certificates are for a scheduler of yours (--scheduler tls://HOST:PORT)')
        return None
    scheme, host, port = _parts(address)
    if scheme == 'tcp':
        if tls:
            raise ClusterError('--tls: %s is plain tcp://; name it tls://%s:%d to use the certificates'
                               % (address, host, port))
        return Scheduler(address)
    if not tls:
        raise ClusterError('--scheduler %s: a tls:// scheduler needs --tls DIR, the folder with %s, %s and %s '
                           '(closed_loop.batch.certificates makes them)' % (address, CA_FILE, CLIENT_CERT, CLIENT_KEY))
    folder = os.path.abspath(os.path.expanduser(tls))
    missing = [name for name in (CA_FILE, CLIENT_CERT, CLIENT_KEY) if not os.path.isfile(os.path.join(folder, name))]
    if missing:
        raise ClusterError('--tls %s: no %s in it' % (folder, ', '.join(missing)))
    return Scheduler(address, folder)


def _parts(address):
    if not isinstance(address, str) or '://' not in address:
        raise ClusterError('--scheduler %r: expected tcp://HOST:PORT or tls://HOST:PORT' % (address,))
    split = urlsplit(address)
    try:
        port = split.port
    except ValueError:
        port = None
    if split.scheme not in ('tcp', 'tls') or not split.hostname or port is None or split.path not in ('', '/'):
        raise ClusterError('--scheduler %r: expected tcp://HOST:PORT or tls://HOST:PORT' % (address,))
    return split.scheme, split.hostname, port


def on_loopback(host):
    """True if ``host`` names this machine's loopback (127.0.0.0/8, ::1, localhost)."""
    if host == 'localhost':
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def warn_if_open(scheduler, stream=sys.stderr):
    """Say once per process that a plain tcp:// scheduler off loopback lets anyone who reaches it run code."""
    scheme, host, port = _parts(scheduler.address)
    if scheme == 'tcp' and not on_loopback(host) and scheduler.address not in _warned:
        _warned.add(scheduler.address)
        stream.write('warning: %s is plain tcp:// and not on loopback: any host that reaches port %d can run code on '
                     'every worker of that cluster, and read what the episodes send; use tls:// with certificates '
                     '(docs/episodes.md, "On many machines")\n' % (scheduler.address, port))
        stream.flush()


def client_for(scheduler, workers):
    """(a Dask client, its local cluster or None): on ``scheduler`` (a Scheduler or an address), else a local
    cluster of ``workers`` processes (default: one per core) on 127.0.0.1."""
    if not quiet.verbose():
        # Dask's own warnings (a worker "still alive after 4.0 seconds, killing" after Ctrl-C) are not the
        # sweep's: only its errors are shown, here and (local_worker) in the local workers, as pybullet's output
        # is (--verbose shows them).
        logging.getLogger('distributed').setLevel(logging.ERROR)
    import distributed
    if scheduler:
        if isinstance(scheduler, str):
            scheduler = scheduler_of(scheduler)
        warn_if_open(scheduler)
        try:
            return distributed.Client(scheduler.address, timeout=CONNECT_TIMEOUT, security=scheduler.security()), None
        except (OSError, TimeoutError) as error:
            why = str(error).split('\n')[0] or type(error).__name__
            raise ClusterError('--scheduler %s: no connection within %s (%s)%s' % (
                scheduler.address, CONNECT_TIMEOUT, why, '; are the certificates of --tls signed by the CA the '
                'scheduler has?' if scheduler.tls else '')) from None
    # The local workers are forked from one server process that has imported Dask (Dask's "forkserver" method),
    # not each started afresh ("spawn", Dask's default): a worker then costs a fork, not Dask's imports again
    # (docs/benchmarks.md).
    import dask
    dask.config.set({'distributed.worker.multiprocessing-method': 'forkserver',
                     'distributed.worker.preload': ['closed_loop.batch.local_worker']})
    cluster = distributed.LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                                       processes=True, host='127.0.0.1', dashboard_address='127.0.0.1:0')
    return distributed.Client(cluster), cluster


def add_arguments(parser):
    """The options every sweep command has: where it runs, and --resume."""
    parser.add_argument('--scheduler', help='tcp://HOST:PORT or tls://HOST:PORT of a running Dask scheduler '
                        '(default: a local cluster of one worker process per core)')
    parser.add_argument('--tls', metavar='DIR', help='with a tls:// scheduler: the folder with %s, %s and %s '
                        '(rosrun closed_loop certificates makes them; default: none)' % (CA_FILE, CLIENT_CERT, CLIENT_KEY))
    parser.add_argument('--workers', type=int, help='local cluster size (default: the number of cores)')
    parser.add_argument('--resume', action='store_true', help='go on with the rows already in --output')
    parser.add_argument('--verbose', action='store_true', help="let pybullet's own output (its banner, its URDF "
                        'importer warnings) through to the terminal')
