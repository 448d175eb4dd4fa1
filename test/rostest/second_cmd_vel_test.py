#!/usr/bin/env python3
"""A second /cmd_vel publisher is reported by the simulator, naming both publishers; a command of 1e308 m/s is
clipped with a warning giving the value and the limit."""
import os
import sys
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from rosgraph_msgs.msg import Log

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

WAIT_S = 10.0


class SecondCmdVel(unittest.TestCase):
    def test_simulator_reports_second_publisher_and_clipping(self):
        rospy.init_node('intruder')
        warnings = []
        rospy.Subscriber('/rosout', Log, lambda m: warnings.append(m) if m.level >= Log.WARN else None,
                         queue_size=100)
        harness.GroundTruth().wait(predicate=lambda m: m.twist.twist.linear.x > 0.1)
        pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        deadline = time.monotonic() + WAIT_S

        def sim_said(*words):
            return [m.msg for m in warnings if m.name == '/sim' and all(w in m.msg for w in words)]
        me = rospy.get_name()
        while time.monotonic() < deadline and not (sim_said('/driver', me)
                                                   and sim_said('1e+308', 'limit 1.5')):
            pub.publish(harness.twist(1e308))
            time.sleep(0.05)
        pub.publish(harness.twist(0.0))
        seen = [m.msg for m in warnings if m.name == '/sim']
        self.assertTrue(sim_said('/driver', me), 'no warning naming both publishers: %s' % seen[:5])
        self.assertTrue(sim_said('1e+308', 'limit 1.5'), 'no clipping warning with value and limit: %s' % seen[:5])


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'second_cmd_vel', SecondCmdVel)
