#!/usr/bin/env python3
"""camera_info matches the rendered image: a known world point projects to where it is seen (2 px)."""
import math
import os
import sys
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from sensor_msgs.msg import CameraInfo, Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop import image_encoding  # noqa: E402

# test/worlds/camera_target.yaml: the centre of the red plate's front face, world frame (m).
TARGET_WORLD = np.array([1.995, 0.4, 0.35])
TOLERANCE_PX = 2.0
RED_MIN, OTHER_MAX = 150, 80


def rotate(q, v):
    """Rotate vector v by quaternion q = (x, y, z, w)."""
    x, y, z, w = q
    u = np.array([x, y, z])
    return v + 2.0 * np.cross(u, np.cross(u, v) + w * v)


def conjugate(q):
    return (-q[0], -q[1], -q[2], q[3])


class CameraProjection(unittest.TestCase):
    def test_known_point_projects_onto_its_image(self):
        rospy.init_node('sim_camera_test')
        buffer = tf2_ros.Buffer()
        tf2_ros.TransformListener(buffer)
        truth = harness.GroundTruth()
        info = harness.Latest('camera/camera_info', CameraInfo).wait()
        image = harness.Latest('camera/image_raw', Image).wait()
        self.assertEqual(image.header.frame_id, 'camera_optical_frame')
        self.assertEqual(info.header.frame_id, 'camera_optical_frame')
        self.assertEqual((info.width, info.height), (image.width, image.height))
        self.assertEqual(image.encoding, 'rgb8')
        self.assertEqual(image.step, image.width * 3)

        pose = truth.wait().pose.pose
        t = buffer.lookup_transform('camera_optical_frame', 'base_footprint', rospy.Time(0), rospy.Duration(20))
        q_world = (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w)
        in_base = rotate(conjugate(q_world), TARGET_WORLD - np.array([pose.position.x, pose.position.y,
                                                                       pose.position.z]))
        r = t.transform.rotation
        tr = t.transform.translation
        in_camera = rotate((r.x, r.y, r.z, r.w), in_base) + np.array([tr.x, tr.y, tr.z])
        self.assertGreater(in_camera[2], 0.0, 'target behind the camera: %s' % in_camera)
        fx, cx, fy, cy = info.K[0], info.K[2], info.K[4], info.K[5]
        u = fx * in_camera[0] / in_camera[2] + cx
        v = fy * in_camera[1] / in_camera[2] + cy

        rgb = image_encoding.image_to_array(image.encoding, image.height, image.width, image.step,
                                            bytes(image.data))
        red = (rgb[:, :, 0] > RED_MIN) & (rgb[:, :, 1] < OTHER_MAX) & (rgb[:, :, 2] < OTHER_MAX)
        rows, cols = np.nonzero(red)
        self.assertGreater(len(rows), 20, 'the red target is not in the image')
        seen_u, seen_v = cols.mean(), rows.mean()
        # Off-axis on purpose (the target is to the robot's left: u below cx), so a sign error shows.
        self.assertLess(u, cx - 20)
        self.assertLess(math.hypot(seen_u - u, seen_v - v), TOLERANCE_PX,
                        'projected (%.1f, %.1f), seen (%.1f, %.1f)' % (u, v, seen_u, seen_v))


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'sim_camera', CameraProjection)
