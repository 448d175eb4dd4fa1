#!/usr/bin/env python3
"""`make demo`: run demo.launch headless for a bounded time, show a live status line, then summarise
what the robot did, from the simulator's ground truth.

Usage (inside ``source env.sh``): python3 tools/demo.py [--world wall] [--controller stop_on_obstacle]
                                                        [--seconds 30] [launch args, e.g. gui:=true]
With ``--controller avoid_obstacles`` (or ``fusion_controller``) it runs avoid.launch (fusion.launch) toward the
world's goal (``goal:`` in the world file, else 10 m ahead) and says whether and when it was reached.
"""
import argparse
import dataclasses
import math
import os
import sys
import threading
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop import launcher, netenv, robot_model  # noqa: E402
from closed_loop.sim import obstacles, shapes, world as world_mod  # noqa: E402
from closed_loop.geometry import quaternion_yaw  # noqa: E402
from closed_loop.sim import quiet  # noqa: E402

STATUS_PERIOD_S = 1.0
AT_REST_MPS = 0.01
# Once the robot has moved and then stayed at rest this long, the demo has shown what it came for.
REST_TO_FINISH_S = 2.0
MASTER_WAIT_S = 30.0
CLEARANCE_PERIOD_S = 0.1
# The controllers that take a goal, and their launch files; their demo ends when they have reached it or given up.
NAVIGATORS = {'avoid_obstacles': 'avoid.launch', 'fusion_controller': 'fusion.launch'}
NAVIGATOR_DONE = ('REACHED', 'FAILED')


def clearance_to_obstacles(world, x, y):
    """Smallest ground-plane distance (m) from point (x, y) to any obstacle's footprint, and its name."""
    return min(((shapes.distance(ob, x, y), ob.name) for ob in world.obstacles), default=(math.inf, None))


def footprint_clearance(world, outline_xy, x, y, yaw, t_s):
    """Least distance (m) between the robot's footprint outline (points in its frame) at pose (x, y, yaw)
    in the world and any obstacle where it is at time ``t_s``, and that obstacle's name."""
    c, s = math.cos(yaw), math.sin(yaw)
    points = [(x + c * px - s * py, y + s * px + c * py) for px, py in outline_xy]
    best = (math.inf, None)
    for ob in world.obstacles:
        if ob.motion is not None:
            ox, oy = obstacles.moving_obstacle_xy(ob, max(t_s, 0.0))
            ob = dataclasses.replace(ob, position=(ox, oy, ob.position[2]))
        best = min(best, min(((shapes.distance(ob, px, py), ob.name) for px, py in points)))
    return best


def footprint_outline(footprint, step_m=0.05):
    """Points at most ``step_m`` apart along the footprint rectangle's edges, in the robot's frame."""
    x0, x1, y0, y1 = footprint.x_min, footprint.x_max, footprint.y_min, footprint.y_max
    nx, ny = max(1, int(math.ceil((x1 - x0) / step_m))), max(1, int(math.ceil((y1 - y0) / step_m)))
    xs = [x0 + (x1 - x0) * i / nx for i in range(nx + 1)]
    ys = [y0 + (y1 - y0) * i / ny for i in range(ny + 1)]
    return [(px, y0) for px in xs] + [(px, y1) for px in xs] + [(x0, py) for py in ys] + [(x1, py) for py in ys]


class Monitor:
    """Subscribes to what the demo shows and keeps the latest values."""

    def __init__(self, controller, world=None, outline_xy=None):
        import rospy
        from geometry_msgs.msg import PoseStamped, Twist
        from nav_msgs.msg import Odometry
        from std_msgs.msg import Bool, Float32, String, UInt32
        self.lock = threading.Lock()
        self.truth = None
        self.cmd = None
        self.zone = None
        self.distance = None
        self.red = None
        self.contacts = 0
        self.moved = False
        self.rest_since = None
        self.path_m = 0.0
        self.last_xy = None
        self.zone_changes = []
        # The closest approach of the footprint to any obstacle over the run (ground truth), checked at
        # CLEARANCE_PERIOD_S of simulated time.
        self.world, self.outline_xy = world, outline_xy
        self.closest = (math.inf, None, None)     # (m, obstacle, t)
        self._clearance_t = -math.inf
        self.goal = None                            # the navigator's goal (odom), from its ~goal
        self.moved_t = None                         # when the robot first moved (simulated s)
        rospy.Subscriber('/%s/goal' % controller, PoseStamped,
                         lambda m: self._set('goal', (m.pose.position.x, m.pose.position.y)), queue_size=1)
        rospy.Subscriber('/base_pose_ground_truth', Odometry, self._on_truth, queue_size=10)
        rospy.Subscriber('/cmd_vel', Twist, lambda m: self._set('cmd', m.linear.x), queue_size=10)
        rospy.Subscriber('/obstacle_distance', Float32, lambda m: self._set('distance', m.data), queue_size=10)
        rospy.Subscriber('/red_detected', Bool, lambda m: self._set('red', m.data), queue_size=10)
        rospy.Subscriber('/contact_count', UInt32, lambda m: self._set('contacts', m.data), queue_size=10)
        # Every controller publishes its mode on ~mode (the controllers' shared contract).
        rospy.Subscriber('/%s/mode' % controller, String, self._on_zone, queue_size=10)

    def _set(self, name, value):
        with self.lock:
            setattr(self, name, value)

    def _on_zone(self, msg):
        with self.lock:
            if msg.data != self.zone and self.truth is not None:
                self.zone_changes.append((self.truth.header.stamp.to_sec(), msg.data,
                                          self.truth.pose.pose.position.x, self.truth.pose.pose.position.y))
            self.zone = msg.data

    def _on_truth(self, msg):
        with self.lock:
            self.truth = msg
            p = msg.pose.pose.position
            if self.last_xy is not None:
                self.path_m += math.hypot(p.x - self.last_xy[0], p.y - self.last_xy[1])
            self.last_xy = (p.x, p.y)
            t = msg.header.stamp.to_sec()
            if self.outline_xy is not None and t - self._clearance_t >= CLEARANCE_PERIOD_S:
                self._clearance_t = t
                q = msg.pose.pose.orientation
                clearance, name = footprint_clearance(self.world, self.outline_xy, p.x, p.y,
                                                      quaternion_yaw((q.x, q.y, q.z, q.w)), t)
                if clearance < self.closest[0]:
                    self.closest = (clearance, name, t)
            speed = math.hypot(msg.twist.twist.linear.x, msg.twist.twist.linear.y)
            if speed > AT_REST_MPS * 5:
                if not self.moved:
                    self.moved_t = t
                self.moved = True
                self.rest_since = None
            elif self.rest_since is None:
                self.rest_since = time.monotonic()


def live_robot_model():
    """The robot as the running graph has it: robot_description and the simulator's frame names."""
    import rospy
    from closed_loop.settings import from_params
    from closed_loop.sim.simulation import SimSettings
    settings = from_params(SimSettings, lambda name, default: rospy.get_param('/sim/' + name[1:], default))
    return robot_model.load_robot_model(rospy.get_param('/robot_description'), settings.names)


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
    parser.add_argument('--robot', default='closed_loop', help='robot profile (config/robots/)')
    parser.add_argument('--seconds', type=float, default=None,
                        help='wall-clock bound of the run (default 30 s; 60 s with the navigator)')
    parser.add_argument('--verbose', action='store_true', help="let pybullet's own output into the log")
    parser.add_argument('launch_args', nargs='*', help='extra roslaunch args (name:=value)')
    args = parser.parse_args()
    quiet.set_verbose(args.verbose)
    if args.seconds is None:
        args.seconds = 60.0 if args.controller in NAVIGATORS else 30.0
    netenv.apply_loopback_defaults(os.environ)

    world = world_mod.load_world(world_mod.resolve_world(args.world, os.path.join(ROOT, 'worlds')))
    log_path = os.path.join(ROOT, 'test_output', 'demo.log')
    os.makedirs(os.path.dirname(log_path), exist_ok=True)
    cmd = ['roslaunch', 'closed_loop', 'demo.launch', 'world:=' + args.world, 'robot:=' + args.robot,
           'controller:=' + args.controller] + args.launch_args
    if args.controller in NAVIGATORS:
        # The navigator's own launch file, with the world's goal (brought into odom) unless one is given.
        cmd = ['roslaunch', 'closed_loop', NAVIGATORS[args.controller], 'world:=' + args.world,
               'robot:=' + args.robot]
        if world.goal is not None and not any(a.startswith(('goal_x:=', 'goal_y:=')) for a in args.launch_args):
            start = world.robot_start
            dx, dy = world.goal[0] - start.x, world.goal[1] - start.y
            c, s = math.cos(start.yaw), math.sin(start.yaw)
            cmd += ['goal_x:=%.3f' % (c * dx + s * dy), 'goal_y:=%.3f' % (-s * dx + c * dy)]
        cmd += args.launch_args
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
        outline_xy = None
        try:
            description = rospy.get_param('/robot_description', None)
            deadline = time.monotonic() + MASTER_WAIT_S
            while description is None and launch.poll() is None and time.monotonic() < deadline:
                time.sleep(0.2)
                description = rospy.get_param('/robot_description', None)
            if description is not None:
                outline_xy = footprint_outline(robot_model.footprint(description))
        except robot_model.RobotModelError as error:
            print('demo: no footprint for the clearance figure: %s' % error)
        except OSError:
            pass    # the master went with the launch, which the loop below reports
        try:
            mon = Monitor(args.controller, world, outline_xy)
        except rospy.ROSException:      # its subscriptions closed: the launch ended meanwhile
            if launch.poll() is None:
                raise
            return report_early_end(launch, log_path)
        started = time.monotonic()
        next_status = started
        while time.monotonic() - started < args.seconds:
            if launch.poll() is not None:
                return report_early_end(launch, log_path)
            now = time.monotonic()
            with mon.lock:
                truth, done = mon.truth, (mon.moved and mon.rest_since is not None
                                          and now - mon.rest_since > REST_TO_FINISH_S
                                          and (args.controller not in NAVIGATORS or mon.zone in NAVIGATOR_DONE))
                if now >= next_status and truth is not None:
                    next_status += STATUS_PERIOD_S
                    p = truth.pose.pose.position
                    print('  t=%5.1fs  x=%5.2f y=%5.2f m  speed=%4.2f m/s  cmd=%s  %s  nearest=%s  red=%s  contacts=%d'
                          % (truth.header.stamp.to_sec(), p.x, p.y, math.hypot(truth.twist.twist.linear.x,
                                                                                truth.twist.twist.linear.y),
                             fmt(mon.cmd, ' m/s'), mon.zone or '-', fmt(mon.distance, ' m'),
                             '-' if mon.red is None else ('yes' if mon.red else 'no'), mon.contacts),
                          flush=True)
            if done:
                break
            time.sleep(0.05)
        with mon.lock:
            truth = mon.truth
            if truth is None:
                print('demo: no ground truth arrived; see %s' % log_path)
                return 1
            p = truth.pose.pose.position
            start = world.robot_start
            model = live_robot_model()
            q = truth.pose.pose.orientation
            yaw = quaternion_yaw((q.x, q.y, q.z, q.w))
            lidar_x = p.x + math.cos(yaw) * model.scan_pose.x - math.sin(yaw) * model.scan_pose.y
            lidar_y = p.y + math.sin(yaw) * model.scan_pose.x + math.cos(yaw) * model.scan_pose.y
            clearance, nearest = clearance_to_obstacles(world, lidar_x, lidar_y)
            print('\nWhat the robot did (ground truth, world "%s", robot %s, controller %s):'
                  % (world.name, args.robot, args.controller))
            for t, zone, x, y in mon.zone_changes:
                print('  t=%5.1fs  %-12s at x=%.2f y=%.2f m' % (t, zone, x, y))
            print('  drove %.2f m: from (%.2f, %.2f) to (%.2f, %.2f); %s'
                  % (mon.path_m, start.x, start.y, p.x, p.y,
                     'at rest' if mon.rest_since is not None else 'still moving'))
            if nearest is not None:
                print('  LIDAR clearance to the nearest obstacle (%s): %.3f m; body front: about %.3f m'
                      % (nearest, clearance, clearance - model.scan_to_front_m))
            if mon.closest[1] is not None:
                print('  closest approach of the footprint to any obstacle: %.3f m (%s, at t=%.1fs)'
                      % mon.closest)
            if mon.goal is not None:
                c, s = math.cos(start.yaw), math.sin(start.yaw)
                gx, gy = start.x + c * mon.goal[0] - s * mon.goal[1], start.y + s * mon.goal[0] + c * mon.goal[1]
                reached = [t for t, zone, _, _ in mon.zone_changes if zone == 'REACHED']
                away = math.hypot(gx - p.x, gy - p.y)
                if reached:
                    print('  goal (%.2f, %.2f): reached %.1f s (simulated) after the robot set off, ends %.2f m '
                          'from it' % (gx, gy, reached[0] - (mon.moved_t or 0.0), away))
                else:
                    print('  goal (%.2f, %.2f): not reached (mode %s), %.2f m from it'
                          % (gx, gy, mon.zone or '-', away))
            print('  contacts: %s' % ('none' if mon.contacts == 0 else '%d (the robot touched something)'
                                      % mon.contacts))
            return 0 if mon.contacts == 0 else 1
    finally:
        launch.end()
        log.close()


if __name__ == '__main__':
    sys.exit(main())
