"""A sweep's report from one pass over its rows (closed_loop.batch.tally): the same figures as the rows read
whole, in any order, keeping only the failing rows it lists and those it draws."""
import random

from closed_loop.batch import sweep_report
from closed_loop.batch.tally import Tally


def rows_of(count, rng):
    rows = []
    for i in range(count):
        outcome = rng.choice(['stopped', 'stopped', 'collided', 'timed_out', 'error'])
        ran = outcome != 'error'
        rows.append({'index': str(i), 'spec': '{}', 'seed': str(i % 7), 'speed': str(0.1 * (i % 3)),
                     'world': rng.choice(['wall', 'red_box']), 'outcome': outcome,
                     'contacts': str(int(outcome == 'collided')) if ran else '',
                     'min_clearance_m': '%.3f' % rng.uniform(0, 1) if ran else '',
                     'time_s': '%.1f' % rng.uniform(1, 30) if ran else '', 'why': 'w%d' % i})
    return rows


def by_hand(rows, key_names):
    """The summary's figures computed from every row at once."""
    groups = {}
    for row in rows:
        groups.setdefault(tuple(row[k] for k in key_names), []).append(row)
    figures = {}
    for values, members in groups.items():
        ran = [r for r in members if r['outcome'] != 'error']
        figures[values] = (len(members), sum(int(r['contacts']) > 0 for r in ran) / len(ran) if ran else None,
                           min((float(r['min_clearance_m']) for r in ran), default=None),
                           sum(float(r['time_s']) for r in ran) / len(ran) if ran else None)
    return figures


def test_the_tally_of_shuffled_rows_is_the_tally_of_the_rows_read_whole():
    rng = random.Random(3)
    rows = rows_of(3000, rng)
    shuffled = rows[:]
    rng.shuffle(shuffled)
    keys = ['seed', 'speed', 'world']
    tally = Tally.of(shuffled, keys, listed=25, pictured=range(0, 3000, 100))
    expected = by_hand(rows, ['speed', 'world'])
    assert set(tally.groups) == set(expected)
    for values, group in tally.groups.items():
        episodes, rate, least, mean_time = expected[values]
        assert group.episodes == episodes and group.contact_rate() == rate
        assert group.least == least and abs(group.mean_time() - mean_time) < 1e-9
    failing = sorted(int(r['index']) for r in rows if r['outcome'] in ('collided', 'timed_out', 'error'))
    assert tally.failing == len(failing)
    assert [int(r['index']) for r in tally.listed_rows()] == failing[:25]
    assert [int(r['index']) for r in tally.drawn_rows()] == [i for i in range(0, 3000, 100) if i in set(failing)]
    assert sum(tally.outcomes().values()) == tally.rows == 3000
    assert tally.contacts == sum(r['outcome'] == 'collided' for r in rows)
    # Kept whole: the listed and the drawn, not the rest.
    assert len(tally._listed) == 25 and len(tally._drawn) <= 30
    # The summary does not depend on the order the rows came in.
    assert sweep_report.summarize(tally) == sweep_report.summarize(Tally.of(rows, keys))


def test_the_default_plot_takes_the_numeric_keys_and_its_points_merge_the_groups():
    rows = rows_of(600, random.Random(4))
    keys = ['seed', 'speed', 'world']
    tally = Tally.of(rows, keys)
    assert sweep_report.default_plot(tally) == {'x': 'speed', 'lines': None}
    points = tally.plot_points('speed', None)['']
    for x, point in points.items():
        ran = [r for r in rows if r['outcome'] != 'error' and abs(float(r['speed']) - x) < 1e-12]
        assert point.ran == len(ran) and point.least == min(float(r['min_clearance_m']) for r in ran)
    # The sweep's own choice (seed on x, world as lines) is tallied row by row, as it comes.
    chosen = Tally.of(rows, keys, plot={'x': 'seed', 'lines': 'world'})
    lines = chosen.plot_points('seed', 'world')
    assert set(lines) == {'wall', 'red_box'} and set(lines['wall']) == {float(s) for s in range(7)}
    assert sum(p.ran for line in lines.values() for p in line.values()) == sum(r['outcome'] != 'error' for r in rows)
