#!/usr/bin/env python3
"""Killing the simulator while the robot drives: stop_on_obstacle publishes zero within scan_timeout plus
one control period of wall time (the simulated clock stops with the simulator, so this is a wall clock)."""
import os
import sys
import time
import unittest

import rosnode
import rospy
import rostest
from geometry_msgs.msg import Twist

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

SCAN_TIMEOUT_S = 0.5   # stop_on_obstacle defaults
PERIOD_S = 0.1
# Delivery and scheduling slack between two processes on a loaded 2-core machine.
SLACK_S = 0.1


class KillSim(unittest.TestCase):
    def test_controller_stops_when_the_simulator_dies(self):
        rospy.init_node('kill_sim_test')
        truth = harness.GroundTruth()
        cmds = []
        rospy.Subscriber('cmd_vel', Twist, lambda m: cmds.append((time.monotonic(), m.linear.x)), queue_size=100)
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.3)
        self.assertTrue(cmds and cmds[-1][1] > 0.3, 'the controller was not driving')
        killed_at = time.monotonic()
        rosnode.kill_nodes(['/sim'])
        deadline = killed_at + SCAN_TIMEOUT_S + PERIOD_S + SLACK_S
        while time.monotonic() < killed_at + 3.0:
            time.sleep(0.02)
        zeros = [t for t, v in cmds if t > killed_at and v == 0.0]
        self.assertTrue(zeros, 'no zero command after the simulator died')
        self.assertLess(zeros[0] - killed_at, deadline - killed_at,
                        'first zero %.3f s after the kill' % (zeros[0] - killed_at))
        late = [v for t, v in cmds if t > zeros[0]]
        self.assertTrue(all(v == 0.0 for v in late), 'moved again after stopping: %s' % late[:5])


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'kill_sim', KillSim)
