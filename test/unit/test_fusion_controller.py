"""The fusion controller's core in episodes (closed_loop.control.fusion_navigator through closed_loop.batch.episode): it
waits for a walker and goes round what is static, judged on ground truth."""
import pytest

from closed_loop.controllers import controller_class
from closed_loop.batch.episode import EpisodeSpec, prepare, run_episode

WALKER_PATH_X = 3.0           # worlds/person_crossing.yaml: the walker's line, its radius 0.25 m
FRONT_M = 0.15                # the package's robot: base_footprint to the front of the footprint


def modes(result):
    return [row[7] for row in result.trajectory]


def runs(world, **fields):
    return run_episode(EpisodeSpec(world=world, controller='fusion_controller', time_limit_s=40.0,
                                   keep_trajectory=True, **fields))


@pytest.mark.parametrize('camera', [True, False])
def test_it_waits_for_the_walker_before_its_path_then_goes_on_to_the_goal_without_a_detour(camera):
    result = runs('person_crossing', sim={'camera': camera})
    seen = modes(result)
    assert result.outcome == 'reached' and result.contacts == 0, result
    assert 'WAITING' in seen
    first, last = seen.index('WAITING'), len(seen) - 1 - seen[::-1].index('WAITING')
    rows = result.trajectory
    assert rows[first][1] + FRONT_M < WALKER_PATH_X - 0.25            # stopped short of the walker's line
    assert all(abs(r[4]) < 0.05 for r in rows[first + 10:last])       # at rest while it waits
    assert rows[last][0] < 8.0                                        # and not for long: it crosses at 3 s
    assert max(abs(r[2]) for r in rows) < 0.1                         # no detour


def test_it_goes_round_a_static_box_without_waiting():
    result = runs('obstacle_left')
    assert result.outcome == 'reached' and result.contacts == 0
    assert 'WAITING' not in modes(result) and 'AVOIDING' in modes(result)


def test_it_waits_for_the_walker_and_goes_round_the_wall():
    result = runs('person_and_wall')
    seen = modes(result)
    assert result.outcome == 'reached' and result.contacts == 0
    assert 'WAITING' in seen and 'AVOIDING' in seen[seen.index('WAITING'):]
    assert max(abs(r[2]) for r in result.trajectory) > 0.6           # round the 1.2 m wall


def test_its_settings_are_the_nodes_and_unknown_ones_are_refused():
    cls = controller_class('fusion_controller')
    assert cls.uses_camera
    prepared = prepare(EpisodeSpec(world='person_crossing', controller='fusion_controller',
                                   settings={'hold_s': 2.0, 'moving_speed': 0.5}))
    assert [s.hold_s for s in prepared.extra_settings if hasattr(s, 'hold_s')] == [2.0]
    with pytest.raises(ValueError, match='settings.hold: not a parameter of fusion_controller'):
        prepare(EpisodeSpec(world='person_crossing', controller='fusion_controller', settings={'hold': 2.0}))
