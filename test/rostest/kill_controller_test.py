#!/usr/bin/env python3
"""Killing the controller outright (SIGKILL: no goodbye zero) while the robot drives: the simulator's
command watchdog brakes the robot to rest within cmd_vel_timeout plus braking, on ground truth.

The kill's instant in simulated time is pinned by pausing the simulator around it: this test's own view of the
clock lags the simulator's by however long it waited for a core, which on a loaded machine moved the deadline
earlier than the watchdog's (a robot at 5.2 mm/s, braking, judged moving). The pause holds simulated time for a
second or more of wall time, with no scan: kill_controller.test gives the controller its longest scan_timeout, so
that its own watchdog (wall time) does not stop the robot before the kill (a timer tick run late, in the pause, once
did: the test then saw the controller's stop, not the simulator's)."""
import os
import signal
import sys
import time
import unittest
import xmlrpc.client

import rosgraph
import rosnode
import rospy
import rostest
from std_srvs.srv import Empty

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.control.decisions import StopSettings  # noqa: E402
from closed_loop.sim.simulation import SimSettings  # noqa: E402

CMD_VEL_TIMEOUT_S = SimSettings().cmd_vel_timeout   # sim_node's defaults, from their one source
MAX_LINEAR_ACCEL_MPS2 = SimSettings().max_linear_accel
CONTROL_PERIOD_S = 1.0 / StopSettings().rate_hz  # the last command may be up to one period old at the kill
SLACK_S = 0.15
QUIET_WALL_S = 0.5  # no ground truth and no clock tick for this long: the paused simulator has said its last


def paused_at(truth):
    """Pauses the simulator and returns its simulated time, once everything it sent before the pause is heard."""
    rospy.ServiceProxy('/sim/pause_physics', Empty)()
    clock = None
    while True:
        time.sleep(QUIET_WALL_S)
        now = rospy.get_time()
        if now == clock and time.monotonic() - truth.received_wall > QUIET_WALL_S:
            return max(now, truth.msg.header.stamp.to_sec())
        clock = now


class KillController(unittest.TestCase):
    def test_watchdog_stops_the_robot(self):
        rospy.init_node('kill_controller_test')
        truth = harness.Latest('base_pose_ground_truth', harness.Odometry, keep_all=True)
        moving = truth.wait(predicate=lambda m: m.twist.twist.linear.x > 0.4)
        speed = moving.twist.twist.linear.x
        api = rosnode.get_api_uri(rosgraph.Master(rospy.get_name()), '/stop_on_obstacle')
        _, _, pid = xmlrpc.client.ServerProxy(api).getPid('/kill_controller_test')
        killed = paused_at(truth)
        os.kill(pid, signal.SIGKILL)
        rospy.ServiceProxy('/sim/unpause_physics', Empty)()
        harness.sim_sleep(2.0)
        deadline = killed + CMD_VEL_TIMEOUT_S + speed / MAX_LINEAR_ACCEL_MPS2 + SLACK_S
        after = [m for m in truth.all if m.header.stamp.to_sec() > deadline]
        self.assertTrue(after)
        for m in after:
            self.assertLess(abs(m.twist.twist.linear.x), harness.REST_SPEED_MPS,
                            'moving %.3f s after the kill' % (m.header.stamp.to_sec() - killed))
        # And not earlier than the watchdog allows: it kept the last command until the timeout.
        early = [m for m in truth.all if killed < m.header.stamp.to_sec() < killed + CMD_VEL_TIMEOUT_S - CONTROL_PERIOD_S]
        self.assertTrue(early and max(m.twist.twist.linear.x for m in early) > 0.4)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'kill_controller', KillController)
