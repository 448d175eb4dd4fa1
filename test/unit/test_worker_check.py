"""What a worker is checked for (closed_loop.batch.worker_check): this package's version and source, the packages
that decide an episode, and the launch files a sweep names in packages; what differs, named."""
import os

import pytest

from closed_loop.batch import worker_check
from closed_loop.batch.episode import EpisodeSpec


@pytest.mark.skipif('CMAKE_PREFIX_PATH' not in os.environ,
                    reason='no catkin workspace in the environment (make compat runs without ROS)')
def test_the_fingerprint_names_the_source_the_deciding_versions_and_the_packages_found():
    mine = worker_check.fingerprint(['closed_loop/launch/sim.launch', 'closed_loop/launch/nope.launch',
                                     'no_such_package_here/x.launch'])
    assert mine['closed_loop'].startswith('0.') and '(source ' in mine['closed_loop']
    assert set(worker_check.DECIDING) <= set(mine) and all(mine[k] != 'none' for k in worker_check.DECIDING)
    assert mine['launch file closed_loop/launch/sim.launch'] == 'found'
    assert mine['launch file closed_loop/launch/nope.launch'] == 'not found'
    assert mine['launch file no_such_package_here/x.launch'] == 'not found (no package no_such_package_here)'
    assert worker_check.fingerprint() == {k: v for k, v in mine.items() if not k.startswith('launch file')}


def test_a_worker_that_differs_is_told_what_and_one_that_does_not_runs():
    mine = worker_check.fingerprint()
    assert worker_check.matches(None) is None and worker_check.matches(mine) is None
    other = dict(mine, numba='0.1.0', closed_loop='0.1.0 (source 000000000000)')
    said = worker_check.matches(other)
    assert 'numba %s where this client has 0.1.0' % mine['numba'] in said
    assert 'closed_loop %s where this client has 0.1.0 (source 000000000000)' % mine['closed_loop'] in said
    needs = dict(mine, **{'launch file my_pkg/launch/a.launch': 'found'})
    assert worker_check.matches(needs) == ('launch file my_pkg/launch/a.launch not found (no package my_pkg) where '
                                           'this client has found')


def test_the_launch_files_a_sweep_needs_are_those_its_graph_controllers_name_in_packages():
    specs = [EpisodeSpec(controller={'launch': 'my_pkg/launch/a.launch'}), EpisodeSpec(controller='stop_on_obstacle'),
             EpisodeSpec(controller={'node': 'avoid_obstacles'}), EpisodeSpec(controller={'launch': '/abs/b.launch'}),
             EpisodeSpec(controller={'launch': 'other_pkg/b.launch'}),
             EpisodeSpec(controller={'launch': 'ws_pkg/c.launch', 'workspace': '/ws'})]
    assert worker_check.graph_launches(specs) == ('my_pkg/launch/a.launch', 'other_pkg/b.launch')
