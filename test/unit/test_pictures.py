"""An episode's picture, its track, a sweep's page and the report choices of a sweep file."""
import dataclasses
import io
import math
import types

import pytest
from matplotlib import image

from closed_loop.batch import pictures, report_page, rerun, sweep_file
from closed_loop.batch.episode import EpisodeSpec, run_episode
from closed_loop.batch.judge import track_from_dict
from closed_loop.batch.tally import Tally
from closed_loop.sim import shapes
from closed_loop.sim.world import load_world, resolve_world
from closed_loop.sim.profiles import PACKAGE_ROOT

CRASH = dict(world='wall', settings={'stop_distance': 0.05, 'slow_distance': 0.1}, time_limit_s=12.0,
             end_on_contact=True, keep_trajectory=True)


@pytest.fixture(scope='module')
def crashed():
    spec = EpisodeSpec(**CRASH)
    return spec, run_episode(spec)


def test_what_is_a_failure():
    assert pictures.is_failure('collided', 1) and pictures.is_failure('timed_out', 0)
    assert pictures.is_failure('error', '') and pictures.is_failure('failed', '0')
    assert pictures.is_failure('stopped', '2')                  # a stop controller that touched: not as meant
    assert not pictures.is_failure('stopped', '0') and not pictures.is_failure('reached', 0)
    assert pictures.wanted('all', 'reached', 0) and not pictures.wanted('none', 'collided', 1)


def test_the_track_has_the_path_clearance_and_each_contact_with_its_obstacle(crashed):
    _, result = crashed
    assert result.outcome == 'collided' and len(result.trajectory[0]) == 9
    assert [r[0] for r in result.trajectory] == sorted(r[0] for r in result.trajectory)
    assert min(r[8] for r in result.trajectory) == pytest.approx(result.min_clearance_m, abs=0.02)
    [(t, x, y, _yaw, names)] = result.contact_log
    assert names == ['front_wall'] and t == pytest.approx(result.time_s) and 2.7 < x < 3.0


def test_a_track_survives_json_with_a_clearance_beyond_the_lookout():
    from closed_loop.batch.judge import Judge, JudgeSettings
    judge = Judge(JudgeSettings(), keep_track=True)
    judge.observe(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    judge.on_clearance(0.3)
    judge.observe(0.1, 0.1, 0.0, 0.0, 1.0, 0.0, (1.0, 0.0), 'CLEAR')
    judge.on_contact(0.15, 1, ['post'])
    rows, log = track_from_dict(judge.track_dict())
    assert rows[0][8] == math.inf and rows[1] == (0.1, 0.1, 0.0, 0.0, 1.0, 1.0, 0.0, 'CLEAR', 0.3)
    assert log == [(0.15, 0.1, 0.0, 0.0, ['post'])]


def test_outlines_follow_the_shapes():
    world = load_world(resolve_world('obstacle_course', PACKAGE_ROOT + '/worlds'))
    for o in world.obstacles:
        corners = shapes.outline(o)
        assert all(abs(shapes.distance(o, x, y)) < 1e-6 for x, y in corners), o.name
        moved = shapes.outline(o, o.position[0] + 1.0, o.position[1])
        assert moved[0][0] == pytest.approx(corners[0][0] + 1.0)


def test_the_picture_shows_the_contact_in_red(crashed, tmp_path):
    spec, result = crashed
    png = pictures.episode_picture(spec, result, label='episode 7')
    path = tmp_path / 'p.png'
    path.write_bytes(png)
    pixels = image.imread(str(path))[:, :, :3]
    red = (abs(pixels[:, :, 0] - 0xd6 / 255) < 0.05) & (pixels[:, :, 1] < 0.25) & (pixels[:, :, 2] < 0.25)
    assert pixels.shape[1] == 800 and red.sum() > 100
    assert pictures.title(result).startswith('collided after')


def test_a_moving_obstacle_and_a_navigator_without_a_track_still_draw():
    spec = EpisodeSpec(world='obstacle_course', controller='avoid_obstacles', time_limit_s=2.0)
    result = run_episode(spec)          # no trajectory kept: the world, the start and the goal only
    assert pictures.episode_picture(spec, result)[:8] == b'\x89PNG\r\n\x1a\n'


def test_the_page_escapes_what_it_shows_and_loads_nothing_from_elsewhere(tmp_path):
    sweep = types.SimpleNamespace(name='page', keys=['seed'], report={'pictures': 'failures'},
                                  text='name: page  # </pre><script>alert(1)</script>')
    rows = [{'index': '0', 'spec': '{"seed": 0}', 'seed': '0', 'outcome': 'collided', 'contacts': '1',
             'why': 'collided <at> the wall', 'time_s': '3.0', 'min_clearance_m': '0.0'},
            {'index': '1', 'spec': '{"seed": 1}', 'seed': '1', 'outcome': 'stopped', 'contacts': '0', 'why': 'ok',
             'time_s': '5.0', 'min_clearance_m': '0.4'}]
    (tmp_path / 'pictures').mkdir()
    (tmp_path / 'pictures' / 'episode-00000.png').write_bytes(b'png')
    page = tmp_path / 'report.html'
    tally = Tally.of(rows, sweep.keys, pictured=[0])
    report_page.write(str(page), sweep, tally, ['seed', 'episodes'], [['0', '1'], ['1', '1']], None,
                      lambda i: str(tmp_path / 'pictures' / ('episode-%05d.png' % int(i))), ['rule: the rule'])
    text = page.read_text()
    assert '<script>alert' not in text and '&lt;at&gt;' in text
    assert 'http://' not in text and 'https://' not in text
    assert text.index('rule: the rule') < text.index('<h2>Summary')
    assert 'src="pictures/episode-00000.png"' in text and 'episode-00001.png' not in text
    assert 'Not as meant (1)' in text
    # The headline, then what did not go as meant, then the tables (a long one folded).
    assert text.index('as meant: 50.0%') < text.index('Not as meant (1)') < text.index('<h2>Summary')
    assert 'contacts: 1' in text and '<details><summary>' not in text.split('<h2>Summary')[1].split('<h2>')[0]
    long_body = [[str(i), '1'] for i in range(300)]
    report_page.write(str(page), sweep, tally, ['seed', 'episodes'], long_body, None,
                      lambda i: str(tmp_path / 'pictures' / ('episode-%05d.png' % int(i))))
    text = page.read_text()
    assert '<details><summary>300 rows (open)</summary>' in text.split('<h2>Summary')[1]


def test_a_graph_rerun_may_end_two_lidar_periods_of_its_top_speed_apart(crashed):
    spec, result = crashed
    top = max(abs(row[4]) for row in result.trajectory)
    assert top > 0.4
    assert rerun.graph_tolerance_m(result, 0.1) == pytest.approx(0.2 * top)
    assert rerun.graph_tolerance_m(dataclasses.replace(result, trajectory=[]), 0.1) == rerun.GRAPH_TOLERANCE_M
    assert rerun.scan_period_s(spec) == pytest.approx(0.1)
    assert rerun.scan_period_s(dataclasses.replace(spec, sim={'scan_rate_hz': 20.0})) == pytest.approx(0.05)


@pytest.mark.parametrize('report, message', [
    ({'pictures': 'some'}, 'report.pictures: expected one of failures, all, none'),
    ({'max_pictures': -1}, 'report.max_pictures: expected a whole number >= 0'),
    ({'colour': 'red'}, 'report: expected {pictures'),
])
def test_a_bad_report_choice_is_refused(report, message):
    with pytest.raises(sweep_file.SweepError, match=message.replace('{', r'\{')):
        sweep_file.build('x', {}, {'seed': [0]}, report=report)


def test_a_rerun_is_held_to_the_row_to_the_bit(crashed):
    _, result = crashed
    row = {'outcome': result.outcome, 'contacts': str(result.contacts), 'final_x': repr(result.final_pose[0]),
           'final_y': repr(result.final_pose[1]), 'final_yaw': repr(result.final_pose[2])}
    assert rerun.differences(row, result) == []
    row['final_x'] = repr(result.final_pose[0] + 1e-12)
    assert 'final pose' in rerun.differences(row, result)[0]
    assert rerun.differences(row, result, graph_tolerance_m=0.03) == []
    row['final_x'] = repr(result.final_pose[0] + 0.05)
    assert 'more than the 0.030 m' in rerun.differences(row, result, graph_tolerance_m=0.03)[0]
    assert rerun.differences(row, result, graph_tolerance_m=0.06) == []
    out = io.StringIO()
    assert not rerun.report_differences(3, ['outcome x'], out) and 'did NOT reproduce' in out.getvalue()
