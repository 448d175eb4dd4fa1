"""Sweeps on several machines, played by network namespaces: a Dask scheduler, two workers and the client each in a
network namespace of its own, joined by a bridge in a namespace of its own (10.R.0.0/24, nothing else reachable),
each worker also in a mount namespace of its own where the client's folder is an empty tmpfs, with a temporary
folder of its own; TLS with the certificates `certificates` writes. A sweep of in-process and graph episodes gets
every row, picture, log and verdict back, with a worker killed mid-sweep; a worker of another closed_loop version
is refused; a client whose certificate another CA signed is refused. All traffic is on the namespaces'
addresses."""
import csv
import json
import os
import secrets
import shutil
import signal
import subprocess
import sys

import pytest

from closed_loop.batch import certificates
from conftest import ROOT, wait_for
from machine import needs_network_namespace

SPEC = """name: many
base: {world: wall, time_limit_s: 15}
grid:
  controller: [stop_on_obstacle, {node: stop_on_obstacle}]
  settings.cruise_speed: [0.3, 0.5, 0.7]
report: {pictures: all}
"""


def sh(*argv):
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)


class Network:
    """Namespaces named PREFIX-NAME, each with one address on a bridge of their own."""

    def __init__(self, names):
        tag = secrets.token_hex(2)
        self.prefix, self.subnet = 'cl%s' % tag, '10.%d.%d' % (200 + int(tag[0], 16), int(tag[1:], 16) % 250)
        self.switch = self.prefix + 'sw'
        self.spaces, self.address = [], {}
        sh('ip', 'netns', 'add', self.switch)
        self.spaces.append(self.switch)
        sh('ip', 'netns', 'exec', self.switch, 'ip', 'link', 'add', 'br0', 'type', 'bridge')
        sh('ip', 'netns', 'exec', self.switch, 'ip', 'link', 'set', 'br0', 'up')
        for n, name in enumerate(names, start=1):
            space, inner, outer = self.ns(name), 'e%s%d' % (tag, n), 'b%s%d' % (tag, n)
            sh('ip', 'netns', 'add', space)
            self.spaces.append(space)
            sh('ip', 'link', 'add', inner, 'type', 'veth', 'peer', 'name', outer)
            sh('ip', 'link', 'set', inner, 'netns', space)
            sh('ip', 'link', 'set', outer, 'netns', self.switch)
            sh('ip', 'netns', 'exec', self.switch, 'ip', 'link', 'set', outer, 'master', 'br0', 'up')
            self.address[name] = '%s.%d' % (self.subnet, n)
            sh('ip', 'netns', 'exec', space, 'ip', 'addr', 'add', self.address[name] + '/24', 'dev', inner)
            sh('ip', 'netns', 'exec', space, 'ip', 'link', 'set', inner, 'up')
            sh('ip', 'netns', 'exec', space, 'ip', 'link', 'set', 'lo', 'up')

    def ns(self, name):
        return '%s-%s' % (self.prefix, name)

    def run_in(self, name, argv, hide=None, **kwargs):
        """``argv`` in the namespace of ``name``; ``hide``: a folder that process sees as an empty tmpfs."""
        prefix = ['ip', 'netns', 'exec', self.ns(name)]
        if hide:
            prefix += ['unshare', '--mount', '--propagation', 'private', 'sh', '-c',
                       'mount -t tmpfs tmpfs "$0" && exec "$@"', str(hide)]
        return subprocess.Popen(prefix + list(argv), **kwargs)

    def close(self):
        for space in reversed(self.spaces):
            subprocess.run(['ip', 'netns', 'del', space], stderr=subprocess.DEVNULL)


@pytest.fixture
def lab(tmp_path):
    """(network, the client's folder, the certificates, the scheduler's tls:// address, start_worker, the log)."""
    dask = os.path.join(os.path.dirname(sys.executable), 'dask')
    net = Network(['scheduler', 'w1', 'w2', 'w3', 'client'])
    client_dir, certs = tmp_path / 'client', tmp_path / 'certs'
    client_dir.mkdir()
    certificates.make(str(certs), hosts=list(net.address.values()))
    log = open(str(tmp_path / 'dask.log'), 'w')
    address = 'tls://%s:8786' % net.address['scheduler']
    procs = []

    def tls(role):
        return ['--tls-ca-file', str(certs / 'ca.pem'), '--tls-cert', str(certs / (role + '.pem')),
                '--tls-key', str(certs / (role + '.key'))]

    def start_worker(name, pythonpath=None):
        tmp = tmp_path / (name + '_tmp')
        tmp.mkdir(exist_ok=True)
        env = dict(os.environ, TMPDIR=str(tmp))
        if pythonpath:
            env['PYTHONPATH'] = os.pathsep.join([pythonpath, env.get('PYTHONPATH', '')])
        p = net.run_in(name, [dask, 'worker', address, '--host', net.address[name], '--nworkers', '1',
                              '--nthreads', '1', '--no-dashboard', '--name', name] + tls('worker'),
                       hide=client_dir, env=env, stdout=log, stderr=log, start_new_session=True)
        procs.append(p)
        return p, tmp
    try:
        procs.append(net.run_in('scheduler', [dask, 'scheduler', '--protocol', 'tls', '--host',
                                              net.address['scheduler'], '--port', '8786', '--no-dashboard']
                                + tls('scheduler'), stdout=log, stderr=log, start_new_session=True))
        yield net, client_dir, certs, address, start_worker, tmp_path / 'dask.log'
    finally:
        for p in reversed(procs):
            try:
                os.killpg(p.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(p.pid, signal.SIGKILL)
                p.wait()
        log.close()
        net.close()


def sweep_in_client(net, args, **kwargs):
    return net.run_in('client', [sys.executable, '-m', 'closed_loop.sweep'] + list(args), stdout=subprocess.PIPE,
                      stderr=subprocess.STDOUT, universal_newlines=True, **kwargs)


def rows_of(path):
    with open(str(path), newline='') as f:
        return list(csv.DictReader(f))


@needs_network_namespace()
def test_a_sweep_on_several_machines_gets_everything_back_and_only_the_right_clients_and_workers_take_part(lab):
    net, client_dir, certs, address, start_worker, log_path = lab
    (w1, w1_tmp), (w2, w2_tmp) = start_worker('w1'), start_worker('w2')
    spec = client_dir / 'many.yaml'
    spec.write_text(SPEC)
    out = client_dir / 'out'
    run = sweep_in_client(net, [str(spec), '--output', str(out), '--scheduler', address, '--tls', str(certs)])
    try:
        # A worker killed mid-sweep (its whole process group, as a machine that goes away): no row is lost.
        wait_for(lambda: (out / 'rows.csv').exists() and len(rows_of(out / 'rows.csv')) >= 1, 180, 'a first row')
        os.killpg(w2.pid, signal.SIGKILL)
        text, _ = run.communicate(timeout=400)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 0, text[-3000:]
    rows = rows_of(out / 'rows.csv')
    assert sorted(int(r['index']) for r in rows) == list(range(6)), [r['index'] for r in rows]
    for row in rows:
        assert row['outcome'] == 'stopped' and not row['error'], row
        assert (out / 'pictures' / ('episode-%05d.png' % int(row['index']))).stat().st_size > 10000
        if row['controller'].startswith('{'):
            folder = out / 'graphs' / ('episode-%05d' % int(row['index']))
            assert row['logs'] == str(folder)
            assert json.loads((folder / 'verdict.json').read_text())['outcome'] == 'stopped'
            assert (folder / 'episode.launch').exists() and (folder / 'graph.log').exists()
    # The surviving worker kept nothing of what it sent back.
    assert [n for n in os.listdir(str(w1_tmp)) if n.startswith('closed_loop-episode-')] == []
    # The cluster's traffic was on the namespaces' addresses.
    log = log_path.read_text()
    assert 'tls://%s:' % net.address['w1'] in log and 'tls://%s:8786' % net.address['scheduler'] in log, log[-2000:]

    # A client whose certificate another CA signed gets nothing.
    strangers = client_dir / 'strangers'
    certificates.make(str(strangers))
    refused = sweep_in_client(net, [str(spec), '--output', str(client_dir / 'stranger'), '--scheduler', address,
                                    '--tls', str(strangers)])
    text, _ = refused.communicate(timeout=120)
    assert refused.returncode == 2 and 'no connection within' in text, text[-2000:]

    # A worker of another closed_loop version joins: the next sweep is refused, naming it.
    other = client_dir.parent / 'other_src'
    shutil.copytree(os.path.join(ROOT, 'src', 'closed_loop'), str(other / 'closed_loop'),
                    ignore=shutil.ignore_patterns('__pycache__'))
    with open(str(other / 'closed_loop' / 'geometry.py'), 'a') as f:
        f.write('# another version\n')
    start_worker('w3', str(other))
    wait_for(lambda: log_path.read_text().count('Register worker') >= 3, 120, 'w3 registered', poll_s=0.5,
             log=log_path)
    again = sweep_in_client(net, [str(spec), '--output', str(client_dir / 'again'), '--scheduler', address,
                                  '--tls', str(certs)])
    text, _ = again.communicate(timeout=120)
    assert again.returncode == 2 and '(w3): closed_loop 0.' in text, text[-2000:]
