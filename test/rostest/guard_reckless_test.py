#!/usr/bin/env python3
"""A reckless controller (1 m/s ahead, always) behind cmd_vel_guard: the robot drives, the guard vetoes the
command before the footprint reaches anything, and the simulator's ground truth counts zero contacts."""
import os
import sys
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from std_msgs.msg import String

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

RECKLESS_MPS = 1.0
# After the robot has driven and come to rest, it is watched this long (simulated s) for a late contact.
WATCH_AT_REST_S = 3.0


class GuardReckless(unittest.TestCase):
    def test_reckless_controller_touches_nothing(self):
        rospy.init_node('guard_reckless_test')
        truth = harness.GroundTruth()
        contacts = harness.contact_count_topic()
        unguarded = harness.Latest('cmd_vel_unguarded', Twist)
        verdicts = harness.Latest('cmd_vel_guard/verdict', String, keep_all=True)
        # Under way, half a metre out: on a loaded machine the reckless node's first commands can reach the guard
        # late, which it rightly vetoes as stale (the robot halts at its start, then goes on when they flow).
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.5 * RECKLESS_MPS and m.pose.pose.position.x > 0.5)
        # Driving; now wait for rest (the guard's doing: the controller never asks for less).
        rest = harness.Judged().rest(timeout_s=60.0)
        self.assertGreater(rest.final_pose[0], 1.0, rest.why)
        harness.sim_sleep(WATCH_AT_REST_S)
        self.assertAlmostEqual(unguarded.wait().linear.x, RECKLESS_MPS,
                               msg='the reckless controller stopped commanding 1 m/s')
        self.assertLess(abs(truth.wait().twist.twist.linear.x), harness.REST_SPEED_MPS, 'the robot moved on')
        self.assertIn('VETOED', [m.data for m in verdicts.all], 'the guard never vetoed')
        self.assertEqual(contacts.wait().data, 0, 'the robot touched an obstacle behind the guard')


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'guard_reckless', GuardReckless)
