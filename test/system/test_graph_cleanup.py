"""Graph episodes leave nothing behind: no process of their graphs and no master's port still listening, after
a sweep of two of them (one of which hits its time limit), after a worker is killed in the middle of one,
and after Ctrl-C. The controller is this package's stop_on_obstacle run as its node (``{node: ...}``)."""
import csv
import os
import signal
import subprocess
import sys

from conftest import graph_leftovers, run_sweep, stop, wait_for

SWEEP_TIMEOUT_S = 300


def write_sweep(tmp_path, name, time_limits, seeds, rtf):
    path = tmp_path / (name + '.yaml')
    path.write_text('name: %s\nbase:\n  world: wall\n  controller: {node: stop_on_obstacle}\n'
                    '  real_time_factor: %g\ngrid:\n  time_limit_s: %s\n  seed: %s\n' % (name, rtf, time_limits, seeds))
    return path


def start_sweep(sweep, out):
    """The sweep on 2 workers, as a session of its own (so that a test can signal it as a terminal would)."""
    return subprocess.Popen([sys.executable, '-m', 'closed_loop.sweep', str(sweep), '--output', str(out),
                             '--workers', '2'], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            universal_newlines=True, start_new_session=True)


def running_keepers(root):
    """(keeper pid, its parent: the worker) of the graphs under ``root`` that are up (their master's port known)."""
    from closed_loop import launcher
    from closed_loop.batch import graph_keeper
    keepers = []
    for pid in launcher.marked_processes(str(root)):
        try:
            with open('/proc/%d/cmdline' % pid, 'rb') as f:
                argv = f.read().rstrip(b'\0').split(b'\0')
            with open('/proc/%d/stat' % pid) as f:
                parent = int(f.read().rsplit(')', 1)[1].split()[1])
        except OSError:
            continue
        if graph_keeper.__name__.encode() in argv and os.path.exists(argv[-2].decode() + '/port'):
            keepers.append((pid, parent))
    return keepers


def test_graph_episodes_one_of_them_timed_out_leave_no_process_and_no_port(tmp_path):
    sweep = write_sweep(tmp_path, 'two', '[2, 30]', '[0]', 8)
    done, rows = run_sweep(os.environ, sweep, tmp_path / 'out', '--workers', '2', timeout_s=SWEEP_TIMEOUT_S)
    assert done.returncode == 0, done.stdout[-3000:]
    assert sorted(rows) == list(range(2))
    outcomes = sorted((r['time_limit_s'], r['outcome']) for r in rows.values())
    assert outcomes == [('2', 'timed_out'), ('30', 'stopped')], outcomes
    assert graph_leftovers(tmp_path / 'out') == {'processes': [], 'listening': []}


def test_a_killed_worker_leaves_nothing_and_its_episode_runs_again(tmp_path):
    sweep = write_sweep(tmp_path, 'killed', '[30]', '[0, 1]', 2)
    out = tmp_path / 'out'
    process = start_sweep(sweep, out)
    try:
        keeper, worker = wait_for(lambda: running_keepers(out), 120, 'a graph episode up', poll_s=0.2)[0]
        os.kill(worker, signal.SIGKILL)
        text, _ = process.communicate(timeout=SWEEP_TIMEOUT_S)
    finally:
        stop(process)
    with open(str(out / 'rows.csv'), newline='') as f:
        rows = list(csv.DictReader(f))
    errors = ['%s: %s' % (r['index'], r['error']) for r in rows if r['outcome'] == 'error']
    assert process.returncode == 0, '%s\nerror rows: %s' % (text[-3000:], errors)
    indices = sorted(int(r['index']) for r in rows)
    assert indices == [0, 1], indices                       # each once
    assert any(name.endswith('.attempt-1') for name in os.listdir(str(out / 'graphs'))), os.listdir(str(out / 'graphs'))
    assert graph_leftovers(out) == {'processes': [], 'listening': []}


def test_ctrl_c_stops_the_sweep_and_its_graphs(tmp_path):
    sweep = write_sweep(tmp_path, 'interrupted', '[60]', '[0, 1, 2, 3]', 1)
    out = tmp_path / 'out'
    process = start_sweep(sweep, out)
    try:
        wait_for(lambda: len(running_keepers(out)) == 2, 120, 'two graph episodes up', poll_s=0.2)
        os.killpg(process.pid, signal.SIGINT)          # what Ctrl-C in its terminal does
        text, _ = process.communicate(timeout=120)
    finally:
        stop(process)
    assert process.returncode == 130 and 'interrupted' in text, text[-3000:]
    assert graph_leftovers(out) == {'processes': [], 'listening': []}
