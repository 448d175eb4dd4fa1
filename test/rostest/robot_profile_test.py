#!/usr/bin/env python3
"""A robot profile on the wire: the LaserScan layout and limits its LIDAR's published figures give, the
first ray where that LIDAR puts it, and the lesson's controller, unchanged, stopping at the wall (ground
truth, no contact). The expected figures are written out here, from the robots' data sheets, not read
from the profile under test."""
import math
import os
import sys
import unittest

import rospy
import rostest
from sensor_msgs.msg import LaserScan

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

# TurtleBot3 Burger's LDS-01; the Jackal's 270-degree front LIDAR.
EXPECTED = {
    'burger': dict(frame='base_scan', samples=360, angle_min=0.0, increment=2 * math.pi / 360,
                   range_min=0.12, range_max=3.5, scan_x=-0.032, front_x=0.038),
    'jackal': dict(frame='front_laser', samples=720, angle_min=-0.75 * math.pi, increment=1.5 * math.pi / 719,
                   range_min=0.1, range_max=30.0, scan_x=0.12, front_x=0.254),
}
WALL_FACE_X = 3.0  # worlds/wall.yaml: a 0.1 m wall centred at x = 3.05 m


class RobotProfile(unittest.TestCase):
    def test_scan_layout_and_stop_at_the_wall(self):
        rospy.init_node('robot_profile_test')
        robot = rospy.get_param('~robot')
        want = EXPECTED[robot]
        poses = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        scan = harness.Latest('scan', LaserScan).wait()
        self.assertEqual(scan.header.frame_id, want['frame'])
        self.assertEqual(len(scan.ranges), want['samples'])
        self.assertAlmostEqual(scan.angle_min, want['angle_min'], places=5)
        self.assertAlmostEqual(scan.angle_increment, want['increment'], places=5)
        self.assertAlmostEqual(scan.angle_max, want['angle_min'] + want['increment'] * (want['samples'] - 1), places=4)
        self.assertAlmostEqual(scan.range_min, want['range_min'], places=5)
        self.assertAlmostEqual(scan.range_max, want['range_max'], places=5)
        # The ray straight ahead (angle 0) sees the wall at its distance from the LIDAR, where the robot was
        # when the scan was taken (the controller may have set off already: judged on ground truth).
        poses.wait(predicate=lambda m: m.header.stamp >= scan.header.stamp)
        at_scan = min(poses.all, key=lambda m: abs((m.header.stamp - scan.header.stamp).to_sec()))
        ahead = int(round((0.0 - scan.angle_min) / scan.angle_increment))
        self.assertAlmostEqual(scan.ranges[ahead], WALL_FACE_X - at_scan.pose.pose.position.x - want['scan_x'],
                               delta=0.02)
        self.assertTrue(all(math.isinf(r) or want['range_min'] <= r <= want['range_max'] for r in scan.ranges))

        judged = harness.Judged()
        contacts = harness.contact_count_topic()
        verdict = judged.rest(timeout_s=60.0)
        self.assertGreater(verdict.final_pose[0], 1.0, verdict.why)
        rest_x = verdict.final_pose[0]
        front = rest_x + want['front_x']
        self.assertGreater(WALL_FACE_X - front, 0.1, 'the body stopped %.3f m from the wall' % (WALL_FACE_X - front))
        lidar_to_wall = WALL_FACE_X - (rest_x + want['scan_x'])
        self.assertLess(lidar_to_wall, 0.55, 'stopped %.2f m short of the stop zone' % lidar_to_wall)
        self.assertEqual(contacts.wait().data, 0)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'robot_profile', RobotProfile)
