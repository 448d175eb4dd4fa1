#!/usr/bin/env python3
"""demo.launch in `wall`: the robot cruises, slows inside slow_distance and rests 0.40-0.50 m (LIDAR to wall)
from the wall without touching it, judged on ground truth. Parameters: ~cruise_speed (what the controller was
given), ~slow_band_end (m), ~min_clearance, ~max_clearance (m), ~red_expected (bool)."""
import math
import os
import sys
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from std_msgs.msg import Bool, UInt32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.control.decisions import StopSettings  # noqa: E402

WALL_NEAR_FACE_X_M = 3.0     # worlds/wall.yaml; the LIDAR is at the robot's centre (urdf/closed_loop.urdf)
SLOW_DISTANCE_M = StopSettings().slow_distance   # stop_on_obstacle's defaults, from their one source
SLOW_SPEED_MPS = StopSettings().slow_speed
SPEED_TOLERANCE_MPS = 0.05
# The body settles back by a fraction of a millimetre after braking.
OVERSHOOT_TOLERANCE_M = 0.005
CMD_RATE_HZ = 10.0
CMD_RATE_TOLERANCE_HZ = 1.0


class LoopStop(unittest.TestCase):
    def test_cruise_slow_stop(self):
        rospy.init_node('loop_stop_test')
        cruise = rospy.get_param('~cruise_speed', 0.5)
        low = rospy.get_param('~min_clearance', 0.40)
        high = rospy.get_param('~max_clearance', 0.50)
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        judged = harness.Judged()
        cmds = []
        rospy.Subscriber('cmd_vel', Twist, lambda m: cmds.append((rospy.get_time(), m.linear.x)), queue_size=100)
        contacts = harness.Latest('contact_count', UInt32)
        red = harness.Latest('red_detected', Bool, keep_all=True)
        truth.wait()
        # Until the judge says it came to rest (bounded by the test's time-limit).
        rest = judged.rest(timeout_s=120.0)
        self.assertEqual(rest.outcome, 'stopped', rest.why)
        rospy.sleep(2.0)  # more stopped-phase commands for the rate check
        log = list(truth.all)

        def clearance(m):
            return WALL_NEAR_FACE_X_M - m.pose.pose.position.x

        far = [m for m in log if clearance(m) > SLOW_DISTANCE_M + 0.3]
        cruising = max(m.twist.twist.linear.x for m in far)
        self.assertAlmostEqual(cruising, cruise, delta=SPEED_TOLERANCE_MPS, msg='did not cruise at %g' % cruise)
        # Where the robot must already be down to slow speed (it brakes at max_linear_accel after
        # entering the slow zone, so the band ends nearer the wall at a faster cruise).
        slow_band_end = rospy.get_param('~slow_band_end', 0.75)
        slow_band = [m for m in log if 0.55 < clearance(m) < slow_band_end]
        self.assertTrue(slow_band)
        off = ['%.3f m: %.3f m/s' % (clearance(m), m.twist.twist.linear.x) for m in slow_band
               if abs(m.twist.twist.linear.x - SLOW_SPEED_MPS) > SPEED_TOLERANCE_MPS]
        self.assertFalse(off, 'not at slow speed %g m/s in the band %g-0.55 m from the wall: %s'
                         % (SLOW_SPEED_MPS, slow_band_end, ', '.join(off[:10])))
        final = WALL_NEAR_FACE_X_M - rest.final_pose[0]
        self.assertTrue(low <= final <= high, 'came to rest %.3f m from the wall, expected [%g, %g]'
                        % (final, low, high))
        self.assertLess(abs(log[-1].twist.twist.linear.x), harness.REST_SPEED_MPS, 'moved on after its rest')
        self.assertEqual(contacts.wait().data, 0, 'the robot touched something')
        self.assertGreater(min(clearance(m) for m in log), final - OVERSHOOT_TOLERANCE_M,
                           'the robot got closer than where it rested (overshoot and back?)')

        # /cmd_vel at 10 Hz while moving and while stopped (rates over simulated time), from when the judge says it
        # came to rest.
        rest_start = rest.time_s
        moving = [t for t, v in cmds if v > 0 and t < rest_start - 0.5]
        stopped = [t for t, v in cmds if v == 0.0 and t > rest_start + 0.2]
        for name, times in (('moving', moving), ('stopped', stopped)):
            self.assertGreater(len(times), 5, 'too few %s commands' % name)
            rate = (len(times) - 1) / (times[-1] - times[0])
            self.assertAlmostEqual(rate, CMD_RATE_HZ, delta=CMD_RATE_TOLERANCE_HZ, msg='cmd_vel %s' % name)

        if not rospy.has_param('~red_expected'):
            return  # this run has no camera
        expected_red = rospy.get_param('~red_expected')
        seen = [m.data for m in red.all]
        self.assertTrue(seen, 'no /red_detected')
        if expected_red:
            self.assertTrue(any(seen), 'red never detected')
        else:
            self.assertFalse(any(seen), 'red detected in a world without red')


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'loop_stop', LoopStop)
