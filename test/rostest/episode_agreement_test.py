#!/usr/bin/env python3
"""The real graph against the episode runner (closed_loop.batch.episode) in `wall`: for each of ~speeds, the graph's
stop_on_obstacle is set to cruise at that speed with no slow zone (slow_speed = cruise_speed) and a stop
distance of STOP_M, room to brake from 1 m/s. Each run starts as an episode does: the controller node is
killed and respawned (the launch file's respawn) with those settings on the parameter server, the world is
reset while it is down and physics paused until the simulator hears the new node, whose first decision is
taken on its first scan; once the robot has been at rest for REST_FOR_S its ground-truth x must be within
AGREE_M of the episode's of the same settings. Both are judged on ground truth.

(A run begun by a world reset under a running node would start at that node's next timer tick instead, whose phase
against the scans its start-up set: at 1 m/s the rest position then moves by up to a scan period's 10 cm.)"""
import os
import sys
import time
import unittest
import xmlrpc.client

import rosgraph
import rosnode
import rospy
import rostest
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
NODE = '/stop_on_obstacle'
RESPAWN_WITHIN_S = 30.0  # wall s for the killed node to be back (bounds a hang)
master = rosgraph.Master('/episode_agreement_test')


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

    def restart_controller(self, settings, sim):
        """The controller node restarted with ``settings`` as an episode's controller starts: physics paused, the
        node killed with the settings on the parameter server for its next start, the world reset while it is
        down, and physics going again once the launch has respawned it and the simulator takes its commands
        (an inbound cmd_vel connection from it), so that its first scan is the first after the pause."""
        for name, value in settings.items():
            rospy.set_param('%s/%s' % (NODE, name), value)
        sim('pause_physics')
        old_uri = master.lookupNode(NODE)
        rosnode.kill_nodes([NODE])
        deadline = time.monotonic() + RESPAWN_WITHIN_S
        while NODE in rosnode.get_node_names():
            self.assertLess(time.monotonic(), deadline, '%s still up after it was killed' % NODE)
            time.sleep(0.05)
        sim('reset_world')
        while not self.commands_reach_the_simulator(old_uri):
            self.assertLess(time.monotonic(), deadline, '%s not back, or not heard by the simulator' % NODE)
            time.sleep(0.05)
        sim('unpause_physics')

    @staticmethod
    def commands_reach_the_simulator(old_uri):
        """True once a new NODE is up and the simulator has an inbound cmd_vel connection from it."""
        try:
            uri = master.lookupNode(NODE)
            _, _, bus = xmlrpc.client.ServerProxy(master.lookupNode('/sim')).getBusInfo('/episode_agreement_test')
        except (rosgraph.MasterError, OSError):
            return False
        return uri != old_uri and any(c[1] == uri and c[2] == 'i' and c[4] == '/cmd_vel' and c[5] for c in bus)

    def test_stop_positions_agree(self):
        rospy.init_node('episode_agreement_test')
        speeds = rospy.get_param('~speeds')
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        contacts = harness.Latest('contact_count', UInt32)
        truth.wait()
        for name in ('reset_world', 'pause_physics', 'unpause_physics'):
            rospy.wait_for_service('/sim/' + name, timeout=30.0)

        def sim(name):
            rospy.ServiceProxy('/sim/' + name, Empty)()
        self.rest_x(truth, 0.0)          # the launch's own first run, at the defaults
        report = []
        for speed in speeds:
            settings = {'cruise_speed': speed, 'slow_speed': speed, 'stop_distance': STOP_M, 'slow_distance': SLOW_M}
            self.restart_controller(settings, sim)
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
