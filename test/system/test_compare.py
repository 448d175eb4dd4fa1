"""compare: one scenario set for two sides on a local Dask cluster, the episodes paired. A deliberately worse
stop_on_obstacle (it neither slows nor stops before 5 cm) against the shipped one: every pair a regression,
exit 1, the page with the pairs and A beside B, and with the gate raised, exit 0; a bad change: refused. (A side
against itself, no regression: test/unit/test_compare_pairs.py.)"""
import csv
import json
import os
import re
import subprocess
import sys

from closed_loop.batch import compare

SET = """name: stopping
base: {world: wall, controller: stop_on_obstacle, time_limit_s: 15}
grid:
  settings.cruise_speed: [0.3, 0.6, 1.0]
report: {pictures: failures}
"""
WORSE = ['settings.stop_distance=0.05', 'settings.slow_distance=0.06']


def test_a_worse_controller_regresses_every_pair_and_fails_the_gate(tmp_path, capsys):
    spec = tmp_path / 'stopping.yaml'
    spec.write_text(SET)
    out = tmp_path / 'out'
    args = [str(spec), '--output', str(out), '--workers', '1']
    assert compare.main(args + sum((['--b', change] for change in WORSE), [])) == 1
    said = capsys.readouterr().out
    assert '3 pairs: 3 regressions (A as meant, B not), 0 fixes' in said, said
    assert "McNemar's exact test: p = 0.25" in said and 'B regressed: 3 regressions, more than --max-regressions 0' in said
    page = (out / 'compare.html').read_text()
    assert page.index('Pairs that differ (3)') < page.index('Every pair')
    assert page.count('class="pair"') == 3
    for index in range(3):                  # A's picture drawn again, B's from its sweep
        assert (out / 'pairs' / ('episode-%05d-a.png' % index)).stat().st_size > 10000
        assert (out / 'b' / 'pictures' / ('episode-%05d.png' % index)).exists()
    assert (out / 'a' / 'report.html').exists() and (out / 'b' / 'rows.csv').exists()
    # The gate is the user's: three regressions allowed, it holds.
    assert compare.main(args + ['--resume', '--max-regressions', '3'] + sum((['--b', c] for c in WORSE), [])) == 0


BAD = {'settings': "--b settings: expected KEY=VALUE", 'colour=red': '--b colour: expected an episode field',
       'sim.start=[1, 2': '--b sim.start=[1, 2: the value is not YAML'}


def test_a_bad_change_is_refused_in_one_line_before_either_side_runs(tmp_path, capsys):
    spec = tmp_path / 'stopping.yaml'
    spec.write_text(SET)
    for change, message in BAD.items():
        assert compare.main([str(spec), '--output', str(tmp_path / 'out'), '--b', change]) == 2, change
        err = capsys.readouterr().err
        assert message in err and err.count('\n') == 1, err
    assert not os.path.exists(tmp_path / 'out')


def test_the_failures_a_search_found_are_a_set_to_compare_a_fix_on(tmp_path, capsys):
    """compare on a search's folder: its failing episodes, each run as it was (A) and with a fix (B)."""
    from closed_loop.batch import search
    spec = tmp_path / 'search.yaml'
    spec.write_text('name: hunt\nbase: {world: wall, controller: stop_on_obstacle, time_limit_s: 12, '
                    'settings: {stop_distance: 0.2}}\nspace:\n  settings.cruise_speed: {from: 0.25, to: 1.0}\n'
                    '  settings.slow_distance: {from: 0.21, to: 1.0}\nbudget: 12\nseed: 1\n'
                    'failure: {outcomes: [collided]}\n')
    assert search.main([str(spec), '--output', str(tmp_path / 'hunt'), '--workers', '2']) == 0
    found = capsys.readouterr().out
    failing = int(re.search(r'search hunt: 12 episodes, (\d+) failing', found).group(1))
    assert failing > 0, found
    assert compare.main([str(tmp_path / 'hunt'), '--output', str(tmp_path / 'out'), '--workers', '2',
                         '--b', 'settings.stop_distance=0.5', '--b', 'settings.slow_distance=1.0']) == 0
    said = capsys.readouterr().out
    assert '%d pairs: 0 regressions (A as meant, B not), %d fixes' % (failing, failing) in said, said


LAUNCH = """<launch>
  <node pkg="closed_loop" type="stop_on_obstacle" name="stop_on_obstacle" output="screen">
    <param name="cruise_speed" value="0.6"/>
    <param name="stop_distance" value="%s"/>
    <param name="slow_distance" value="%s"/>
  </node>
</launch>
"""
CMAKE = """cmake_minimum_required(VERSION 3.0.2)
project(lane_stop)
find_package(catkin REQUIRED)
catkin_package()
install(DIRECTORY launch DESTINATION ${CATKIN_PACKAGE_SHARE_DESTINATION})
"""
MANIFEST = """<?xml version="1.0"?>
<package format="2">
  <name>lane_stop</name>
  <version>0.1.0</version>
  <description>A stop-on-obstacle launch file, as two branches of it have it.</description>
  <maintainer email="dev@example.com">dev</maintainer>
  <license>BSD</license>
  <buildtool_depend>catkin</buildtool_depend>
  <exec_depend>closed_loop</exec_depend>
</package>
"""


def lane_stop_workspace(root, stop_distance, slow_distance):
    """A catkin workspace of its own with the package lane_stop, built with catkin_make."""
    package = root / 'src' / 'lane_stop'
    (package / 'launch').mkdir(parents=True)
    (package / 'launch' / 'stop.launch').write_text(LAUNCH % (stop_distance, slow_distance))
    (package / 'CMakeLists.txt').write_text(CMAKE)
    (package / 'package.xml').write_text(MANIFEST)
    build = subprocess.run(['catkin_make', '-C', str(root), '-DPYTHON_EXECUTABLE=' + sys.executable],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, timeout=600)
    assert build.returncode == 0, build.stdout[-4000:]
    return str(root)


def test_the_same_launch_file_from_two_workspaces_is_compared(tmp_path, capsys):
    """One launch file, lane_stop/launch/stop.launch, as two workspaces have it (B's stops at 5 cm): the graph episodes of
    each side run the launch file of their own workspace, with this package's simulator and judge."""
    before = lane_stop_workspace(tmp_path / 'ws_main', 0.5, 1.0)
    after = lane_stop_workspace(tmp_path / 'ws_change', 0.05, 0.06)
    spec = tmp_path / 'lane.yaml'
    spec.write_text('name: lane\nbase: {world: wall, time_limit_s: 15, controller: {launch: lane_stop/launch/stop.launch, '
                    'mode_topic: /stop_on_obstacle/mode}}\ngrid:\n  time_limit_s: [15]\n')
    out = tmp_path / 'out'
    assert compare.main([str(spec), '--output', str(out), '--workers', '1', '--a', 'controller.workspace=' + before,
                         '--b', 'controller.workspace=' + after]) == 1
    said = capsys.readouterr().out
    assert '1 pairs: 1 regressions (A as meant, B not), 0 fixes' in said, said
    for side, outcome, workspace in (('a', 'stopped', before), ('b', 'collided', after)):
        with open(str(out / side / 'rows.csv'), newline='') as f:
            row, = csv.DictReader(f)
        assert row['outcome'] == outcome and row['error'] == '', row
        assert workspace in json.loads(row['spec'])['controller']['workspace']
