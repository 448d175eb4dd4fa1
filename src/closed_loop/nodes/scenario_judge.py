"""scenario_judge: the judge (``closed_loop.batch.judge``) in a ROS graph, watching the simulator's ground truth."""
import dataclasses
import json
import os
import tempfile
import threading

import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from std_msgs.msg import Float32, String, UInt32

from closed_loop.batch.judge import Judge, JudgeSettings, StartSettings
from closed_loop.geometry import quaternion_yaw
from closed_loop.nodes import graph_ready
from closed_loop.nodes.common import Publisher, goal_param, init_node, load_settings, stamp_to_sec
from closed_loop.sim.simulation import SimSettings

#: A command older than this (s, simulated) is no longer the base's: its watchdog has braked it to zero.
COMMAND_FRESH_S = SimSettings().cmd_vel_timeout


class ScenarioJudge:
    """Decides what the robot did in a scenario, by the rules of ``closed_loop.batch.judge`` (those of an
    in-process episode), on the simulator's ground truth and simulated time.

    Subscriptions: ``base_pose_ground_truth`` (nav_msgs/Odometry, frame world), ``contact_count``
    (std_msgs/UInt32), ``clearance`` (std_msgs/Float32), ``cmd_vel`` (geometry_msgs/Twist: what the base is
    told), ``mode`` (std_msgs/String, optional: remap it to the controller's ``~mode``; REACHED and
    FAILED are honoured), and ``missed_ticks`` (std_msgs/UInt32: a lockstepped simulator's count of instants it
    went on without a node, scenario.launch's ``/sim/missed_ticks``; in the verdict).
    Publications: ``~verdict`` (std_msgs/String, latched): the verdict as JSON (outcome, mode, time_s,
    contacts, min_clearance_m, final_pose, goal_error_m, path_m, peak_decel_mps2, commands, why), once, when
    the scenario is over; the verdict's line is also logged.
    Parameters: :class:`closed_loop.batch.judge.JudgeSettings` and :class:`closed_loop.batch.judge.StartSettings`
    (with ``~unpause``, it starts the paused simulator once a node publishes ``cmd_vel`` and its connections
    are made: ``closed_loop.nodes.graph_ready``); ``~goal_x``,
    ``~goal_y`` (m, in the world frame: both or neither); ``~verdict_file`` (a path: the verdict's JSON is
    also written there, whole or not at all); ``~keep_track`` (bool: the verdict file also holds the track, a
    row per judged instant, and the contacts, for a picture of the scenario: ``closed_loop.batch.pictures``).
    """

    def __init__(self):
        self.settings = load_settings(JudgeSettings)
        self.goal = goal_param()
        self.verdict_file = rospy.get_param('~verdict_file', '')
        self.judge = Judge(self.settings, self.goal, keep_track=bool(rospy.get_param('~keep_track', False)))
        self.lock = threading.Lock()
        self.command = None          # (v, w, stamp s)
        self.contact_count = 0
        self.mode = None
        self.done = False
        self.verdict_pub = Publisher('~verdict', String, queue_size=1, latch=True)
        rospy.Subscriber('contact_count', UInt32, self._on_contacts, queue_size=10, tcp_nodelay=True)
        rospy.Subscriber('clearance', Float32, self._on_clearance, queue_size=10, tcp_nodelay=True)
        rospy.Subscriber('cmd_vel', Twist, self._on_command, queue_size=10, tcp_nodelay=True)
        rospy.Subscriber('mode', String, self._on_mode, queue_size=10, tcp_nodelay=True)
        self.missed_ticks = 0
        rospy.Subscriber('missed_ticks', UInt32, self._on_missed, queue_size=10, tcp_nodelay=True)
        rospy.Subscriber('base_pose_ground_truth', Odometry, self._on_truth, queue_size=50, tcp_nodelay=True)
        self.start = load_settings(StartSettings)
        if self.start.unpause:
            threading.Thread(target=graph_ready.start_when_ready, args=(self.start,), daemon=True).start()
        rospy.loginfo('judging: %s; time limit %.1f s', 'goal (%.2f, %.2f), success within %.2f m'
                      % (self.goal + (self.settings.success_radius,)) if self.goal else 'no goal',
                      self.settings.time_limit)

    def _on_contacts(self, msg):
        with self.lock:
            began, self.contact_count = msg.data - self.contact_count, msg.data
            if began > 0 and not self.done:
                self.judge.on_contact(rospy.Time.now().to_sec(), began)

    def _on_clearance(self, msg):
        with self.lock:
            self.judge.on_clearance(msg.data)

    def _on_command(self, msg):
        with self.lock:
            self.command = (msg.linear.x, msg.angular.z, rospy.Time.now().to_sec())
            if not self.judge.commands:
                rospy.loginfo('first command: linear.x %.3f m/s, angular.z %.3f rad/s', msg.linear.x, msg.angular.z)
            self.judge.on_command((msg.linear.x, msg.angular.z))

    def _on_missed(self, msg):
        with self.lock:
            self.missed_ticks = msg.data

    def _on_mode(self, msg):
        with self.lock:
            self.mode = msg.data

    def _on_truth(self, msg):
        t = stamp_to_sec(msg.header.stamp)
        p, twist = msg.pose.pose, msg.twist.twist
        q = p.orientation
        with self.lock:
            if self.done:
                return
            if self.judge.due(t):
                command = None
                if self.command is not None and t - self.command[2] <= COMMAND_FRESH_S:
                    command = self.command[:2]
                # nav_msgs/Odometry carries the twist in the child frame: linear.x is the forward speed.
                self.judge.observe(t, p.position.x, p.position.y, quaternion_yaw((q.x, q.y, q.z, q.w)),
                                   twist.linear.x, twist.angular.z, command, self.mode)
            if self.judge.ended:
                self._conclude(t, (p.position.x, p.position.y, quaternion_yaw((q.x, q.y, q.z, q.w))))

    def _conclude(self, t, pose):
        self.done = True
        verdict = self.judge.verdict(t, pose)
        if self.missed_ticks:
            verdict = dataclasses.replace(verdict, missed_ticks=self.missed_ticks, why='%s; %d instant%s missed (a node '
                                          'busy past the simulator\'s lockstep_timeout)' % (
                                              verdict.why, self.missed_ticks, '' if self.missed_ticks == 1 else 's'))
        text = json.dumps(verdict.to_dict())
        if self.verdict_file:
            whole = dict(verdict.to_dict(), **self.judge.track_dict()) if self.judge.track is not None else None
            write_whole(self.verdict_file, json.dumps(whole) if whole else text)
        self.verdict_pub.publish(String(data=text))
        (rospy.loginfo if verdict.outcome in ('reached', 'stopped') else rospy.logwarn)('verdict: %s', verdict.why)


def write_whole(path, text):
    """Write ``text`` to ``path`` whole or not at all (a temporary file beside it, then renamed)."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    with tempfile.NamedTemporaryFile('w', dir=folder, prefix='.verdict-', delete=False) as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(f.name, path)


def main():
    init_node('scenario_judge')
    ScenarioJudge()
    rospy.spin()
