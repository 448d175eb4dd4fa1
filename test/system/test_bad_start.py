"""Starting a node with bad input ends it at once with one clear line: a file that is not a world, a world
over the limits, a rate that would put the watchdogs to sleep, a log folder that cannot be written, a starter with no service to
call."""
import subprocess
import time

import pytest

from closed_loop.sim import world as world_mod

# Hang guard only: each of these is refused in about two seconds of wall time, 2 CPU-s. Generous: make test runs this
# file at niceness 19 beside jobs at 0, and a node started while those take both cores gets about 1.5% of one (a
# node that had printed nothing after 60 s, on a loaded CI machine, was still importing).
RUN_LIMIT_S = 300.0


def run_node(env, node, *params):
    started = time.monotonic()
    done = subprocess.run(['rosrun', 'closed_loop', node] + list(params), env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, timeout=RUN_LIMIT_S)
    return done.returncode, done.stdout.decode(errors='replace'), time.monotonic() - started


def fatal_lines(output):
    return [line for line in output.splitlines() if 'FATAL' in line]


def test_a_file_that_is_not_a_world_gives_one_short_line(roscore):
    code, out, _ = run_node(roscore, 'sim_node', '_world:=/etc/passwd', '_camera:=false')
    assert code != 0, out
    lines = fatal_lines(out)
    assert len(lines) == 1, out
    assert '/etc/passwd' in lines[0] and 'expected a mapping' in lines[0]
    # Not a word of the file: its kind and length only.
    assert len(lines[0]) < 300, lines[0]
    assert 'got text (' in lines[0] and 'root' not in lines[0].split('/etc/passwd', 1)[1]
    assert 'Traceback' not in out


def test_a_world_over_the_obstacle_limit_is_refused_before_anything_is_built(roscore, tmp_path):
    path = tmp_path / 'huge.yaml'
    count = world_mod.MAX_OBSTACLES + 1
    with open(path, 'w') as out:
        out.write('name: huge\nobstacles:\n')
        for i in range(count):
            out.write('  - {name: c%d, type: cylinder, position: [%d, 50], radius: 0.1}\n' % (i, 10 + i))
    assert path.stat().st_size < world_mod.MAX_WORLD_FILE_BYTES
    code, out, took_s = run_node(roscore, 'sim_node', '_world:=%s' % path, '_camera:=false')
    assert code != 0, out
    lines = fatal_lines(out)
    assert len(lines) == 1 and 'at most %d obstacles' % world_mod.MAX_OBSTACLES in lines[0], out
    assert '%d obstacles' % count in lines[0]


def test_a_world_file_over_the_size_limit_is_refused(roscore, tmp_path):
    path = tmp_path / 'big.yaml'
    path.write_text('name: big\n# ' + 'x' * world_mod.MAX_WORLD_FILE_BYTES + '\n')
    code, out, _ = run_node(roscore, 'sim_node', '_world:=%s' % path, '_camera:=false')
    assert code != 0
    lines = fatal_lines(out)
    assert len(lines) == 1 and 'at most %d bytes' % world_mod.MAX_WORLD_FILE_BYTES in lines[0], out


@pytest.mark.parametrize('node', ['stop_on_obstacle', 'state_machine_controller'])
def test_a_rate_that_would_stall_the_watchdog_is_refused(roscore, node):
    code, out, _ = run_node(roscore, node, '_rate_hz:=0.001')
    assert code == 2, out
    lines = fatal_lines(out)
    assert len(lines) == 1 and '~rate_hz' in lines[0] and 'at least 1' in lines[0], out


def test_log_lines_name_their_node(roscore):
    code, out, _ = run_node(roscore, 'obstacle_detector', '_warn_distance:=-1')
    assert code == 2
    assert '[/obstacle_detector]' in fatal_lines(out)[0], out


def test_an_unwritable_log_folder_gives_one_line(roscore, tmp_path):
    target = tmp_path / 'a_file'
    target.write_text('not a folder')
    env = dict(roscore, ROS_LOG_DIR=str(target / 'logs'))
    code, out, _ = run_node(env, 'obstacle_detector')
    assert code == 1, out
    assert 'Traceback' not in out
    lines = [line for line in out.splitlines() if line.strip()]
    assert len(lines) == 1 and 'obstacle_detector' in lines[0] and str(target) in lines[0] \
        and 'ROS_LOG_DIR' in lines[0], out


def test_start_when_ready_without_a_service_to_call_says_so(roscore):
    code, out, _ = run_node(roscore, 'start_when_ready')
    assert code == 2, out
    assert fatal_lines(out) == [line for line in out.splitlines() if '~unpause' in line] and len(fatal_lines(out)) == 1, out
