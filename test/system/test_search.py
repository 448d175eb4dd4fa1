"""search on a local Dask cluster: it finds a stop_on_obstacle's collisions (too short a stop distance, fast and
slowing late) within a small budget, writes them as rows with their objective, resumes where it stopped, and
refuses a bad search file in one line before anything runs."""
import csv
import time

from closed_loop.batch import search

SEARCH = """name: stopping_search
base: {world: wall, controller: stop_on_obstacle, time_limit_s: 12, settings: {stop_distance: 0.2}}
space:
  settings.cruise_speed: {from: 0.25, to: 1.0}
  settings.slow_distance: {from: 0.21, to: 1.0}
budget: %d
batch: 4
seed: 1
failure: {outcomes: [collided]}
"""


def rows_of(path):
    with open(path, newline='') as f:
        return list(csv.DictReader(f))


def test_a_search_finds_the_collisions_and_resumes_where_it_stopped(tmp_path, capsys):
    spec = tmp_path / 'search.yaml'
    spec.write_text(SEARCH % 8)
    out = tmp_path / 'out'
    assert search.main([str(spec), '--output', str(out), '--workers', '2']) == 0
    first = rows_of(out / 'rows.csv')
    assert len(first) == 8 and {'objective', 'failing', 'settings.cruise_speed', 'outcome'} <= set(first[0])
    spec.write_text(SEARCH % 24)
    assert search.main([str(spec), '--output', str(out), '--workers', '2', '--resume']) == 0
    rows = rows_of(out / 'rows.csv')
    assert len(rows) == 24 and rows[:8] == first                  # the first eight kept, told to the sampler
    failing = [r for r in rows if r['failing'] == 'True']
    assert failing and all(r['outcome'] == 'collided' and float(r['objective']) == -1.0 for r in failing)
    # Every failure fast and slowing late; every other one's objective its least clearance (none within 0).
    assert all(float(r['settings.cruise_speed']) > 0.5 for r in failing)
    assert all(0.0 <= float(r['objective']) <= 1.0 for r in rows if r['failing'] == 'False')
    assert 'search stopping_search: 24 episodes, %d failing' % len(failing) in capsys.readouterr().out


BAD = {'space:\n  settings.cruise_speed: {from: 1.0, to: 0.25}\n': 'space.settings.cruise_speed: expected from < to',
       'space:\n  colour: [red]\n': 'space.colour: expected an episode field',
       'space:\n  seed: {from: 0, to: 9, int: true}\nbudget: 1000000000\n': 'budget: expected a whole number from 1',
       'space:\n  seed: [0]\nsampler: annealing\n': 'sampler: expected one of tpe, cmaes, random'}


def test_a_bad_search_file_is_refused_in_one_line_within_a_second(tmp_path, capsys):
    for body, message in BAD.items():
        spec = tmp_path / 'bad.yaml'
        spec.write_text('name: bad\nbase: {world: wall, controller: stop_on_obstacle}\nbudget: 4\n' + body
                        if 'budget' not in body else 'name: bad\nbase: {world: wall, controller: stop_on_obstacle}\n'
                        + body)
        started = time.monotonic()
        assert search.main([str(spec), '--output', str(tmp_path / 'out')]) == 2, body
        assert time.monotonic() - started < 5.0                  # (a bound that catches a run; refused in far less)
        err = capsys.readouterr().err
        assert message in err and err.count('\n') == 1, (body, err)
    assert not (tmp_path / 'out').exists()
