"""shrink (closed_loop.batch.shrink): delta debugging finds the one obstacle a failure needs among 300, the start
moves nearer the failure, the time limit and the settings shrink while it fails the same way, and the rostest,
world and picture come out."""
import json
import math
import xml.etree.ElementTree as ET

import numpy
import pytest
import yaml

from closed_loop.batch import shrink
from closed_loop.batch.episode import EpisodeSpec, run_episode


def test_ddmin_keeps_what_the_failure_needs_and_nothing_else():
    needed = {13, 201, 202}
    calls = []

    def fails(subset):
        calls.append(len(subset))
        return needed <= set(subset)
    assert sorted(shrink.ddmin(list(range(300)), fails)) == [13, 201, 202]
    assert len(calls) < 300                                  # far fewer tries than one per item
    assert shrink.ddmin([7], lambda s: True) == [7]


def crowded_world(path):
    """299 posts off the robot's way (behind it and to the sides), and one 3 m ahead of it."""
    rng = numpy.random.default_rng(4)
    posts = []
    while len(posts) < 299:
        x, y = float(rng.uniform(-8, 8)), float(rng.uniform(-8, 8))
        if abs(y) > 1.5 or x < -1.5:
            posts.append({'name': 'post_%d' % len(posts), 'type': 'cylinder', 'position': [x, y], 'radius': 0.1,
                          'height': 0.5})
    posts.insert(150, {'name': 'ahead', 'type': 'cylinder', 'position': [3.0, 0.0], 'radius': 0.15, 'height': 0.5})
    path.write_text(yaml.safe_dump({'name': 'crowded', 'robot': {'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}},
                                    'obstacles': posts}))
    return str(path)


def test_a_collision_among_300_obstacles_shrinks_to_the_one_it_needs(tmp_path, capsys):
    # stop_on_obstacle told to stop only 0.2 m short, slowing from 0.234567 m: at 1 m/s it runs into the post.
    spec = EpisodeSpec(world=crowded_world(tmp_path / 'crowded.yaml'), controller='stop_on_obstacle',
                       settings={'cruise_speed': 1.0, 'stop_distance': 0.2, 'slow_distance': 0.234567},
                       time_limit_s=30.0)
    assert run_episode(spec).outcome == 'collided'
    spec_file = tmp_path / 'episode.json'
    spec_file.write_text(json.dumps(spec.to_dict()))
    out = tmp_path / 'shrunk'
    assert shrink.main(['--spec', str(spec_file), '--output', str(out)]) == 0
    world = yaml.safe_load((out / 'world.yaml').read_text())
    assert [o['name'] for o in world['obstacles']] == ['ahead']
    small = EpisodeSpec.from_dict(json.loads((out / 'episode.json').read_text()))
    assert small.time_limit_s <= 5.0 and small.settings['slow_distance'] == pytest.approx(0.23)
    x, y, _ = (float(v) for v in small.sim['start'].split())    # it starts nearer the post, where it still hits it
    assert 0.5 < x < 2.7 and abs(y) < 0.01
    again = run_episode(small)
    assert again.outcome == 'collided' and again.time_s < 3.0    # still fails the same way, sooner
    test = ET.parse(str(out / 'regression.test')).getroot()
    assert test.find('include').get('file') == '$(find closed_loop)/launch/scenario.launch'
    args = {a.get('name'): a.get('value') for a in test.find('include').findall('arg')}
    assert args['world'] == '$(dirname)/world.yaml' and args['controller_type'] == 'stop_on_obstacle'
    assert {p.get('name'): p.get('value') for p in test.findall('param')}['/controller/stop_distance'] == '0.2'
    assert args['start'] == small.sim['start']
    assert (out / 'picture.png').stat().st_size > 10000
    assert 'shrink: 1 obstacles (of 300)' in capsys.readouterr().out


def test_an_episode_that_goes_as_meant_is_not_shrunk(tmp_path, capsys):
    spec_file = tmp_path / 'fine.json'
    spec_file.write_text(json.dumps(EpisodeSpec(world='wall', controller='stop_on_obstacle').to_dict()))
    assert shrink.main(['--spec', str(spec_file), '--output', str(tmp_path / 'out')]) == 2
    assert 'the episode went as meant' in capsys.readouterr().err
