#!/usr/bin/env python3
"""avoid.launch in one world, judged on ground truth. Parameters: ~expect: 'reached' (REACHED, ground truth
within ~goal_radius_m of the goal, no contact), 'trapped' (ends RECOVERING or FAILED, at rest if FAILED, no
contact) or 'hold'; ~goal_x, ~goal_y (world frame, m): the goal expected (default ~goal_distance ahead of the
origin); ~send_goal: send that goal on move_base_simple/goal (frame world, as rviz's "2D Nav Goal" does)
once the robot is under way, and expect it followed; ~hold_after_x (m, optional): with no goal, once the
robot is ~passed_by_m (3 m) past this x its heading is within 10 degrees of the start heading, judged over
the next ~hold_window_m (0.5 m) of travel; ~limit_s: simulated seconds allowed; ~episode_world (a world
name, optional): run the same scenario (world, ~episode_robot, goal, the navigator's parameters as the graph
has them, limit) through the episode runner (closed_loop.batch.episode) too, and require the same outcome."""
import math
import os
import sys
import unittest

import rospy
import rostest
from geometry_msgs.msg import PoseStamped
from std_msgs.msg import String, UInt32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.batch.episode import EpisodeSpec, run_episode  # noqa: E402
from closed_loop.geometry import quaternion_yaw  # noqa: E402
from closed_loop.control.navigation.navigator import GoalSettings, NavigatorSettings, NavState  # noqa: E402

HOLD_TOLERANCE_RAD = math.radians(10.0)
PASSED_BY_M = 3.0
HOLD_WINDOW_M = 0.5
GOAL_RADIUS_M = 0.4


def _yaw(odometry):
    q = odometry.pose.pose.orientation
    return quaternion_yaw((q.x, q.y, q.z, q.w))


class Avoid(unittest.TestCase):
    def test_navigate(self):
        rospy.init_node('avoid_test')
        expect = rospy.get_param('~expect')
        limit_s = rospy.get_param('~limit_s', 60.0)
        hold_after_x = rospy.get_param('~hold_after_x', None)
        passed_by = rospy.get_param('~passed_by_m', PASSED_BY_M)
        window = rospy.get_param('~hold_window_m', HOLD_WINDOW_M)
        goal = (rospy.get_param('~goal_x', rospy.get_param('/avoid_obstacles/goal_distance', 10.0)),
                rospy.get_param('~goal_y', 0.0))
        send_goal = rospy.get_param('~send_goal', False)
        goal_pub = rospy.Publisher('move_base_simple/goal', PoseStamped, queue_size=1, latch=True)
        followed = harness.Latest('avoid_obstacles/goal', PoseStamped)
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        mode = harness.Latest('avoid_obstacles/mode', String, keep_all=True)
        contacts = harness.Latest('contact_count', UInt32)
        start = truth.wait().header.stamp.to_sec()
        final = {'reached': (NavState.REACHED.name,), 'trapped': (NavState.FAILED.name,), 'hold': ()}[expect]
        while not rospy.is_shutdown():
            m = truth.wait()
            if send_goal is True and followed.msg is not None and m.header.stamp.to_sec() - start > 1.0:
                send_goal = 'sent'   # once, under way, after the navigator's own default goal
                msg = PoseStamped()
                msg.header.frame_id, msg.header.stamp = 'world', rospy.Time(0)
                msg.pose.position.x, msg.pose.position.y = goal
                msg.pose.orientation.w = 1.0
                goal_pub.publish(msg)
            if m.header.stamp.to_sec() - start > limit_s:
                break
            if mode.msg is not None and mode.msg.data in final:
                break
            if hold_after_x is not None and m.pose.pose.position.x > hold_after_x + passed_by + window:
                break
            rospy.sleep(0.2)
        seen = [msg.data for msg in mode.all]
        self.assertEqual(contacts.wait().data, 0, 'contact; modes %s' % seen)
        p = truth.wait().pose.pose
        if expect == 'reached':
            self.assertEqual(seen[-1], NavState.REACHED.name, 'not reached within %g s: modes %s, at (%.2f, %.2f)'
                             % (limit_s, seen, p.position.x, p.position.y))
            self.assertIn(NavState.AVOIDING.name, seen)
            radius = rospy.get_param('~goal_radius_m', GOAL_RADIUS_M)
            self.assertLess(math.hypot(p.position.x - goal[0], p.position.y - goal[1]), radius,
                            'REACHED by odometry at (%.2f, %.2f), goal (%.2f, %.2f)' % (p.position.x, p.position.y,
                                                                                         goal[0], goal[1]))
            if send_goal:
                self.assertEqual(send_goal, 'sent', 'the navigator never published its goal')
                g = followed.wait().pose.position
                self.assertLess(math.hypot(g.x - goal[0], g.y - goal[1]), 0.05, 'the sent goal was not taken')
        elif expect == 'trapped':
            self.assertIn(seen[-1], (NavState.FAILED.name, NavState.RECOVERING.name), seen)
            self.assertIn(NavState.RECOVERING.name, seen)
            if seen[-1] == NavState.FAILED.name:
                harness.sim_sleep(1.0)
                self.assertLess(abs(truth.wait().twist.twist.linear.x), harness.REST_SPEED_MPS)
        if hold_after_x is not None:
            begin, end = hold_after_x + passed_by, hold_after_x + passed_by + window
            xs = [m.pose.pose.position.x for m in truth.all]
            self.assertTrue(any(x > end for x in xs), 'never got %g m past x = %g: at x = %.2f m, modes %s'
                            % (passed_by + window, hold_after_x, p.position.x, seen))
            last = next(i for i, x in enumerate(xs) if x > end)
            track = [(m.pose.pose.position.x, m.pose.pose.position.y, _yaw(m)) for m in truth.all[:last + 1]]
            where = ' '.join('(%.2f, %.2f, %.0f deg)' % (x, y, math.degrees(a)) for x, y, a in track[::10])
            for x, y, yaw in track:
                if x > begin:
                    self.assertLess(abs(yaw), HOLD_TOLERANCE_RAD, 'heading %.1f deg at x = %.2f m; track: %s'
                                    % (math.degrees(yaw), x, where))
            self.assertNotIn(NavState.REACHED.name, seen)
        world = rospy.get_param('~episode_world', None)
        if world is not None:
            self.agrees_with_episode(expect, world, goal, limit_s)

    def agrees_with_episode(self, expect, world, goal, limit_s):
        """The episode runner, given what the graph was given, ends the same way: REACHED within the goal
        radius; or trapped (RECOVERING, never REACHED); with no contact either way."""
        fields = {f for cls in (NavigatorSettings, GoalSettings) for f in cls.__dataclass_fields__}
        settings = {k: v for k, v in rospy.get_param('/avoid_obstacles', {}).items() if k in fields}
        result = run_episode(EpisodeSpec(world=world, robot=rospy.get_param('~episode_robot', 'closed_loop'),
                                         controller='avoid_obstacles', settings=settings,
                                         goal=goal if expect == 'reached' else None, time_limit_s=limit_s,
                                         keep_trajectory=True))
        modes = [row[7] for row in result.trajectory]
        rospy.loginfo('episode: %s, %s, %.1f s, modes seen %s', result.outcome, result.mode, result.time_s,
                      sorted(set(m for m in modes if m)))
        self.assertEqual(result.contacts, 0, 'the episode touched: %s' % result)
        if expect == 'reached':
            self.assertEqual(result.outcome, 'reached', 'the graph reached the goal, the episode: %s' % result)
        else:
            self.assertNotIn(NavState.REACHED.name, modes)
            self.assertIn(NavState.RECOVERING.name, modes, 'the graph was trapped, the episode: %s' % result)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'avoid', Avoid)
