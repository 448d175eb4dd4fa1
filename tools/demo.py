#!/usr/bin/env python3
"""`make demo`: run demo.launch headless, judged by scenario_judge (the judge of every episode and sweep row,
``closed_loop.batch.judge``), show a live status line, then print the judge's verdict: what the robot did, on the
simulator's ground truth.

Usage (inside ``source env.sh``): python3 tools/demo.py [--world wall] [--controller stop_on_obstacle]
                                                        [--seconds 30] [launch args, e.g. gui:=true]
A controller that takes a goal (``avoid_obstacles``, ``fusion_controller``) is sent to the world's goal (``goal:``
in the world file, else 10 m ahead); its run ends when it has reached it or given up, the others' when the robot
has come to rest; every run at ``--seconds`` of simulated time at the latest.
"""
import argparse
import json
import math
import os
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop import launcher, netenv  # noqa: E402
from closed_loop.controllers import ControllerError, controller_class  # noqa: E402
from closed_loop.sim import world as world_mod  # noqa: E402
from closed_loop.sim import quiet  # noqa: E402

STATUS_PERIOD_S = 1.0
MASTER_WAIT_S = 30.0
#: Wall time beyond the run's simulated seconds that the judge's verdict is waited for (a start-up, a slow machine).
VERDICT_SLACK_S = 30.0
#: With no goal in the world, a controller that takes one goes this far ahead (its own default).
GOAL_AHEAD_M = 10.0


class Monitor:
    """Subscribes to what the status line shows, the controller's mode changes, and the judge's verdict."""

    def __init__(self, controller):
        import rospy
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from std_msgs.msg import Bool, Float32, String, UInt32
        self.lock = threading.Lock()
        self.truth = None
        self.cmd = None
        self.zone = None
        self.distance = None
        self.red = None
        self.contacts = 0
        self.zone_changes = []
        self.verdict = None
        rospy.Subscriber('/base_pose_ground_truth', Odometry, lambda m: self._set('truth', m), queue_size=10)
        rospy.Subscriber('/cmd_vel', Twist, lambda m: self._set('cmd', m.linear.x), queue_size=10)
        rospy.Subscriber('/obstacle_distance', Float32, lambda m: self._set('distance', m.data), queue_size=10)
        rospy.Subscriber('/red_detected', Bool, lambda m: self._set('red', m.data), queue_size=10)
        rospy.Subscriber('/contact_count', UInt32, lambda m: self._set('contacts', m.data), queue_size=10)
        # Every controller publishes its mode on ~mode (the controllers' shared contract).
        rospy.Subscriber('/%s/mode' % controller, String, self._on_zone, queue_size=10)
        rospy.Subscriber('/scenario_judge/verdict', String, lambda m: self._set('verdict', json.loads(m.data)),
                         queue_size=1)

    def _set(self, name, value):
        with self.lock:
            setattr(self, name, value)

    def _on_zone(self, msg):
        with self.lock:
            if msg.data != self.zone and self.truth is not None:
                self.zone_changes.append((self.truth.header.stamp.to_sec(), msg.data,
                                          self.truth.pose.pose.position.x, self.truth.pose.pose.position.y))
            self.zone = msg.data


def goal_args(world, takes_goal):
    """(the launch args that send a controller that takes a goal to the world's: its own in odom, the judge's in
    the world frame; that goal in the world frame), or ([], None) for one that takes none."""
    if not takes_goal:
        return [], None
    start = world.robot_start
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    if world.goal is None:
        goal = (start.x + GOAL_AHEAD_M * c, start.y + GOAL_AHEAD_M * s)
        args = []
    else:
        goal = world.goal
        dx, dy = goal[0] - start.x, goal[1] - start.y
        args = ['goal_x:=%.3f' % (c * dx + s * dy), 'goal_y:=%.3f' % (-s * dx + c * dy)]
    return args + ['judge_goal_x:=%.3f' % goal[0], 'judge_goal_y:=%.3f' % goal[1], 'end_at_rest:=false'], goal


def report_early_end(launch, log_path):
    """Say that the launch ended before the run did, and why; the demo's exit status (1)."""
    print('\n' + launcher.early_end_report('demo', launch, log_path))
    return 1


def fmt(value, unit='', spec='%.2f'):
    if value is None:
        return '-'
    return (spec % value) + unit


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--world', default='wall')
    parser.add_argument('--controller', default='stop_on_obstacle')
    parser.add_argument('--robot', default='closed_loop', help='robot profile (config/robots/), or a profile file')
    parser.add_argument('--seconds', type=float, default=None,
                        help='simulated seconds the run may last (default 30 s; 60 s for a controller that takes a '
                             'goal)')
    parser.add_argument('--verbose', action='store_true', help="let pybullet's own output into the log")
    parser.add_argument('launch_args', nargs='*', help='extra roslaunch args (name:=value)')
    args = parser.parse_args()
    quiet.set_verbose(args.verbose)
    try:
        takes_goal = controller_class(args.controller).uses_goal
    except ControllerError as error:
        print('demo: %s' % error)
        return 2
    if args.seconds is None:
        args.seconds = 60.0 if takes_goal else 30.0
    netenv.apply_loopback_defaults(os.environ)

    world = world_mod.load_world(world_mod.resolve_world(args.world, os.path.join(ROOT, 'worlds')))
    log_path = os.path.join(ROOT, 'test_output', 'demo.log')
    verdict_path = os.path.join(ROOT, 'test_output', 'demo_verdict.json')
    os.makedirs(os.path.dirname(log_path), exist_ok=True)
    if os.path.exists(verdict_path):
        os.remove(verdict_path)
    given = {a.split(':=', 1)[0] for a in args.launch_args}
    cmd = ['roslaunch', 'closed_loop', 'demo.launch', 'world:=' + args.world, 'robot:=' + args.robot,
           'controller:=' + args.controller, 'verdict_file:=' + verdict_path, 'time_limit:=%g' % args.seconds]
    to_goal, goal = goal_args(world, takes_goal)
    cmd += [a for a in to_goal if a.split(':=', 1)[0] not in given] + args.launch_args
    problem = launcher.master_problem(os.environ['ROS_MASTER_URI'])
    if problem is not None:
        print('demo: %s; nothing started' % problem)
        return 1
    print('demo: %s   (full log: %s)' % (' '.join(cmd), log_path), flush=True)
    log = open(log_path, 'w')
    launch = launcher.Launch(cmd[1:], log)
    try:
        import rospy
        from closed_loop.nodes.common import join_launch
        if not join_launch('demo_monitor', launch, MASTER_WAIT_S):
            if launch.poll() is not None:
                return report_early_end(launch, log_path)
            print('demo: roslaunch did not bring up a master; see %s' % log_path)
            return 1
        try:
            mon = Monitor(args.controller)
        except rospy.ROSException:      # its subscriptions closed: the launch ended meanwhile
            if launch.poll() is None:
                raise
            return report_early_end(launch, log_path)
        started = time.monotonic()
        next_status = started
        while True:
            if launch.poll() is not None:
                return report_early_end(launch, log_path)
            now = time.monotonic()
            with mon.lock:
                truth, verdict = mon.truth, mon.verdict
                if now >= next_status and truth is not None:
                    next_status += STATUS_PERIOD_S
                    p = truth.pose.pose.position
                    print('  t=%5.1fs  x=%5.2f y=%5.2f m  speed=%4.2f m/s  cmd=%s  %s  nearest=%s  red=%s  contacts=%d'
                          % (truth.header.stamp.to_sec(), p.x, p.y, math.hypot(truth.twist.twist.linear.x,
                                                                                truth.twist.twist.linear.y),
                             fmt(mon.cmd, ' m/s'), mon.zone or '-', fmt(mon.distance, ' m'),
                             '-' if mon.red is None else ('yes' if mon.red else 'no'), mon.contacts),
                          flush=True)
            if verdict is not None:
                break
            if now - started > args.seconds + VERDICT_SLACK_S:
                print('demo: no verdict from the judge within %.0f s of wall time; see %s' % (now - started,
                                                                                            log_path))
                return 1
            time.sleep(0.05)
        with mon.lock:
            changes = list(mon.zone_changes)
        print('\nWhat the robot did (judged as every episode is, on ground truth; world "%s", robot %s, controller '
              '%s):' % (world.name, args.robot, args.controller))
        for t, zone, x, y in changes:
            print('  t=%5.1fs  %-12s at x=%.2f y=%.2f m' % (t, zone, x, y))
        print('  %s' % verdict['why'])
        start = world.robot_start
        final = verdict['final_pose']
        print('  drove %.2f m: from (%.2f, %.2f) to (%.2f, %.2f)' % (verdict['path_m'], start.x, start.y, final[0],
                                                                   final[1]))
        clearance = verdict['min_clearance_m']
        print('  least clearance of the footprint to any obstacle: %s' % (
            '%.3f m' % clearance if clearance is not None and math.isfinite(clearance) else 'none in sight'))
        if goal is not None and verdict.get('goal_error_m') is not None:
            print('  goal (%.2f, %.2f): %s (%.2f m from it)' % (goal + (
                'reached' if verdict['outcome'] == 'reached' else 'not reached (%s)' % verdict['outcome'],
                verdict['goal_error_m'])))
        print('  contacts: %s' % ('none' if verdict['contacts'] == 0 else '%d (the robot touched something)'
                                  % verdict['contacts']))
        return 0 if verdict['contacts'] == 0 else 1
    finally:
        launch.end()
        log.close()


if __name__ == '__main__':
    sys.exit(main())
