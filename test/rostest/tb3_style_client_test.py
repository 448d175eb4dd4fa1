#!/usr/bin/env python3
"""A client in the style of TurtleBot3's own examples, which index the LDS-01's 360 samples directly (index 0
straight ahead, counter-clockwise): it drives at 0.15 m/s while the front samples (indices 0-14 and 345-359)
are over 0.5 m, and stops. Against robot:=burger it must stop before the wall with no contact."""
import os
import sys
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from sensor_msgs.msg import LaserScan

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

STOP_M = 0.5
SPEED_MPS = 0.15
WALL_FACE_X = 3.0
LDS_X = -0.032  # the LDS-01 behind base_footprint, as on the real robot


class Tb3StyleClient(unittest.TestCase):
    def test_index_based_front_works_on_the_burger(self):
        rospy.init_node('tb3_style_client')
        pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        state = {'front': None}

        def on_scan(scan):
            # As TurtleBot3 example code does it: the samples around index 0, ignoring zeros and inf.
            front = [r for r in list(scan.ranges[0:15]) + list(scan.ranges[345:360]) if 0.0 < r < float('inf')]
            state['front'] = min(front) if front else float('inf')
            cmd = Twist()
            cmd.linear.x = SPEED_MPS if state['front'] > STOP_M else 0.0
            pub.publish(cmd)
        rospy.Subscriber('scan', LaserScan, on_scan, queue_size=1)
        truth = harness.GroundTruth()
        contacts = harness.contact_count_topic()
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.1)
        rest = truth.wait(timeout_s=60.0, predicate=lambda m: abs(m.twist.twist.linear.x) < 0.01
                          and m.pose.pose.position.x > 1.0)
        lidar_to_wall = WALL_FACE_X - (rest.pose.pose.position.x + LDS_X)
        self.assertGreater(lidar_to_wall, 0.4, lidar_to_wall)
        self.assertLess(lidar_to_wall, STOP_M + 0.05, lidar_to_wall)
        self.assertEqual(contacts.wait().data, 0)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'tb3_style_client', Tb3StyleClient)
