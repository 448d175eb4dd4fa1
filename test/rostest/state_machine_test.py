#!/usr/bin/env python3
"""state_machine_controller in `wall`: explores, backs up at -0.3 m/s for 2.0 s of simulated time when the
wall is within 0.5 m, then explores again (ground truth shows the reversal and the resumption)."""
import os
import sys
import unittest

import rospy
import rostest
from std_msgs.msg import String, UInt32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.control.state_machine import BackUpSettings, State  # noqa: E402

BACKUP_S = BackUpSettings().backup_duration   # state_machine_controller's defaults (the lesson's)
BACKUP_SPEED_MPS = BackUpSettings().backup_speed
TIME_TOLERANCE_S = 0.15   # one 10 Hz control period plus a clock step
SPEED_TOLERANCE_MPS = 0.05


class StateMachineInLoop(unittest.TestCase):
    def test_backs_up_for_two_seconds_and_resumes(self):
        rospy.init_node('state_machine_test')
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        contacts = harness.Latest('contact_count', UInt32)
        states = []
        rospy.Subscriber('state_machine_controller/mode', String,
                         lambda m: states.append((rospy.get_time(), m.data)), queue_size=20)
        truth.wait()
        while not rospy.is_shutdown():
            rospy.sleep(0.1)
            names = [s for _, s in states]
            if State.BACKING_UP.name in names and names.index(State.BACKING_UP.name) < len(names) - 1:
                break
        harness.sim_sleep(1.0)
        names = [s for _, s in states]
        i = names.index(State.BACKING_UP.name)
        self.assertEqual(names[i + 1], State.EXPLORING.name, states)
        began, ended = states[i][0], states[i + 1][0]
        self.assertAlmostEqual(ended - began, BACKUP_S, delta=TIME_TOLERANCE_S,
                               msg='backed up for %.3f s of simulated time' % (ended - began))
        log = list(truth.all)
        middle = [m for m in log if began + 0.6 < m.header.stamp.to_sec() < ended - 0.1]
        self.assertTrue(middle)
        for m in middle:
            self.assertAlmostEqual(m.twist.twist.linear.x, BACKUP_SPEED_MPS, delta=SPEED_TOLERANCE_MPS)
        after = [m for m in log if m.header.stamp.to_sec() > ended + 0.5]
        self.assertTrue(after and after[-1].twist.twist.linear.x > 0.2, 'did not resume exploring')
        self.assertEqual(contacts.wait().data, 0)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'state_machine', StateMachineInLoop)
