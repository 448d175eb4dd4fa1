#!/usr/bin/env python3
"""avoid.launch in one world, judged on ground truth. Parameters: ~expect: 'reached' (the goal within
~goal_tolerance_m, REACHED, no contact) or 'trapped' (ends RECOVERING or FAILED, at rest if FAILED, no
contact); ~hold_after_x (m, optional): with no goal, once the robot is 3 m past this x its heading is within
10 degrees of the start heading; ~limit_s: simulated seconds allowed."""
import math
import os
import sys
import unittest

import rospy
import rostest
from std_msgs.msg import String, UInt32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.geometry import quaternion_yaw  # noqa: E402
from closed_loop.navigator import NavState  # noqa: E402

HOLD_TOLERANCE_RAD = math.radians(10.0)
PASSED_BY_M = 3.0
AT_REST_MPS = 0.01


class Avoid(unittest.TestCase):
    def test_navigate(self):
        rospy.init_node('avoid_test')
        expect = rospy.get_param('~expect')
        limit_s = rospy.get_param('~limit_s', 60.0)
        hold_after_x = rospy.get_param('~hold_after_x', None)
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        mode = harness.Latest('avoid_obstacles/mode', String, keep_all=True)
        contacts = harness.Latest('contact_count', UInt32)
        start = truth.wait().header.stamp.to_sec()
        final = {'reached': (NavState.REACHED.name,), 'trapped': (NavState.FAILED.name,), 'hold': ()}[expect]
        while not rospy.is_shutdown():
            m = truth.wait()
            if m.header.stamp.to_sec() - start > limit_s:
                break
            if mode.msg is not None and mode.msg.data in final:
                break
            if hold_after_x is not None and m.pose.pose.position.x > hold_after_x + PASSED_BY_M + 0.5:
                break
            rospy.sleep(0.2)
        seen = [msg.data for msg in mode.all]
        self.assertEqual(contacts.wait().data, 0, 'contact; modes %s' % seen)
        p = truth.wait().pose.pose
        if expect == 'reached':
            self.assertEqual(seen[-1], NavState.REACHED.name, 'not reached within %g s: modes %s, at (%.2f, %.2f)'
                             % (limit_s, seen, p.position.x, p.position.y))
            self.assertIn(NavState.AVOIDING.name, seen)
            goal = rospy.get_param('/avoid_obstacles/goal_distance', 10.0)
            self.assertLess(math.hypot(p.position.x - goal, p.position.y), 0.4)
        elif expect == 'trapped':
            self.assertIn(seen[-1], (NavState.FAILED.name, NavState.RECOVERING.name), seen)
            self.assertIn(NavState.RECOVERING.name, seen)
            if seen[-1] == NavState.FAILED.name:
                harness.sim_sleep(1.0)
                self.assertLess(abs(truth.wait().twist.twist.linear.x), AT_REST_MPS)
        if hold_after_x is not None:
            past = [m for m in truth.all if m.pose.pose.position.x > hold_after_x + PASSED_BY_M]
            self.assertTrue(past, 'never got %g m past x = %g' % (PASSED_BY_M, hold_after_x))
            for m in past:
                q = m.pose.pose.orientation
                yaw = quaternion_yaw((q.x, q.y, q.z, q.w))
                self.assertLess(abs(yaw), HOLD_TOLERANCE_RAD, 'heading %.1f deg at x = %.2f m'
                                % (math.degrees(yaw), m.pose.pose.position.x))
            self.assertNotIn(NavState.REACHED.name, seen)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'avoid', Avoid)
