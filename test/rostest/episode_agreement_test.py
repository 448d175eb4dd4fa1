#!/usr/bin/env python3
"""The real graph against the episode runner (closed_loop.batch.episode) in `wall`: for each of ~speeds, the graph's
stop_on_obstacle is set to cruise at that speed with no slow zone (slow_speed = cruise_speed) and a stop
distance of STOP_M, room to brake from 1 m/s (through dynamic_reconfigure), the world is reset, and once the robot has been at rest for REST_FOR_S its ground-truth
x must be within AGREE_M of the episode's of the same settings. Both are judged on ground truth."""
import os
import sys
import unittest

import rospy
import rostest
from dynamic_reconfigure.client import Client
from std_msgs.msg import UInt32
from std_srvs.srv import Empty

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402

AGREE_M = 0.03
STOP_M, SLOW_M = 0.8, 1.2
AT_REST_MPS = 0.005
REST_FOR_S = 1.0
MOVED_X_M = 1.0
RUN_LIMIT_S = 30.0       # simulated s a run may take to come to rest (bounds a hang)


class EpisodeAgreement(unittest.TestCase):
    def rest_x(self, truth, after_s):
        """The ground-truth x once the robot, having moved past MOVED_X_M after ``after_s``, has been at rest
        for REST_FOR_S."""
        deadline = after_s + RUN_LIMIT_S
        while not rospy.is_shutdown():
            harness.sim_sleep(0.2)
            log = [m for m in truth.all if m.header.stamp.to_sec() > after_s]
            if not log:
                continue
            end = log[-1].header.stamp.to_sec()
            self.assertLess(end, deadline, 'not at rest %g s after the reset' % RUN_LIMIT_S)
            if not any(m.pose.pose.position.x > MOVED_X_M for m in log):
                continue
            recent = [m for m in log if m.header.stamp.to_sec() > end - REST_FOR_S]
            if end - log[0].header.stamp.to_sec() > REST_FOR_S and \
                    all(abs(m.twist.twist.linear.x) < AT_REST_MPS for m in recent):
                return log[-1].pose.pose.position.x

    def test_stop_positions_agree(self):
        rospy.init_node('episode_agreement_test')
        speeds = rospy.get_param('~speeds')
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        contacts = harness.Latest('contact_count', UInt32)
        truth.wait()
        client = Client('/stop_on_obstacle', timeout=30.0)
        rospy.wait_for_service('/sim/reset_world', timeout=30.0)
        reset = rospy.ServiceProxy('/sim/reset_world', Empty)
        self.rest_x(truth, 0.0)          # the launch's own first run, at the defaults
        report = []
        for speed in speeds:
            settings = {'cruise_speed': speed, 'slow_speed': speed, 'stop_distance': STOP_M, 'slow_distance': SLOW_M}
            client.update_configuration(settings)
            harness.sim_sleep(0.5)
            reset()
            graph_x = self.rest_x(truth, rospy.get_time())
            result = run_episode(EpisodeSpec(world='wall', controller='stop_on_obstacle', time_limit_s=RUN_LIMIT_S,
                                             settings=settings,
                                             keep_trajectory=True))
            self.assertEqual(result.outcome, 'stopped', '%s; last ticks %s' % (result, result.trajectory[-40::4]))
            report.append('%.1f m/s: graph %.4f m, episode %.4f m' % (speed, graph_x, result.final_pose[0]))
            print('agreement: %s' % report[-1], flush=True)
            self.assertLess(abs(graph_x - result.final_pose[0]), AGREE_M, '; '.join(report))
        self.assertEqual(contacts.wait().data, 0)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'episode_agreement', EpisodeAgreement)
