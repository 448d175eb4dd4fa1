#!/usr/bin/env python3
"""multi_robot.launch in `two_robots`: r1 and r2 drive toward each other and both come to rest with no
contact, each stopped by its own controller on its own scan of the other robot (ground truth). One node
publishes /clock and it never jumps back; each robot's topics are under its name and its frames carry its
prefix (r1/base_scan, r1/odom, r1/base_footprint), with world above each odom in one TF tree."""
import math
import os
import sys
import unittest

import rosgraph
import rospy
import rostest
import tf2_ros
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String, UInt32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.control.decisions import StopSettings, Zone  # noqa: E402
from closed_loop.sim.world import load_world  # noqa: E402

ROBOTS = ('r1', 'r2')
BODY_LENGTH_M = 0.30        # urdf/closed_loop.urdf: the body is 0.30 m long, the LIDAR at its centre
MOVED_M = 1.0
TF_TOLERANCE_M = 0.01


class MultiRobot(unittest.TestCase):
    def test_two_robots_stop_for_each_other(self):
        rospy.init_node('multi_robot_test')
        world = load_world(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'worlds',
                                        'two_robots.yaml'))
        starts = {spec.name: spec.start for spec in world.robots}
        self.assertEqual(sorted(starts), list(ROBOTS))
        clock = harness.Latest('/clock', Clock, keep_all=True)
        truth = {name: harness.Latest('/%s/base_pose_ground_truth' % name, harness.Odometry, keep_all=True)
                 for name in ROBOTS}
        judged = {name: harness.Judged('/%s/' % name) for name in ROBOTS}
        scans = {name: harness.Latest('/%s/scan' % name, LaserScan) for name in ROBOTS}
        contacts = {name: harness.Latest('/%s/contact_count' % name, UInt32) for name in ROBOTS}
        modes = {name: harness.Latest('/%s/stop_on_obstacle/mode' % name, String) for name in ROBOTS}

        for name in ROBOTS:
            self.assertEqual(scans[name].wait().header.frame_id, name + '/base_scan')
            m = truth[name].wait()
            self.assertEqual((m.header.frame_id, m.child_frame_id), ('world', name + '/base_footprint'))

        # Both came to rest, as the judge has it, after having moved.
        rests = {name: judged[name].rest(timeout_s=120.0) for name in ROBOTS}
        for name in ROBOTS:
            self.assertGreater(abs(rests[name].final_pose[0] - starts[name].x), MOVED_M, rests[name].why)

        x = {name: truth[name].wait().pose.pose.position.x for name in ROBOTS}
        gap = abs(x['r2'] - x['r1']) - BODY_LENGTH_M
        self.assertGreater(gap, 0.0, 'the robots overlap: centres %.3f m apart' % abs(x['r2'] - x['r1']))
        for name in ROBOTS:
            self.assertEqual(contacts[name].wait().data, 0, '%s touched something' % name)
            self.assertEqual(modes[name].wait().data, Zone.STOP.name)
        # Each stopped for the other at its own stop distance (LIDAR to the other's housing, 0.035 m radius).
        centres = abs(x['r2'] - x['r1'])
        self.assertLess(centres, StopSettings().stop_distance + 0.035 + 0.01)

        # One /clock, from the simulator, never jumping back.
        state = rosgraph.Master('/multi_robot_test').getSystemState()
        publishers = dict((topic, nodes) for topic, nodes in state[0])
        self.assertEqual(publishers['/clock'], ['/sim'])
        stamps = [m.clock.to_sec() for m in clock.all]
        self.assertTrue(all(b >= a for a, b in zip(stamps, stamps[1:])), 'the clock went back')

        # One TF tree: world -> NAME/odom -> NAME/base_footprint is the ground truth.
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        for name in ROBOTS:
            t = buffer.lookup_transform('world', name + '/base_footprint', rospy.Time(0), rospy.Duration(5.0))
            p = truth[name].wait().pose.pose.position
            self.assertLess(math.hypot(t.transform.translation.x - p.x, t.transform.translation.y - p.y),
                            TF_TOLERANCE_M, name)
            buffer.lookup_transform(name + '/base_footprint', name + '/base_scan', rospy.Time(0),
                                    rospy.Duration(5.0))   # robot_state_publisher's prefixed frames


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'multi_robot', MultiRobot)
