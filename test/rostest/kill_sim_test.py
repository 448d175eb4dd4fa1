#!/usr/bin/env python3
"""Killing the simulator while the robot drives: stop_on_obstacle publishes zero within scan_timeout plus
one control period of wall time after the last scan (the simulated clock stops with the simulator, so
this is a wall clock). The last scan, not the kill request, starts the count: the simulator may still
publish for a moment while it shuts down."""
import os
import sys
import time
import unittest

import rosnode
import rospy
import rostest
from geometry_msgs.msg import Twist
from sensor_msgs.msg import LaserScan

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.control.decisions import StopSettings  # noqa: E402

SCAN_TIMEOUT_S = StopSettings().scan_timeout   # stop_on_obstacle's defaults, from their one source
PERIOD_S = StopSettings().watchdog_period_s
# Delivery and scheduling slack between two processes on a loaded 2-core machine.
SLACK_S = 0.1


class KillSim(unittest.TestCase):
    def test_controller_stops_when_the_simulator_dies(self):
        rospy.init_node('kill_sim_test')
        truth = harness.GroundTruth()
        cmds = []
        rospy.Subscriber('cmd_vel', Twist, lambda m: cmds.append((time.monotonic(), m.linear.x)), queue_size=100)
        scans = []
        rospy.Subscriber('scan', LaserScan, lambda m: scans.append(time.monotonic()), queue_size=100)
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.3)
        # The ground truth's subscription may connect before the command's: wait for a driving command too.
        deadline = time.monotonic() + harness.WAIT_FOR_TOPIC_S
        while not (cmds and cmds[-1][1] > 0.3) and time.monotonic() < deadline:
            time.sleep(0.01)
        self.assertTrue(cmds and cmds[-1][1] > 0.3, 'the controller was not driving')
        killed_at = time.monotonic()
        rosnode.kill_nodes(['/sim'])
        while time.monotonic() < killed_at + 3.0:
            time.sleep(0.02)
        self.assertTrue(scans, 'no /scan before the kill')
        last_scan = scans[-1]
        self.assertLess(last_scan - killed_at, 1.0, 'the simulator went on publishing after the kill')
        zeros = [t for t, v in cmds if t > last_scan and v == 0.0]
        self.assertTrue(zeros, 'no zero command after the simulator died')
        self.assertLess(zeros[0] - last_scan, SCAN_TIMEOUT_S + PERIOD_S + SLACK_S,
                        'first zero %.3f s after the last scan (%.3f s after the kill request)'
                        % (zeros[0] - last_scan, zeros[0] - killed_at))
        late = [v for t, v in cmds if t > zeros[0]]
        self.assertTrue(all(v == 0.0 for v in late), 'moved again after stopping: %s' % late[:5])


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'kill_sim', KillSim)
