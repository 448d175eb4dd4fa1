#!/usr/bin/env python3
"""A spoofed /scan (a second publisher sending all +inf, stamped now, frame base_scan) cannot drive the robot
into the wall: stop_on_obstacle logs an error naming both publishers and stops; zero contacts on ground truth."""
import math
import os
import sys
import threading
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import LaserScan

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

SPOOF_RATE_HZ = 20.0


class SpoofedScan(unittest.TestCase):
    def test_second_scan_publisher_stops_the_robot(self):
        rospy.init_node('spoofer')
        truth = harness.GroundTruth()
        judged = harness.Judged()            # (from the start: it sees the robot told to cruise)
        contacts = harness.contact_count_topic()
        errors = []
        rospy.Subscriber('/rosout', Log, lambda m: errors.append(m) if m.level >= Log.ERROR else None,
                         queue_size=100)
        real = harness.Latest('scan', LaserScan).wait()
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.3 and m.pose.pose.position.x > 0.5)
        x_spoof = truth.wait().pose.pose.position.x

        pub = rospy.Publisher('scan', LaserScan, queue_size=1)
        stop = threading.Event()

        def spoof():
            rate = rospy.Rate(SPOOF_RATE_HZ)
            while not stop.is_set() and not rospy.is_shutdown():
                fake = LaserScan()
                fake.header.stamp = rospy.Time.now()
                fake.header.frame_id = real.header.frame_id
                for field in ('angle_min', 'angle_max', 'angle_increment', 'time_increment', 'scan_time',
                              'range_min', 'range_max'):
                    setattr(fake, field, getattr(real, field))
                fake.ranges = [math.inf] * len(real.ranges)
                pub.publish(fake)
                rate.sleep()
        spoofer = threading.Thread(target=spoof, daemon=True)
        spoofer.start()
        try:
            at_rest = judged.rest(timeout_s=20.0)
            # Stopped well before the wall (front face at x = 3.0 m): by the refusal, not by the wall.
            self.assertLess(at_rest.final_pose[0], 2.0,
                            'with the spoofer running the robot drove on to x = %.2f m (spoofing began at %.2f m)'
                            % (at_rest.final_pose[0], x_spoof))
            harness.sim_sleep(3.0)
            self.assertLess(abs(truth.wait().twist.twist.linear.x), harness.REST_SPEED_MPS, 'moved while spoofed')
        finally:
            stop.set()
            spoofer.join(2.0)
            pub.unregister()
        me = rospy.get_name()
        named = [m.msg for m in errors if m.name == '/stop_on_obstacle' and '/sim' in m.msg and me in m.msg]
        self.assertTrue(named, 'no error from /stop_on_obstacle naming /sim and %s; errors: %s'
                        % (me, [(m.name, m.msg) for m in errors][:5]))
        # With the spoofer gone, the controller trusts /scan again and stops at the wall as usual.
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.1)
        at_wall = harness.Judged().rest(timeout_s=30.0)
        self.assertGreater(at_wall.final_pose[0], 2.0, at_wall.why)
        self.assertEqual(contacts.wait().data, 0, 'the robot touched the wall')


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'spoofed_scan', SpoofedScan)
