"""Sweep files fail fast: a grid is made lazily (a million combinations start in seconds and little memory),
each key's values are checked once, and an error about a file that is not a sweep never shows its content."""
import json
import os
import subprocess
import sys
import textwrap

import pytest

from closed_loop.batch import sweep_file
from closed_loop.batch.episode import EpisodeError, prepare
from closed_loop.batch.sweep_file import SweepError

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))

MILLION = textwrap.dedent("""\
    import json, sys, time
    def peak_mb():
        # This process's own peak (VmHWM: since its exec; ru_maxrss would count the pytest it was forked from).
        with open('/proc/self/status') as f:
            return next(int(line.split()[1]) for line in f if line.startswith('VmHWM:')) / 1024.0
    started = time.monotonic()
    from closed_loop.batch import sweep, sweep_file
    told = []
    built = sweep_file.load(sys.argv[1], lambda done, total: told.append((done, total)))
    last_assignment, last = built.specs[len(built.specs) - 1]
    made = [spec.seed for _, (_, spec) in zip(range(1000), built.specs)]
    print(json.dumps({'episodes': len(built.specs), 'last_seed': last.seed, 'made': made[-1],
                      'wall_s': time.monotonic() - started,
                      'peak_mb': peak_mb()}))
    """)


def write(tmp_path, text, name='s.yaml'):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_a_million_combinations_are_made_lazily_and_checked_once_per_key_value(tmp_path):
    """The issue's grid (seed from 0 to 999999): bench_sweep_file times it (5 s and 200 MB are the targets)."""
    path = write(tmp_path, 'name: big\nbase: {world: wall}\ngrid:\n  seed: {from: 0, to: 999999, step: 1}\n'
                 '  settings.stop_distance: [0.3]\n')
    script = tmp_path / 'million.py'
    script.write_text(MILLION)
    # The package from this source tree, as conftest.py gives it to the tests (not only where a workspace's
    # setup puts it on PYTHONPATH).
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in (SRC, os.environ.get('PYTHONPATH')) if p))
    done = subprocess.run([sys.executable, str(script), path], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True, timeout=120, env=env)
    assert done.returncode == 0, done.stdout[-2000:]
    figures = json.loads(done.stdout.strip().splitlines()[-1])
    assert figures['episodes'] == 1000000 and figures['last_seed'] == 999999 and figures['made'] == 999
    assert figures['peak_mb'] < 200, figures


def test_past_the_limit_a_grid_is_refused_before_any_combination_is_made(tmp_path):
    path = write(tmp_path, 'name: big\ngrid:\n  seed: {from: 0, to: 999999, step: 1}\n  scan_noise: [0.0, 0.01]\n')
    with pytest.raises(SweepError, match='2000000 episodes is more than 1000000'):
        sweep_file.load(path)
    with pytest.raises(SweepError, match='values is too many'):
        sweep_file.load(write(tmp_path, 'name: big\ngrid:\n  seed: {from: 0, to: 1000000000, step: 1}\n'))


def test_a_long_check_tells_how_many_checks_are_done(tmp_path, monkeypatch):
    """Each report counts the checks made so far (never 0 of N once one is done), up to all of them."""
    monkeypatch.setattr(sweep_file, 'PROGRESS_S', -1.0)          # every check is "long"
    path = write(tmp_path, 'name: t\nbase: {world: wall}\ngrid:\n  settings.stop_distance: [0.3, 0.4]\n')
    told = []
    sweep_file.load(path, lambda done, total: told.append((done, total)))
    total = told[0][1]
    assert [done for done, _ in told] == list(range(1, total + 1)) and {t for _, t in told} == {total}


def test_each_value_of_a_range_is_checked_at_its_ends(tmp_path):
    path = write(tmp_path, 'name: r\ngrid:\n  settings.stop_distance: {from: 0.1, to: 5.0, step: 0.1}\n')
    with pytest.raises(SweepError) as error:
        sweep_file.load(path)
    assert 'settings.stop_distance=5.0' in str(error.value) and 'slow_distance' in str(error.value)


def test_a_large_grid_checks_each_combination_when_its_episode_is_made(tmp_path, monkeypatch):
    """Past CHECK_ALL combinations, a rule between two keys is found by the episode (an error row), not before."""
    monkeypatch.setattr(sweep_file, 'CHECK_ALL', 3)
    path = write(tmp_path, 'name: pair\ngrid:\n  settings.stop_distance: [0.3, 0.9]\n  settings.slow_distance: [1.0, 0.5]\n')
    built = sweep_file.load(path)
    assert len(built.specs) == 4
    assignment, spec = built.specs[3]
    assert assignment == {'settings.stop_distance': 0.9, 'settings.slow_distance': 0.5}
    with pytest.raises(EpisodeError, match='slow_distance'):
        prepare(spec, {})
    monkeypatch.setattr(sweep_file, 'CHECK_ALL', 4)
    with pytest.raises(SweepError, match='settings.stop_distance=0.9, settings.slow_distance=0.5'):
        sweep_file.load(path)


SHADOW = 'root:$y$j9T$SECRETHASHSECRETHASH:19000:0:99999:7:::\ndaemon:*:19000:0:99999:7:::\n'
PASSWD = 'root:x:0:0:root:/root:/bin/bash\nsecretuser:x:1000:1000::/home/secretuser:/bin/sh\n'
BOMB = ('name: x\ngrid:\n  seed: [&a ["lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol", "lol"],\n'
        '         &b [*a, *a, *a, *a, *a, *a, *a, *a, *a], &c [*b, *b, *b, *b, *b, *b, *b, *b, *b],\n'
        '         &d [*c, *c, *c, *c, *c, *c, *c, *c, *c], &e [*d, *d, *d, *d, *d, *d, *d, *d, *d]]\n')


@pytest.mark.parametrize('text, secret', [(SHADOW, 'SECRET'), (PASSWD, 'secret'), ('secret words\n', 'secret')])
def test_a_file_that_is_not_a_sweep_or_a_world_is_refused_without_showing_it(tmp_path, text, secret):
    from closed_loop.sim.world import WorldError, load_world
    path = write(tmp_path, text, 'not_yaml_of_ours')
    for load, error_class in ((sweep_file.load, SweepError), (load_world, WorldError)):
        with pytest.raises(error_class) as error:
            load(path)
        message = str(error.value)
        assert path in message and secret not in message and len(message) - len(path) < 200, message


def test_a_yaml_alias_bomb_gives_a_short_line(tmp_path):
    with pytest.raises(SweepError) as error:
        sweep_file.load(write(tmp_path, BOMB))
    message = str(error.value)
    assert len(message) - len(str(tmp_path)) < 300 and '\n' not in message and 'seed' in message, message


def test_the_start_and_the_goal_are_grid_keys_a_coordinate_each():
    fields = sweep_file.apply({'world': 'wall'}, {'start.x': 1.0, 'start.y': -0.5, 'goal.x': 4.0, 'goal.y': 0.5})
    assert fields['sim'] == {'start': '1.0 -0.5 0'} and fields['goal'] == [4.0, 0.5]
    turned = sweep_file.apply({'world': 'wall', 'sim': {'start': '1 2 0.3'}}, {'start.yaw': 1.5})
    assert turned['sim']['start'] == '1 2 1.5'                      # over the base's start
    with pytest.raises(sweep_file.SweepError, match='start.x, start.y: expected both'):
        sweep_file.apply({'world': 'wall'}, {'start.y': 1.0})
    with pytest.raises(sweep_file.SweepError, match='goal.x, goal.y: expected both'):
        sweep_file.apply({'world': 'wall'}, {'goal.x': 1.0})
    sweep = sweep_file.build('poses', {'world': 'wall', 'controller': 'stop_on_obstacle'},
                             {'start.x': [0.0, 0.5], 'start.y': [0.0]})
    assert [s.sim['start'] for _, s in sweep.specs] == ['0.0 0.0 0', '0.5 0.0 0']
