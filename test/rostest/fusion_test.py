#!/usr/bin/env python3
"""fusion.launch in one world, judged on ground truth. Parameters: ~goal_x, ~goal_y (world frame, m): the goal,
reached (REACHED, ground truth within GOAL_RADIUS_M) with no contact within ~limit_s simulated seconds;
~expect_wait: whether the controller must wait (WAITING) or must not; with a wait, ~stop_before_x (m): the
robot's front stays short of this x while it waits, its ~belief then names a PERSON in the path, ~tracks
(watched as rviz would) draws that person as a red cylinder with a velocity arrow, and ~max_detour_m: how
far from the line y = 0 the robot may go."""
import json
import math
import os
import sys
import unittest

import rospy
import rostest
from std_msgs.msg import String, UInt32
from visualization_msgs.msg import Marker, MarkerArray

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

GOAL_RADIUS_M = 0.4
FRONT_M = 0.15        # urdf/closed_loop.urdf: base_footprint to the front of the footprint


class Fusion(unittest.TestCase):
    def test_fusion(self):
        rospy.init_node('fusion_test')
        goal = rospy.get_param('~goal_x'), rospy.get_param('~goal_y')
        limit_s = rospy.get_param('~limit_s', 60.0)
        expect_wait = rospy.get_param('~expect_wait')
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        mode = harness.Latest('fusion_controller/mode', String, keep_all=True)
        beliefs = harness.Latest('fusion_controller/belief', String, keep_all=True)
        contacts = harness.Latest('contact_count', UInt32)
        drawn = harness.Latest('fusion_controller/tracks', MarkerArray, keep_all=True)
        start = truth.wait().header.stamp.to_sec()
        waiting_x = []
        while not rospy.is_shutdown():
            m = truth.wait()
            if mode.msg is not None and mode.msg.data == 'WAITING':
                waiting_x.append(m.pose.pose.position.x)
            if m.header.stamp.to_sec() - start > limit_s or (mode.msg is not None and mode.msg.data in
                                                            ('REACHED', 'FAILED')):
                break
            rospy.sleep(0.1)
        seen = [msg.data for msg in mode.all]
        self.assertEqual(contacts.wait().data, 0, 'contact; modes %s' % seen)
        p = truth.wait().pose.pose.position
        self.assertEqual(seen[-1], 'REACHED', 'modes %s, at (%.2f, %.2f)' % (seen, p.x, p.y))
        self.assertLess(math.hypot(p.x - goal[0], p.y - goal[1]), GOAL_RADIUS_M)
        if not expect_wait:
            self.assertNotIn('WAITING', seen)
            return
        self.assertIn('WAITING', seen)
        self.assertLess(max(waiting_x) + FRONT_M, rospy.get_param('~stop_before_x'))
        said = [json.loads(b.data) for b in beliefs.all]
        self.assertTrue(any(b['mode'] == 'WAITING' and any(t['belief'] == 'PERSON' and t['in_path']
                                                          for t in b['tracks']) for b in said), said[-3:])
        self.assertLess(max(abs(m.pose.pose.position.y) for m in truth.all), rospy.get_param('~max_detour_m'))
        markers = [m for array in drawn.all for m in array.markers]
        self.assertTrue(any(m.type == Marker.CYLINDER and m.color.r > 0.9 and m.color.g < 0.3 for m in markers),
                        'no PERSON (red) track drawn on ~tracks')
        self.assertTrue(any(m.type == Marker.ARROW for m in markers), 'no velocity arrow on ~tracks')


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'fusion', Fusion)
