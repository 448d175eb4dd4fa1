"""The crossing generator (closed_loop.sim.crossing): a walker crosses the robot's way where and how fast its
settings say; settings out of range refused naming the field; an episode in it, by its settings."""
import math

import pytest

from closed_loop.batch.episode import EpisodeSpec, prepare
from closed_loop.sim import crossing, generators


def test_the_walker_crosses_the_line_where_and_when_its_settings_say():
    world = crossing.generate(crossing.CrossingSettings(walker_speed=0.8, crossing_x=4.0, walker_start=2.0))
    (walker,) = [o for o in world['obstacles'] if o['name'] == 'walker']
    assert walker['position'] == [4.0, -2.0]                      # 2 m to the right of the line
    assert walker['motion']['waypoints'][0][0] == 4.0 and walker['motion']['waypoints'][0][1] > 3.0
    assert walker['motion']['speed'] == 0.8                        # across the line at 2 / 0.8 = 2.5 s
    left = crossing.generate(crossing.CrossingSettings(walker_start=-2.0))
    assert [o for o in left['obstacles'] if o['name'] == 'walker'][0]['motion']['waypoints'][0][1] < -3.0
    jittered = {tuple(o['position']) for s in range(5) for o in crossing.generate(
        crossing.CrossingSettings(seed=s, jitter=0.5))['obstacles'] if o['name'] == 'walker'}
    assert len(jittered) == 5 and all(abs(x - 3.0) <= 0.5 for x, _ in jittered)


@pytest.mark.parametrize('field, value, message', [
    ('walker_speed', 0.0, 'walker_speed: expected a number from 0.05 to 5'),
    ('walker_start', 0.3, "walker_start: expected at least 0.75 m off the robot's line"),
    ('crossing_x', math.nan, 'crossing_x: expected a number from 0.8 to 50'),
])
def test_settings_out_of_range_are_refused_naming_the_field(field, value, message):
    with pytest.raises(generators.GeneratorError, match=message):
        generators.settings_from({'method': 'crossing', field: value}, 'closed_loop')


def test_an_episode_names_the_crossing_by_its_settings():
    p = prepare(EpisodeSpec(world={'generator': {'method': 'crossing', 'walker_speed': 1.5, 'crossing_x': 2.5}},
                            controller='avoid_obstacles'), {})
    walker = [o for o in p.world.obstacles if o.name == 'walker'][0]
    assert walker.motion.speed == 1.5 and walker.position[0] == 2.5 and p.goal_world == (7.0, 0.0)
