"""A Dask worker whose files the client does not see, as on a machine of its own: it runs in a mount namespace of
its own where the client's folder is an empty tmpfs (the same path, another filesystem). A sweep of an in-process
and a graph episode gets every row and picture back, and the graph episode's folder (its launch file, the graph's
and each node's logs, its verdict) on the client, where the row's logs column points; the worker keeps nothing
of it."""
import csv
import json
import os

import pytest

from closed_loop.batch import sweep
from conftest import HandCluster, graph_leftovers

SPEC = """name: far
base: {world: wall, time_limit_s: 15}
grid:
  controller: [stop_on_obstacle, {node: stop_on_obstacle}]
report: {pictures: all}
"""


@pytest.fixture
def far_cluster(tmp_path):
    """(scheduler address, the client's folder the worker cannot see, the worker's temporary folder)."""
    hidden, worker_tmp = tmp_path / 'client', tmp_path / 'worker_tmp'
    hidden.mkdir()
    worker_tmp.mkdir()
    with HandCluster(tmp_path / 'dask.log') as cluster:
        cluster.worker('far', env=dict(os.environ, TMPDIR=str(worker_tmp)),
                       prefix=['unshare', '--mount', '--propagation', 'private', 'sh', '-c',
                               'mount -t tmpfs tmpfs "$0" && exec "$@"', str(hidden)])
        yield cluster.address, hidden, worker_tmp


def test_everything_a_row_points_to_comes_back_and_the_worker_keeps_nothing(far_cluster, capsys):
    address, hidden, worker_tmp = far_cluster
    spec = hidden / 'far.yaml'
    spec.write_text(SPEC)
    out = hidden / 'out'
    assert sweep.main([str(spec), '--output', str(out), '--scheduler', address]) == 0, capsys.readouterr()
    with open(str(out / 'rows.csv'), newline='') as f:
        rows = {json.loads(r['spec'])['controller'] if r['controller'].startswith('stop') else 'graph': r
                for r in csv.DictReader(f)}
    assert sorted(rows) == ['graph', 'stop_on_obstacle'], rows
    for row in rows.values():
        assert row['outcome'] == 'stopped' and not row['error'], row
        assert (out / 'pictures' / ('episode-%05d.png' % int(row['index']))).stat().st_size > 10000
    graph = rows['graph']
    assert graph['logs'] == str(out / 'graphs' / ('episode-%05d' % int(graph['index']))), graph['logs']
    folder = out / 'graphs' / ('episode-%05d' % int(graph['index']))
    verdict = json.loads((folder / 'verdict.json').read_text())
    assert verdict['outcome'] == 'stopped' and (folder / 'episode.launch').read_text().startswith('<launch>')
    assert 'scenario_judge' in (folder / 'graph.log').read_text()
    node_logs = [n for _, _, names in os.walk(str(folder / 'log')) for n in names if n.startswith('stop_on_obstacle')]
    assert node_logs, sorted(os.listdir(str(folder)))
    assert not (folder / 'LEFT_ON_WORKER.txt').exists()
    # The worker ran it in a folder of its own, which it removed once the row went.
    assert [n for n in os.listdir(str(worker_tmp)) if n.startswith('closed_loop-episode-')] == []
    assert graph_leftovers(worker_tmp) == {'processes': [], 'listening': []}       # its graph is down
