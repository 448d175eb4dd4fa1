"""A catkin workspace as a graph controller's place (closed_loop.batch.workspace), on the workspace this package
is found through (a real catkin_make's devel space), and refused paths; the spec and the sweep file's key."""
import os

import pytest

from closed_loop.batch import sweep_file, workspace
from closed_loop.batch.spec import EpisodeError, parse_controller

pytestmark = pytest.mark.skipif('CMAKE_PREFIX_PATH' not in os.environ,
                                reason='no catkin workspace in the environment (make compat runs without ROS)')


def built_workspace():
    """The catkin workspace the environment has this package from (its devel space first on CMAKE_PREFIX_PATH)."""
    for prefix in os.environ['CMAKE_PREFIX_PATH'].split(os.pathsep):
        if os.path.isfile(os.path.join(prefix, '.catkin')) and os.path.isfile(os.path.join(prefix, '_setup_util.py')):
            return os.path.dirname(prefix), prefix
    raise AssertionError('no built catkin workspace on CMAKE_PREFIX_PATH: %s' % os.environ['CMAKE_PREFIX_PATH'])


def test_the_workspace_comes_first_behind_this_package_alone():
    root, prefix = built_workspace()
    env = {'CMAKE_PREFIX_PATH': '/elsewhere' + os.pathsep + prefix, 'ROS_PACKAGE_PATH': '/elsewhere/src',
           'PYTHONPATH': '/elsewhere/lib', 'PATH': '/usr/bin', 'LD_LIBRARY_PATH': ''}
    got = workspace.environment(root, env, '/this/package', '/this/package/src')
    assert env['CMAKE_PREFIX_PATH'] == '/elsewhere' + os.pathsep + prefix                     # not changed
    assert got['CMAKE_PREFIX_PATH'].split(os.pathsep) == [prefix, '/elsewhere']              # moved to the front
    with open(os.path.join(prefix, '.catkin')) as f:
        sources = f.read().strip().split(';')
    assert got['ROS_PACKAGE_PATH'].split(os.pathsep) == ['/this/package'] + sources + ['/elsewhere/src']
    python = [p for p in got['PYTHONPATH'].split(os.pathsep)]
    assert python[0] == '/this/package/src' and python[-1] == '/elsewhere/lib' and len(python) == 3
    assert python[1].startswith(os.path.join(prefix, 'lib', 'python')) and os.path.isdir(python[1])
    assert got['LD_LIBRARY_PATH'] == os.path.join(prefix, 'lib')
    assert got['PATH'].split(os.pathsep)[-1] == '/usr/bin'
    # Named by its devel space itself, the same.
    assert workspace.environment(prefix, env, '/this/package', '/this/package/src') == got


def test_a_path_that_is_not_a_built_workspace_is_refused_naming_it(tmp_path):
    with pytest.raises(workspace.WorkspaceError, match='no such folder'):
        workspace.prefix_of(str(tmp_path / 'gone'))
    (tmp_path / 'src').mkdir()
    with pytest.raises(workspace.WorkspaceError, match=r'%s is not a built catkin workspace: no devel/\.catkin'
                       % tmp_path):
        workspace.prefix_of(str(tmp_path))
    (tmp_path / 'devel').mkdir()
    (tmp_path / 'devel' / '.catkin').write_text(str(tmp_path / 'src'))
    with pytest.raises(workspace.WorkspaceError, match="cannot read catkin's setup utility"):
        workspace.environment(str(tmp_path), {}, '/p', '/p/src')


def test_a_controller_names_its_workspace_by_an_absolute_path_to_a_built_one(tmp_path):
    root, _ = built_workspace()
    launch = {'launch': 'my_pkg/my.launch'}
    assert parse_controller(dict(launch, workspace=root), ())['workspace'] == root
    for place, message in (('ws', 'expected the absolute path of a catkin workspace'),
                           (str(tmp_path), 'is not a built catkin workspace'), (3, 'expected the absolute path')):
        with pytest.raises(EpisodeError, match='controller.workspace: .*' + message):
            parse_controller(dict(launch, workspace=place), ())


def test_a_sweep_varies_the_workspace_of_a_graph_controller_only():
    sweep_file.check_key('x.yaml', 'controller.workspace')
    base = {'controller': {'launch': 'my_pkg/my.launch', 'args': {'a': 1}}}
    assert sweep_file.apply(base, {'controller.workspace': '/ws_b'})['controller'] == {
        'launch': 'my_pkg/my.launch', 'args': {'a': 1}, 'workspace': '/ws_b'}
    with pytest.raises(sweep_file.SweepError, match='the base needs controller'):
        sweep_file.apply({'controller': 'stop_on_obstacle'}, {'controller.workspace': '/ws_b'})
