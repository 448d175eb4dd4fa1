#!/usr/bin/env python3
"""In red_box, vision_node sees the red box in the simulator's camera: /red_detected true, with a centroid
near the image's middle column (the box is centred on the robot's path) and a growing area as it nears."""
import os
import sys
import unittest

import rospy
import rostest
from geometry_msgs.msg import PointStamped
from sensor_msgs.msg import CameraInfo
from std_msgs.msg import Bool, UInt32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

CENTRE_TOLERANCE_PX = 15.0


class VisionInLoop(unittest.TestCase):
    def test_red_box_is_seen(self):
        rospy.init_node('vision_in_loop_test')
        info = harness.Latest('camera/camera_info', CameraInfo).wait()
        detected = harness.Latest('red_detected', Bool, keep_all=True)
        centroid = harness.Latest('red_centroid', PointStamped, keep_all=True)
        area = harness.Latest('red_area', UInt32, keep_all=True)
        detected.wait(predicate=lambda m: m.data)
        harness.sim_sleep(3.0)
        self.assertTrue(all(m.data for m in detected.all[-10:]), 'red not seen steadily')
        c = centroid.wait()
        self.assertAlmostEqual(c.point.x, info.K[2], delta=CENTRE_TOLERANCE_PX)
        areas = [m.data for m in area.all]
        self.assertGreater(areas[-1], areas[0], 'the box did not grow as the robot approached')


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'vision_in_loop', VisionInLoop)
