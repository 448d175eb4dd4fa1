"""Controllers written elsewhere (test/fixtures/fixture_controllers: a rospy node that reads a 360-sample scan
by index the way TurtleBot3's obstacle example does, and a roscpp node), in a package of their own built in a
catkin workspace of its own, as docs/own_controller.md tells a user to: judged by scenario.launch in that
package's rostests, and by a sweep of graph episodes; a robot of one's own (test/fixtures/fixture_robot_description,
built in the same workspace) driven in a rostest and a sweep; and the rows a sweep writes when a controller goes
wrong."""
import concurrent.futures
import glob
import json
import math
import os
import re
import subprocess
import xml.etree.ElementTree as ET

import pytest
import rosbag

from conftest import LOAD, busy, fixture_workspace, graph_leftovers, run_sweep, same_rows

ROSTEST_TIMEOUT_S = 300


@pytest.fixture(scope='module')
def fixture_env(tmp_path_factory):
    return fixture_workspace(tmp_path_factory.mktemp('fixture'))


def rostest(env, home, name):
    """``rostest fixture_controllers NAME`` with its own ROS_HOME; (exit status, output, failure texts)."""
    env = dict(env, ROS_HOME=str(home))
    done = subprocess.run(['rostest', 'fixture_controllers', name], env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True, timeout=ROSTEST_TIMEOUT_S)
    failures = []
    for path in glob.glob(str(home / 'test_results' / '**' / 'rosunit-*.xml'), recursive=True):
        try:
            failures += [f.text or '' for f in ET.parse(path).getroot().iter('failure')]
        except ET.ParseError as error:      # (a test node killed at its time-limit leaves its file empty)
            failures.append('%s: unreadable (%s)' % (path, error))
    return done.returncode, done.stdout, failures


def test_a_package_of_ones_own_passes_its_rostests(fixture_env, tmp_path):
    # (A failing one, and how it reads: test_walkthrough, on the rospy package the docs build.)
    names = ('tb3_obstacle.test', 'goal_seeker.test')
    with concurrent.futures.ThreadPoolExecutor(len(names)) as pool:
        results = dict(zip(names, pool.map(lambda n: rostest(fixture_env, tmp_path / n, n), names)))
    for name in names:
        code, out, failures = results[name]
        assert code == 0 and not failures, '%s: %s\n%s' % (name, failures, out[-3000:])


def test_a_robot_of_ones_own_is_driven_in_a_rostest_and_a_sweep(fixture_env, tmp_path):
    # fixture_robot_description, built in the same workspace: a xacro with includes, args and macros, STL and
    # COLLADA collision meshes, a caster, the LIDAR on a mount. Its profile file is all closed_loop is told.
    sweep = os.path.join(fixture_env['ROS_PACKAGE_PATH'].split(':')[0], 'fixture_controllers', 'sweeps',
                         'my_robot.yaml')
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        course = pool.submit(rostest, fixture_env, tmp_path / 'rostest', 'my_robot.test')
        done, rows = run_sweep(fixture_env, sweep, tmp_path / 'out', '--workers', '1')
        code, out, failures = course.result()
    assert code == 0 and not failures, '%s\n%s' % (failures, out[-3000:])
    assert done.returncode == 0 and sorted(rows) == [0, 1], done.stdout[-3000:]
    for row in rows.values():
        # tb3_obstacle (this workspace's node) and closed_loop's stop_on_obstacle stop short of the wall at x = 2.5,
        # the STL chassis' front 0.18 m ahead of the robot's origin.
        assert row['outcome'] == 'stopped' and row['contacts'] == '0', row
        assert 0.1 < float(row['min_clearance_m']) < 0.5 and abs(float(row['final_y'])) < 0.05, row
    assert graph_leftovers(tmp_path / 'out') == {'processes': [], 'listening': []}


def test_both_controllers_run_as_graph_episodes_in_a_sweep_and_leave_nothing(fixture_env, tmp_path):
    sweep = os.path.join(fixture_env['ROS_PACKAGE_PATH'].split(':')[0], 'fixture_controllers', 'sweeps', 'both.yaml')
    done, rows = run_sweep(fixture_env, sweep, tmp_path / 'out', '--workers', '2')
    assert done.returncode == 0, done.stdout[-3000:]
    assert sorted(rows) == [0, 1, 2, 3]
    by_case = {(r['controller'].split('/')[-1].split('.')[0], r['goal']): r for r in rows.values()}
    for goal in ('[2.0, 1.0]', '[5.0, 0.0]'):
        tb3 = by_case[('tb3_obstacle', goal)]
        assert tb3['outcome'] == 'stopped' and tb3['contacts'] == '0', tb3
        assert 0.1 < float(tb3['min_clearance_m']) < 0.4 and 2.5 < float(tb3['final_x']) < 2.9, tb3
    reached = by_case[('goal_seeker', '[2.0, 1.0]')]
    assert reached['outcome'] == 'reached' and float(reached['goal_error_m']) < 0.4, reached
    behind = by_case[('goal_seeker', '[5.0, 0.0]')]
    assert behind['outcome'] == 'timed_out' and behind['contacts'] == '0' and float(behind['final_x']) < 2.9, behind
    # Only the episode not as meant is drawn, from the track its judge kept in the graph.
    assert os.listdir(tmp_path / 'out' / 'pictures') == ['episode-%05d.png' % int(behind['index'])]
    with open(os.path.join(behind['logs'], 'verdict.json')) as f:
        track = json.load(f)['trajectory']
    assert len(track) > 100 and abs(track[-1][1] - float(behind['final_x'])) < 0.05, track[-1]
    # Its row as a bag: the graph re-run with scenario.launch's recorder, every topic from t = 0.
    bag_path = tmp_path / 'behind.bag'
    again = subprocess.run(['rosrun', 'closed_loop', 'episode_bag', str(tmp_path / 'out'), behind['index'], '--out',
                            str(bag_path)], env=fixture_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           universal_newlines=True, timeout=180)
    assert again.returncode == 0 and 'the re-run reproduces the row' in again.stdout, again.stdout
    check = subprocess.run(['rosbag', 'check', str(bag_path)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           universal_newlines=True, timeout=60)
    assert check.returncode == 0 and 'does not need any migrations' in check.stdout, check.stdout
    with rosbag.Bag(str(bag_path)) as bag:
        topics = bag.get_type_and_topic_info().topics
        clock = [m.clock.to_sec() for _, m, _ in bag.read_messages('/clock')]
        scans = [m.header.stamp.to_sec() for _, m, _ in bag.read_messages('/scan')]
        commands = bag.get_message_count('/cmd_vel')
    assert {'/clock', '/scan', '/odom', '/base_pose_ground_truth', '/tf', '/tf_static', '/cmd_vel', '/world_markers',
            '/scenario_judge/verdict'} <= set(topics), sorted(topics)
    # From the first physics step to the time limit, every scan (5 Hz on the burger), none missing.
    # The clock from the first scan on, with no gap longer than between two scans: the simulator sends every
    # step's clock at real time, and after a stall of its own (a loaded machine) at least the one before a scan.
    gaps = [(a, b) for a, b in zip(clock, clock[1:]) if b - a > 0.201]
    assert clock[0] <= 0.2 and clock[-1] >= 15.0 and clock == sorted(clock) and not gaps, (clock[:3], clock[-3:], gaps)
    assert scans[0] <= 0.2 and all(abs(b - a - 0.2) < 1e-6 for a, b in zip(scans[1:], scans[2:])), scans[:5]
    assert len(scans) >= 75 and commands > 50, (len(scans), commands)
    for row in rows.values():
        assert not row['error'] and row['why'].startswith(row['outcome']), row
        assert os.path.isfile(os.path.join(row['logs'], 'verdict.json')), row['logs']
        assert os.path.isfile(os.path.join(row['logs'], 'graph.log')), row['logs']
        assert math.isfinite(float(row['wall_s']))
    assert graph_leftovers(tmp_path / 'out') == {'processes': [], 'listening': []}
    # In lockstep, the same rows beside a busy process (the rospy node answers each scan; the C++ one on a
    # ros::Timer of simulated time): both controllers to the goal in front of the wall.
    front = tmp_path / 'front.yaml'
    with open(sweep) as f:
        front.write_text(f.read().replace('goal: [[2.0, 1.0], [5.0, 0.0]]', 'goal: [[2.0, 1.0]]'))
    with busy(LOAD):
        done, loaded = run_sweep(fixture_env, front, tmp_path / 'loaded', '--workers', '2')
    idle = {(r['controller'], r['goal']): r for r in rows.values()}
    loaded = {(r['controller'], r['goal']): r for r in loaded.values()}
    same = same_rows({case: idle[case] for case in loaded}, loaded)
    assert done.returncode == 0 and len(loaded) == 2 and same == [], (same, done.stdout[-2000:])
    assert all(row['missed_ticks'] == '0' for row in loaded.values()), loaded


def test_what_goes_wrong_is_a_clear_row_and_the_sweep_goes_on(fixture_env, tmp_path):
    sweep = os.path.join(fixture_env['ROS_PACKAGE_PATH'].split(':')[0], 'fixture_controllers', 'sweeps', 'errors.yaml')
    done, rows = run_sweep(fixture_env, sweep, tmp_path / 'out', '--workers', '2')
    assert done.returncode == 1 and 'episodes: 6, errors: 3' in done.stdout, done.stdout[-3000:]
    by_case = {r['controller']: r for r in rows.values()}
    missing = by_case['{"launch": "fixture_controllers/launch/nope.launch"}']
    assert missing['outcome'] == 'error', missing
    assert missing['error'].startswith('fixture_controllers/launch/nope.launch: the graph did not start: roslaunch: '), missing
    assert "No such file or directory: '" in missing['error'] and "/nope.launch'" in missing['error'], missing
    unstartable = by_case['{"launch": "fixture_controllers/launch/no_such_node.launch"}']
    assert unstartable['outcome'] == 'error', unstartable
    assert 'could not start node fixture_controllers/no_such_node' in unstartable['error'], unstartable
    crash = by_case['{"launch": "fixture_controllers/launch/misbehaving.launch", "args": {"how": "crash"}}']
    assert crash['outcome'] == 'error', crash
    assert 'node misbehaving died (exit code 3)' in crash['error'] and 'crashing on purpose' in crash['error'], crash
    silent = by_case['{"launch": "fixture_controllers/launch/misbehaving.launch", "args": {"how": "silent"}}']
    assert silent['outcome'] == 'stopped' and abs(float(silent['final_x'])) < 0.01, silent
    assert silent['why'].endswith('no command ever reached the base'), silent
    stubborn = by_case['{"launch": "fixture_controllers/launch/misbehaving.launch", "args": {"how": "stubborn"}}']
    assert stubborn['outcome'] == 'stopped' and not stubborn['error'], stubborn
    # It ignored SIGINT and SIGTERM at the end, and was stopped after their grace (3 s, then 2 s).
    with open(os.path.join(stubborn['logs'], 'graph.log')) as f:
        text = f.read()
    assert 'escalating to SIGTERM' in text and 'escalating to SIGKILL' in text, text[-2000:]
    # The node that hangs is waited for once (2 s of its CPU time: it spins), then the scenario goes on without it:
    # the base stops with no command, and the verdict counts the instant missed.
    hung = by_case['{"launch": "fixture_controllers/launch/misbehaving.launch", "args": {"how": "hang"}}']
    assert hung['outcome'] == 'stopped' and not hung['error'] and hung['missed_ticks'] == '1', hung
    assert hung['why'].endswith("; 1 instant missed (a node busy past the simulator's lockstep_timeout)"), hung
    assert 1.0 < float(hung['time_s']) < 5.0 and 0.1 < float(hung['final_x']) < 1.0, hung
    # The simulator's warning names the node and the rule (it computed for the timeout), not the others busy then.
    with open(os.path.join(hung['logs'], 'simulator.log')) as f:
        text = f.read()
    assert re.search(r'lockstep: 1 instant missed \(the last: misbehaving \(pid \d+\) computing for over 2 s of CPU '
                     r'time\)', text), text[-2000:]
    assert graph_leftovers(tmp_path / 'out') == {'processes': [], 'listening': []}
