#!/usr/bin/env python3
"""Black-box contract of sim_node in the `wall` world: clock, scan geometry, driving, watchdog, NaN."""
import math
import os
import sys
import unittest

import time

import rospy
import rostest
import tf2_ros
from std_srvs.srv import Empty
from geometry_msgs.msg import Twist
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from std_msgs.msg import UInt32
from visualization_msgs.msg import Marker, MarkerArray

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.sim.simulation import SimSettings  # noqa: E402
from closed_loop.sim.world import load_world  # noqa: E402

WALL_NEAR_FACE_X_M = 3.0        # worlds/wall.yaml
WALL_HALF_SPAN_Y_M = 2.0
RANGE_TOLERANCE_M = 0.01
CMD_VEL_TIMEOUT_S = SimSettings().cmd_vel_timeout        # sim_node's defaults, from their one source
MAX_LINEAR_ACCEL_MPS2 = SimSettings().max_linear_accel
# Slack for the physics settling and the 50 Hz ground-truth period.
STOP_SLACK_S = 0.15


class SimContract(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('sim_contract_test')
        cls.truth = harness.GroundTruth()
        cls.scan = harness.Latest('scan', LaserScan)
        cls.clock = harness.Latest('/clock', Clock)
        cls.contacts = harness.Latest('contact_count', UInt32)
        cls.cmd = rospy.Publisher('cmd_vel', Twist, queue_size=10)
        cls.truth.wait()
        cls.scan.wait()

    def test_1_clock_advances(self):
        first = self.clock.wait().clock.to_sec()
        later = self.clock.wait(predicate=lambda m: m.clock.to_sec() > first + 0.5).clock.to_sec()
        self.assertGreater(later, first)

    def test_2_scan_fields_agree(self):
        scan = self.scan.wait()
        n = len(scan.ranges)
        self.assertEqual(n, 360)
        self.assertAlmostEqual(scan.angle_min, -math.pi, places=5)
        self.assertAlmostEqual(scan.angle_min + (n - 1) * scan.angle_increment, scan.angle_max, places=5)
        self.assertAlmostEqual(n * scan.angle_increment, 2 * math.pi, places=5)
        self.assertAlmostEqual(scan.scan_time, 0.1, places=6)
        self.assertAlmostEqual(scan.time_increment * n, scan.scan_time, places=6)
        self.assertEqual(scan.header.frame_id, 'base_scan')

    def test_3_wall_at_known_index_and_range(self):
        x, y = self.truth.xy()
        scan = self.scan.wait()
        front = int(round((0.0 - scan.angle_min) / scan.angle_increment))
        self.assertEqual(front, 180)
        self.assertAlmostEqual(scan.ranges[front], WALL_NEAR_FACE_X_M - x, delta=RANGE_TOLERANCE_M)
        for degrees in (-30, 15, 25):
            i = front + degrees
            angle = scan.angle_min + i * scan.angle_increment
            expected = (WALL_NEAR_FACE_X_M - x) / math.cos(angle)
            self.assertLess(expected, scan.range_max)
            self.assertLess(abs(y + expected * math.sin(angle)), WALL_HALF_SPAN_Y_M)
            self.assertAlmostEqual(scan.ranges[i], expected, delta=RANGE_TOLERANCE_M, msg='ray %d deg' % degrees)
        # Left, right and behind: nothing within range_max, so +inf (REP 117), never a number.
        for i in (front + 90, front - 90, 0):
            self.assertTrue(math.isinf(scan.ranges[i]) and scan.ranges[i] > 0, 'ray %d: %r' % (i, scan.ranges[i]))

    def _publish_for(self, msg, seconds, rate_hz=10.0):
        end = rospy.get_time() + seconds
        rate = rospy.Rate(rate_hz)
        while rospy.get_time() < end and not rospy.is_shutdown():
            self.cmd.publish(msg)
            rate.sleep()

    def test_4_nan_command_does_not_move(self):
        x0, y0 = self.truth.xy()
        for field in ('linear.x', 'angular.z', 'linear.y'):
            msg = harness.twist()
            group, axis = field.split('.')
            setattr(getattr(msg, group), axis, float('nan'))
            self._publish_for(msg, 0.5)
        inf = harness.twist(float('inf'))
        self._publish_for(inf, 0.5)
        harness.sim_sleep(0.3)
        x1, y1 = self.truth.xy()
        self.assertLess(math.hypot(x1 - x0, y1 - y0), 0.005)
        self.assertLess(self.truth.speed(), harness.REST_SPEED_MPS)

    def test_5_forward_moves_and_watchdog_stops(self):
        x0, _ = self.truth.xy()
        log = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        self._publish_for(harness.twist(0.5), 1.0)
        last_command = rospy.get_time()
        moving_x, _ = self.truth.xy()
        self.assertGreater(moving_x - x0, 0.35, 'the robot did not follow 0.5 m/s for 1 s')
        harness.sim_sleep(CMD_VEL_TIMEOUT_S + 1.0)
        deadline = last_command + CMD_VEL_TIMEOUT_S + 0.5 / MAX_LINEAR_ACCEL_MPS2 + STOP_SLACK_S
        after = [m for m in log.all if m.header.stamp.to_sec() >= deadline]
        self.assertTrue(after, 'no ground truth after the stop deadline')
        for m in after:
            self.assertLess(abs(m.twist.twist.linear.x), harness.REST_SPEED_MPS,
                            'still moving at t = %.3f, %.3f s after the last command'
                            % (m.header.stamp.to_sec(), m.header.stamp.to_sec() - last_command))
        # It did keep going until the watchdog: moving just before the timeout.
        before = [m for m in log.all if last_command < m.header.stamp.to_sec() < last_command + CMD_VEL_TIMEOUT_S - 0.1]
        self.assertTrue(before and max(m.twist.twist.linear.x for m in before) > 0.4)
        self.assertEqual(self.contacts.wait().data, 0)

    def test_6_pause_unpause_reset(self):
        for name in ('sim/pause_physics', 'sim/unpause_physics', 'sim/reset_world'):
            rospy.wait_for_service(name, timeout=harness.WAIT_FOR_TOPIC_S)
        rospy.ServiceProxy('sim/pause_physics', Empty)()
        paused_at = self.clock.wait().clock.to_sec()
        time.sleep(0.5)  # wall time: simulated time must not move while paused
        self.assertEqual(self.clock.msg.clock.to_sec(), paused_at)
        rospy.ServiceProxy('sim/unpause_physics', Empty)()
        self.clock.wait(predicate=lambda m: m.clock.to_sec() > paused_at + 0.2)
        self._publish_for(harness.twist(0.5), 0.5)
        x_moved, _ = self.truth.xy()
        self.assertGreater(x_moved, 0.05)
        rospy.ServiceProxy('sim/reset_world', Empty)()
        harness.sim_sleep(0.2)
        x, y = self.truth.xy()
        self.assertLess(abs(x) + abs(y), 0.01, 'reset_world left the robot at (%.3f, %.3f)' % (x, y))


    def test_7_world_markers_and_world_frame_in_tf(self):
        wall = load_world(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'worlds',
                                       'wall.yaml'))
        markers = harness.Latest('world_markers', MarkerArray).wait().markers
        self.assertEqual(markers[0].action, Marker.DELETEALL)
        shown = markers[1:]
        self.assertEqual([m.id for m in shown], list(range(len(wall.obstacles))))
        for m, obstacle in zip(shown, wall.obstacles):
            self.assertEqual((m.header.frame_id, m.type, m.action), ('world', Marker.CUBE, Marker.ADD))
            p = m.pose.position
            self.assertEqual((p.x, p.y, p.z), obstacle.position)
            self.assertEqual((m.scale.x, m.scale.y, m.scale.z), obstacle.size)
            for got, want in zip((m.color.r, m.color.g, m.color.b, m.color.a), obstacle.color):
                self.assertAlmostEqual(got, want, places=6)   # std_msgs/ColorRGBA is float32
        # Drive a little so odometry and ground truth differ from the start; world -> base_footprint
        # through odom must then be the ground truth.
        self._publish_for(harness.twist(0.3, 0.4), 1.0)
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        harness.sim_sleep(CMD_VEL_TIMEOUT_S + 1.0)   # at rest: the two are compared at one pose
        t = buffer.lookup_transform('world', 'base_footprint', rospy.Time(0), rospy.Duration(5.0))
        truth = self.truth.wait()
        x, y = t.transform.translation.x, t.transform.translation.y
        tx, ty = truth.pose.pose.position.x, truth.pose.pose.position.y
        self.assertGreater(math.hypot(tx, ty), 0.1)
        self.assertLess(math.hypot(x - tx, y - ty), 0.01, 'TF world -> base_footprint (%.3f, %.3f) is not the '
                        'ground truth (%.3f, %.3f)' % (x, y, tx, ty))


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'sim_contract', SimContract)
