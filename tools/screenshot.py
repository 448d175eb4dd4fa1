#!/usr/bin/env python3
"""`make screenshot`: run demo.launch rviz:=true on a virtual screen (Xvfb) with its own master, wait until
the robot has driven, and save a screenshot of rviz to rviz/screenshot.png (shown in the README and the tutorial).

Usage (inside ``source env.sh``): python3 tools/screenshot.py [--world red_box] [--out rviz/screenshot.png]
[--port 11397] (its master's port)
"""
import argparse
import math
import os
import sys
import time

import cv2

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop import launcher, netenv  # noqa: E402
from closed_loop.nodes.screen import VirtualScreen  # noqa: E402

MASTER_PORT = 11397
MOVED_M = 1.6          # far enough for the slow zone and the camera to show the box large
WAIT_LIMIT_S = 90.0
RENDER_SETTLE_S = 3.0


def main():
    netenv.apply_loopback_defaults(os.environ)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--world', default='red_box')
    parser.add_argument('--out', default=os.path.join(ROOT, 'rviz', 'screenshot.png'))
    parser.add_argument('--port', type=int, default=MASTER_PORT, help="its own master's port")
    args = parser.parse_args()
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % args.port)
    os.environ.update(env)
    problem = launcher.master_problem(env['ROS_MASTER_URI'])
    if problem is not None:
        print('screenshot: %s; nothing started' % problem)
        return 1
    log_path = os.path.join(ROOT, 'test_output', 'screenshot.log')
    os.makedirs(os.path.dirname(log_path), exist_ok=True)
    with VirtualScreen() as screen, open(log_path, 'w') as log:
        env['DISPLAY'] = screen.display
        launch = launcher.Launch(['-p', str(args.port), 'closed_loop', 'demo.launch', 'world:=' + args.world,
                                  'rviz:=true'], log, env)
        try:
            import rospy
            from nav_msgs.msg import Odometry
            from closed_loop.nodes.common import join_launch
            deadline = time.monotonic() + WAIT_LIMIT_S
            if not join_launch('screenshot', launch, WAIT_LIMIT_S):
                print(launcher.early_end_report('screenshot', launch, log_path) if launch.poll() is not None
                      else 'screenshot: no master within %.0f s; see %s' % (WAIT_LIMIT_S, log_path))
                return 1
            while True:
                try:
                    msg = rospy.wait_for_message('/base_pose_ground_truth', Odometry, timeout=WAIT_LIMIT_S)
                except rospy.ROSException:      # rospy.ROSInterruptException too
                    # The launch ended (join_launch shut the node down), or no ground truth came in time.
                    print(launcher.early_end_report('screenshot', launch, log_path) if launch.poll() is not None
                          else 'screenshot: no /base_pose_ground_truth within %.0f s; see %s' % (WAIT_LIMIT_S,
                                                                                                 log_path))
                    return 1
                p = msg.pose.pose.position
                if math.hypot(p.x, p.y) > MOVED_M or time.monotonic() > deadline:
                    break
            time.sleep(RENDER_SETTLE_S)
            rgb = screen.screenshot()
        finally:
            launch.end()
    cv2.imwrite(args.out, cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    print('screenshot: %s (%dx%d)' % (os.path.relpath(args.out, ROOT), rgb.shape[1], rgb.shape[0]))
    return 0


if __name__ == '__main__':
    sys.exit(main())
