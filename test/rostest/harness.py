"""Shared helpers for closed_loop's black-box rostest nodes: wait for topics, read ground truth, drive."""
import math
import os
import threading
import time

import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from std_msgs.msg import UInt32

# Bounds that only catch hangs; behaviour is asserted on values, not on wall-clock time.
WAIT_FOR_TOPIC_S = 30.0


def output_dir(name):
    """A folder for a test's artefacts (screenshots, bags), under make test's test_output/."""
    base = os.environ.get('CLOSED_LOOP_TEST_OUTPUT') or os.path.join(os.getcwd(), 'test_output', name)
    os.makedirs(base, exist_ok=True)
    return base


class Latest:
    """Keeps the latest message of a topic (and optionally every message) with its arrival wall time."""

    def __init__(self, topic, msg_type, keep_all=False):
        self._lock = threading.Lock()
        self.msg = None
        self.received_wall = None
        self.all = [] if keep_all else None
        self.sub = rospy.Subscriber(topic, msg_type, self._on, queue_size=50)

    def _on(self, msg):
        with self._lock:
            self.msg = msg
            self.received_wall = time.monotonic()
            if self.all is not None:
                self.all.append(msg)

    def wait(self, timeout_s=WAIT_FOR_TOPIC_S, predicate=None):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not rospy.is_shutdown():
            with self._lock:
                msg = self.msg
            if msg is not None and (predicate is None or predicate(msg)):
                return msg
            time.sleep(0.01)
        raise AssertionError('no %s on %s within %g s' % ('matching message' if predicate else 'message',
                                                         self.sub.name, timeout_s))


class GroundTruth(Latest):
    def __init__(self):
        Latest.__init__(self, 'base_pose_ground_truth', Odometry)

    def xy(self):
        p = self.wait().pose.pose.position
        return p.x, p.y

    def speed(self):
        t = self.wait().twist.twist
        return math.hypot(t.linear.x, t.linear.y)


def twist(linear_x=0.0, angular_z=0.0):
    msg = Twist()
    msg.linear.x = linear_x
    msg.angular.z = angular_z
    return msg


def sim_sleep(seconds):
    """Sleep in simulated time (the test runs with use_sim_time)."""
    rospy.sleep(rospy.Duration.from_sec(seconds))


def contact_count_topic():
    return Latest('contact_count', UInt32)
