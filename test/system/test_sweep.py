"""Sweeps on real Dask clusters: a local one of two processes, and a `dask scheduler` with two `dask worker`
processes on 127.0.0.1; a malformed sweep file; an episode that fails; an interrupted sweep resumed."""
import csv
import json
import os
import signal
import subprocess
import sys
import time

import pytest

import machine
from conftest import ROOT, HandCluster

from closed_loop.batch import sweep, sweep_file, sweep_report, tune_thresholds
from closed_loop.batch.episode import EpisodeSpec
from closed_loop.batch.tally import Tally

TINY = """name: tiny
base: {world: wall, controller: stop_on_obstacle, time_limit_s: 15}
grid:
  settings.stop_distance: [0.1, 0.3]
  settings.cruise_speed: [0.5, 1.0]
  seed: [0, 1]
plot: {x: settings.stop_distance, lines: settings.cruise_speed}
"""
#: Bounds that only catch hangs.
HANG_S = 240.0


def rows_of(path):
    with open(path, newline='') as f:
        return list(csv.DictReader(f))


def test_a_tiny_sweep_on_a_local_cluster_writes_rows_summary_plot_and_a_recommendation(tmp_path, capsys):
    spec = tmp_path / 'tiny.yaml'
    spec.write_text(TINY)
    assert sweep.main([str(spec), '--output', str(tmp_path / 'out'), '--workers', '2']) == 0
    rows = rows_of(tmp_path / 'out' / 'rows.csv')
    assert len(rows) == 8 and len({r['spec'] for r in rows}) == 8
    by_stop = {s: [r for r in rows if r['settings.stop_distance'] == s] for s in ('0.1', '0.3')}
    assert all(r['outcome'] == 'collided' for r in by_stop['0.1'])      # the front is 0.15 m ahead of the LIDAR
    assert all(r['outcome'] == 'stopped' and float(r['min_clearance_m']) > 0.1 for r in by_stop['0.3'])
    assert (tmp_path / 'out' / 'plot.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert 'contact rate' in (tmp_path / 'out' / 'summary.txt').read_text()
    out = tmp_path / 'tune'
    assert tune_thresholds.main(['--speeds', '0.5', '--stops', '0.1,0.3', '--worlds', 'wall', '--seeds', '1',
                                 '--noise', '0', '--workers', '2', '--output', str(out)]) == 0
    printed = capsys.readouterr().out
    assert 'rule: recommended stop_distance: the smallest tried' in printed
    assert 'cruise 0.50 m/s: stop_distance 0.30 m, slow_distance 0.80 m' in printed
    page = (out / 'report.html').read_text()
    assert page.index('rule: recommended stop_distance') < page.index('cruise 0.50 m/s: stop_distance 0.30 m') \
        < page.index('<h2>Summary')
    assert (tmp_path / 'out' / 'report.html').exists() and (out / 'pictures' / 'episode-00000.png').exists()


@pytest.mark.parametrize('text, message', [
    ('name: x\ngrid: [1, 2\n', 'expected valid YAML'),
    ('name: x\ngrid: {seed: [0]}\ncolour: red\n', 'colour: expected a known key (name, base, grid, plot, report)'),
    ('name: x\ngrid: {speed: [0.5]}\n', 'grid.speed: expected an episode field'),
    ('name: x\ngrid: {settings.stop_distance: {from: 0.5, to: 0.1, step: 0.1}}\n', 'expected step > 0 and to >= from'),
    ('name: x\ngrid: {settings.stop_distance: [0.5, 1.5]}\n', 'settings.stop_distance=1.5'),
    ('name: x\nbase: {world: atlantis}\ngrid: {seed: [0]}\n', 'world'),
    ('name: ../x\ngrid: {seed: [0]}\n', 'name: expected 1 to 64 letters'),
    ('name: x\ngrid: {seed: [0]}\nplot: {x: settings.stop_distance}\n', 'plot.x: expected one of the grid keys'),
])
def test_a_malformed_sweep_file_is_refused_before_anything_runs(tmp_path, capsys, text, message):
    spec = tmp_path / 'bad.yaml'
    spec.write_text(text)
    assert sweep.main([str(spec), '--output', str(tmp_path / 'out')]) == 2
    error = capsys.readouterr().err
    assert str(spec) in error and message in error
    assert not (tmp_path / 'out').exists()


def test_an_episode_that_fails_is_a_row_with_its_error_and_the_sweep_goes_on(tmp_path):
    good = EpisodeSpec(world='wall', time_limit_s=10.0)
    bad = EpisodeSpec(world='wall', robot='no_such_robot', time_limit_s=10.0)     # past the file's checks
    built = sweep_file.Sweep('mixed', ['robot'], [({'robot': 'closed_loop'}, good), ({'robot': 'no_such_robot'}, bad)])
    rows = sweep.run(built, str(tmp_path / 'out'), workers=2)
    outcome = {r['robot']: r for r in rows}
    assert outcome['closed_loop']['outcome'] == 'stopped'
    assert outcome['no_such_robot']['outcome'] == 'error' and 'no_such_robot' in outcome['no_such_robot']['error']


@pytest.fixture(scope='module')
def hand_cluster(tmp_path_factory):
    """``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, started by hand: (address, its log)."""
    log_path = tmp_path_factory.mktemp('dask') / 'dask.log'
    with HandCluster(log_path) as cluster:
        for i in range(2):
            cluster.worker('w%d' % i)
        yield cluster.address, log_path


def test_a_sweep_runs_on_a_dask_scheduler_and_workers_started_by_hand(tmp_path, hand_cluster):
    address, log_path = hand_cluster
    spec = tmp_path / 'tiny.yaml'
    spec.write_text(TINY)
    assert sweep.main([str(spec), '--output', str(tmp_path / 'out'), '--scheduler', address]) == 0
    assert len(rows_of(tmp_path / 'out' / 'rows.csv')) == 8
    log = log_path.read_text()
    assert log.count('Register worker') >= 2, log[-2000:]


QUICK = """name: quick
base: {world: empty, controller: stop_on_obstacle, time_limit_s: 0.5}
grid:
  seed: {from: 0, to: 59, step: 1}
report: {pictures: none}
"""
#: Kills a sweep process (SIGKILL) at random moments, resuming it each time, then lets it finish: the sweep is
#: imported once and each run is a child forked from it (a fresh interpreter per run would cost seconds).
KILLER = r"""
import json, os, random, signal, sys, time
from closed_loop.batch import sweep, sweep_file
import distributed
spec, out, address, kills = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
built = sweep_file.load(spec)
chance = random.Random(7)
torn = 0

def child():
    try:
        with open(os.devnull, 'w') as quiet:
            sweep.run(built, out, scheduler=address, resume=True, stream=quiet)
    finally:
        os._exit(0)

killed_with = []
for attempt in range(kills + 1):
    pid = os.fork()
    if pid == 0:
        child()
    if attempt < kills:
        time.sleep(chance.uniform(0.5, 2.0))
        os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    path = os.path.join(out, 'rows.csv')
    if os.path.exists(path):
        with open(path, 'rb') as f:
            data = f.read()
        killed_with.append([data.count(b'\n') - 1, not data.endswith(b'\n')])
print(json.dumps(killed_with))
"""


def test_a_sweep_killed_at_random_moments_and_resumed_has_every_row_once_and_the_same_summary(tmp_path,
                                                                                                hand_cluster):
    address, _ = hand_cluster
    spec = tmp_path / 'quick.yaml'
    spec.write_text(QUICK)
    built = sweep_file.load(str(spec))
    whole = sweep.run(built, str(tmp_path / 'whole'), scheduler=address, stream=open(os.devnull, 'w'))
    script = tmp_path / 'killer.py'
    script.write_text(KILLER)
    done = subprocess.run([sys.executable, str(script), str(spec), str(tmp_path / 'out'), address, '10'],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=HANG_S)
    assert done.returncode == 0, done.stdout[-3000:]
    after_each = json.loads(done.stdout.strip().splitlines()[-1])
    # The kills came before, during and after the episodes (rows counted after each).
    assert len(after_each) == 11 and after_each[0][0] < 60 and after_each[-1] == [60, False], after_each
    rows = rows_of(tmp_path / 'out' / 'rows.csv')
    assert sorted(int(r['index']) for r in rows) == list(range(60))
    assert sorted(r['spec'] for r in rows) == sorted(r['spec'] for r in whole)
    summary = sweep_report.summarize
    assert summary(Tally.of(rows, built.keys)) == summary(Tally.of(whole, built.keys))
    results = ('outcome', 'time_s', 'final_x', 'final_y', 'final_yaw', 'min_clearance_m')
    by_spec = {r['spec']: [r[k] for k in results] for r in whole}
    assert all([r[k] for k in results] == by_spec[r['spec']] for r in rows)


FULL_DISK = """
import json, subprocess, sys
spec, out, address = sys.argv[1:4]
subprocess.run(['mount', '-t', 'tmpfs', '-o', 'size=12k', 'tmpfs', out], check=True)
def sweep(*more):
    done = subprocess.run([sys.executable, '-m', 'closed_loop.batch.sweep', spec, '--output', out, '--scheduler',
                           address] + list(more), stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    with open(out + '/rows.csv', 'rb') as f:
        return [done.returncode, done.stderr, f.read().decode()]
full = sweep()
subprocess.run(['mount', '-o', 'remount,size=4m', out], check=True)
print(json.dumps({'full': full, 'resumed': sweep('--resume')}))
"""


@machine.needs_mount()                   # a small tmpfs, in a mount namespace of its own
def test_a_full_disk_is_one_line_with_the_room_needed_and_the_rows_stay_whole_for_resume(tmp_path, hand_cluster):
    address, _ = hand_cluster
    spec = tmp_path / 'quick.yaml'
    spec.write_text(QUICK)
    out = tmp_path / 'small'
    out.mkdir()
    script = tmp_path / 'full.py'
    script.write_text(FULL_DISK)
    done = subprocess.run(['unshare', '--mount', '--propagation', 'private', sys.executable, str(script), str(spec),
                           str(out), address], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=HANG_S)
    assert done.returncode == 0, done.stdout[-3000:]
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    status, err, text = figures['full']
    # Progress (the episodes; the file's check, on a loaded machine) is not the error.
    lines = [line for line in err.splitlines()
             if line.strip() and not line.startswith(('sweep ', 'checking the sweep file: '))]
    assert status == 3 and len(lines) == 1 and 'Traceback' not in err, err
    assert lines[0].startswith('sweep: %s: the disk is full (' % out) and 'MiB more' in lines[0], lines
    parsed = list(csv.reader(text.splitlines()))
    assert text.endswith('\r\n') and 1 < len(parsed) < 61 and {len(cells) for cells in parsed} == {len(parsed[0])}
    status, err, text = figures['resumed']
    assert status == 0, err
    assert sorted(int(r['index']) for r in csv.DictReader(text.splitlines())) == list(range(60))


def test_an_interrupted_sweep_keeps_its_rows_and_resumes_where_it_stopped(tmp_path):
    spec = tmp_path / 'longer.yaml'
    spec.write_text(TINY.replace('seed: [0, 1]', 'seed: [0, 1, 2]'))
    out = tmp_path / 'out'
    env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, 'src') + os.pathsep + os.environ.get('PYTHONPATH', ''))
    p = subprocess.Popen([sys.executable, '-m', 'closed_loop.batch.sweep', str(spec), '--output', str(out),
                          '--workers', '2'], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    deadline = time.monotonic() + HANG_S
    while time.monotonic() < deadline and (not (out / 'rows.csv').exists() or len(rows_of(out / 'rows.csv')) < 3):
        time.sleep(0.05)
    os.killpg(p.pid, signal.SIGINT)          # Ctrl-C as a terminal sends it: to every process of the group
    _, err = p.communicate(timeout=HANG_S)
    assert p.returncode == 130, err
    assert '--resume' in err
    # Our lines only: no worker's KeyboardInterrupt traceback, no Dask warning.
    assert not [line for line in err.splitlines() if line.strip() and not line.startswith('sweep')], err
    kept = rows_of(out / 'rows.csv')
    assert 3 <= len(kept) < 12
    assert sweep.main([str(spec), '--output', str(out)]) == 2                   # not over it without --resume
    assert sweep.main([str(spec), '--output', str(out), '--resume', '--workers', '2']) == 0
    rows = rows_of(out / 'rows.csv')
    assert len(rows) == 12 and len({r['spec'] for r in rows}) == 12
    assert [r['spec'] for r in rows[:len(kept)]] == [r['spec'] for r in kept]
