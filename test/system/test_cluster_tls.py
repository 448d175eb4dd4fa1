"""A sweep on a Dask cluster only its owner can use: a `dask scheduler` and a `dask worker` started by hand with
TLS and the certificates `rosrun closed_loop certificates` writes (mutual authentication), on 127.0.0.1. The
owner's sweep runs (--scheduler tls://... --tls DIR); a client whose certificate another CA signed, and one that
speaks plain tcp:// to the scheduler, are refused in one line each, and neither runs anything there."""
import os

import pytest

from closed_loop.batch import certificates, cluster, sweep
from conftest import HandCluster

TINY = """name: tiny
base: {world: wall, controller: stop_on_obstacle, time_limit_s: 8}
grid:
  settings.cruise_speed: [0.3, 0.5]
report: {pictures: none}
"""


@pytest.fixture(scope='module')
def tls_cluster(tmp_path_factory):
    """(the scheduler's tls:// address, the owner's certificates, a stranger's, the cluster's log)."""
    root = tmp_path_factory.mktemp('tls')
    mine, theirs = root / 'mine', root / 'theirs'
    certificates.make(str(mine))
    certificates.make(str(theirs))
    with HandCluster(root / 'dask.log', certs=mine) as hand:
        hand.worker('w0')
        yield hand.address, mine, theirs, hand.log_path


def test_the_owners_sweep_runs_over_tls(tmp_path, tls_cluster, capsys):
    address, mine, _, log_path = tls_cluster
    spec = tmp_path / 'tiny.yaml'
    spec.write_text(TINY)
    assert sweep.main([str(spec), '--output', str(tmp_path / 'out'), '--scheduler', address, '--tls', str(mine)]) == 0
    assert 'episodes: 2, errors: 0' in capsys.readouterr().out
    log = log_path.read_text()
    assert 'Register worker' in log and 'tls://127.0.0.1' in log, log[-2000:]


def test_a_stranger_and_a_plain_client_are_refused_in_one_line(tmp_path, tls_cluster, capsys, monkeypatch):
    address, _, theirs, log_path = tls_cluster
    monkeypatch.setattr(cluster, 'CONNECT_TIMEOUT', '4s')     # (the refusal itself comes at once; Dask retries)
    spec = tmp_path / 'tiny.yaml'
    spec.write_text(TINY)
    for scheduler, tls in ((address, str(theirs)), (address.replace('tls://', 'tcp://'), None)):
        args = [str(spec), '--output', str(tmp_path / 'out'), '--scheduler', scheduler] + (['--tls', tls] if tls else [])
        assert sweep.main(args) == 2
        err = capsys.readouterr().err
        assert err.startswith('sweep: --scheduler %s: no connection within 4s' % scheduler), err
        assert err.count('\n') == 1, err
    assert not os.path.exists(str(tmp_path / 'out' / 'rows.csv')) or \
        open(str(tmp_path / 'out' / 'rows.csv')).read().count('\n') <= 1           # no row ran
