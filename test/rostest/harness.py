"""Shared helpers for closed_loop's black-box rostest nodes: wait for topics, read ground truth, drive."""
import math
import os
import threading
import time

import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from std_msgs.msg import UInt32

from closed_loop.batch.judge import Judge, JudgeSettings
from closed_loop.geometry import quaternion_yaw
from closed_loop.nodes.scenario_judge import COMMAND_FRESH_S

# Bounds that only catch hangs; behaviour is asserted on values, not on wall-clock time.
WAIT_FOR_TOPIC_S = 30.0
#: At rest at an instant, as the judge of every episode has it (closed_loop.batch.judge): under this speed (m/s).
REST_SPEED_MPS = JudgeSettings().rest_speed


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
        with self._lock:
            msg = self.msg
        header = getattr(msg, 'header', None)
        last = ('no message at all' if msg is None else
                'the last stamped %.3f s' % header.stamp.to_sec() if header is not None else 'the last did not match')
        raise AssertionError('no %s on %s within %g s (%s, simulated time now %.3f s)' % (
            'matching message' if predicate else 'message', self.sub.name, timeout_s, last, rospy.get_time()))


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


class Judged:
    """The judge of every episode and scenario (``closed_loop.batch.judge``) watching this graph from now on, so
    that "came to rest" in a rostest is what it is in every verdict: ground truth under the judge's rest speed and
    yaw rate, under a zero command, for its ``rest_hold``, after the robot was told to move (a command other than
    zero since this watch began). ``namespace``: a robot's of a world of several (``/r1/``)."""

    def __init__(self, namespace=''):
        self._lock = threading.Lock()
        self.judge = Judge(JudgeSettings(time_limit=1e9, end_at_rest=True, first_command_wait=1e9), None)
        self._command = None
        self._truth = None
        rospy.Subscriber(namespace + 'cmd_vel', Twist, self._on_command, queue_size=10)
        rospy.Subscriber(namespace + 'base_pose_ground_truth', Odometry, self._on_truth, queue_size=50)

    def _on_command(self, msg):
        with self._lock:
            self._command = (msg.linear.x, msg.angular.z, rospy.get_time())
            self.judge.on_command((msg.linear.x, msg.angular.z))

    def _on_truth(self, msg):
        t = msg.header.stamp.to_sec()
        with self._lock:
            self._truth = msg
            if self.judge.due(t):
                c = self._command
                command = c[:2] if c is not None and t - c[2] <= COMMAND_FRESH_S else None
                p, q = msg.pose.pose.position, msg.pose.pose.orientation
                self.judge.observe(t, p.x, p.y, quaternion_yaw((q.x, q.y, q.z, q.w)), msg.twist.twist.linear.x,
                                   msg.twist.twist.angular.z, command)

    def rest(self, timeout_s=WAIT_FOR_TOPIC_S):
        """Wait until the judge says the robot came to rest; its verdict (``time_s``: when it came to rest,
        ``final_pose``: ground truth then). ``timeout_s``: wall time, a bound that catches hangs."""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not rospy.is_shutdown():
            with self._lock:
                if self.judge.ended:
                    p, q = self._truth.pose.pose.position, self._truth.pose.pose.orientation
                    return self.judge.verdict(self._truth.header.stamp.to_sec(),
                                              (p.x, p.y, quaternion_yaw((q.x, q.y, q.z, q.w))))
            time.sleep(0.02)
        raise AssertionError('the robot did not come to rest, as the judge has it, within %g s' % timeout_s)
