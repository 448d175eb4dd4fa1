"""The right workers, or none, on a `dask scheduler` with `dask worker`s started by hand: a worker whose
closed_loop differs from the client's (a copy of its source with one line changed, first on its PYTHONPATH) is
refused before the first episode, in one line naming it and what differs; one that joins a running sweep runs
nothing of it: it is retired, its episodes run on the others, and every row is there once."""
import os
import shutil
import subprocess
import sys
import time

import pytest

from closed_loop.batch import sweep
from conftest import ROOT, HandCluster, wait_for

QUICK = """name: quick
base: {world: wall, controller: stop_on_obstacle, time_limit_s: 6}
grid:
  settings.cruise_speed: {from: 0.2, to: 1.0, step: 0.02}
report: {pictures: none}
"""


def other_source(root):
    """This package's Python source, copied, with a comment added: another version of closed_loop."""
    copy = root / 'other_src'
    shutil.copytree(os.path.join(ROOT, 'src', 'closed_loop'), str(copy / 'closed_loop'),
                    ignore=shutil.ignore_patterns('__pycache__'))
    with open(str(copy / 'closed_loop' / 'geometry.py'), 'a') as f:
        f.write('# another version\n')
    return str(copy)


@pytest.fixture
def cluster(tmp_path):
    with HandCluster(tmp_path / 'dask.log') as hand:
        yield hand


def worker(cluster, name, pythonpath=None):
    """A worker named ``name``; ``pythonpath``: a folder put first on its PYTHONPATH."""
    env = dict(os.environ)
    if pythonpath:
        env['PYTHONPATH'] = os.pathsep.join([pythonpath, env.get('PYTHONPATH', '')])
    return cluster.worker(name, env=env)


def registered(address, count):
    import distributed
    with distributed.Client(address, timeout='20s') as client:
        client.wait_for_workers(count, timeout=60)


def test_a_worker_of_another_version_is_refused_before_the_first_episode(tmp_path, cluster, capsys):
    worker(cluster, 'same')
    worker(cluster, 'other', other_source(tmp_path))
    registered(cluster.address, 2)
    spec = tmp_path / 'quick.yaml'
    spec.write_text(QUICK)
    assert sweep.main([str(spec), '--output', str(tmp_path / 'out'), '--scheduler', cluster.address]) == 2
    err = capsys.readouterr().err
    assert err.startswith('sweep: worker tcp://127.0.0.1:') and '(other): closed_loop 0.' in err, err
    assert 'where this client has 0.' in err and err.count('\n') == 1, err
    with open(str(tmp_path / 'out' / 'rows.csv')) as f:
        assert f.read().count('\n') == 1                              # the header: no episode ran


def test_a_worker_of_another_version_that_joins_is_retired_and_runs_nothing(tmp_path, cluster):
    worker(cluster, 'same')
    registered(cluster.address, 1)
    spec = tmp_path / 'quick.yaml'
    spec.write_text(QUICK)
    out = tmp_path / 'out'
    run = subprocess.Popen([sys.executable, '-m', 'closed_loop.sweep', str(spec), '--output', str(out),
                            '--scheduler', cluster.address], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           universal_newlines=True)
    try:
        wait_for(lambda: os.path.exists(str(out / 'rows.csv')) and open(str(out / 'rows.csv')).read().count('\n') > 2,
                 120, 'the sweep under way')
        other = worker(cluster, 'other', other_source(tmp_path))
        text, _ = run.communicate(timeout=300)
    finally:
        if run.poll() is None:
            run.kill()
    assert run.returncode == 0, text[-3000:]
    with open(str(out / 'rows.csv')) as f:
        lines = f.read().splitlines()[1:]
    assert len(lines) == 41 and len({line.split(',')[0] for line in lines}) == 41, len(lines)
    assert 'differs from this client: closed_loop' in text and 'retired, its episodes run elsewhere' in text, text[-3000:]
    deadline = time.monotonic() + 30
    while other.poll() is None and time.monotonic() < deadline:
        time.sleep(0.2)
    assert other.poll() is not None                                    # retired: closed
