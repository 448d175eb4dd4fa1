"""cmd_vel_guard: a safety filter between any controller and the base (logic in closed_loop.control.guard)."""
import threading
import time

import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String

from closed_loop.watchdog import SilenceWatchdog
from closed_loop.control.guard import GuardSettings, GuardVerdict, filter_command, scan_problem
from closed_loop.control.scan import scan_points
from closed_loop.nodes.common import (LiveSettings, Publisher, StopsOnShutdown, clock_held, frame_id,
                                      init_node, load_settings, robot_geometry)
from closed_loop.nodes.conversions import (connected_publishers, message_callerid, scan_from_msg, twist)
from closed_loop.control.scan import ScanError
from closed_loop.sources import SourceCheck



class CmdVelGuard(StopsOnShutdown):
    """Vetoes or slows any command whose predicted path brings the footprint within a margin of the scan.

    The footprint is the rectangle around the collision shapes of ``robot_description`` (the URDF on the
    parameter server), and the laser's pose in it comes from the same URDF (``~scan_frame``). Each command
    is checked against the newest scan as it arrives and passed on at once, whole, scaled down (keeping
    its curvature) or replaced by zero; a new scan that makes the current command less safe is acted on
    at once too. Zero goes out, with a throttled error, while the scan is missing, stale, refused (a
    second publisher, a wrong frame) or silent on the wall clock (a dead simulator), while the input
    command is stale, when two nodes publish input commands, and on shutdown.

    Subscriptions:
        ``cmd_vel_in`` (geometry_msgs/Twist): the controller's command (remap it there).
        ``scan`` (sensor_msgs/LaserScan), ``odom`` (nav_msgs/Odometry: the current speed; without it the
        last command sent is taken as the speed).
    Publications:
        ``cmd_vel`` (geometry_msgs/Twist): the guarded command, for the base.
        ``~verdict`` (std_msgs/String, latched): PASS, SLOWED or VETOED, on every change (logged with why).
    Parameters: see :class:`closed_loop.control.guard.GuardSettings` (``~safety_margin`` m, ``~reaction_time`` s,
        ``~braking_decel`` m/s^2, ``~angular_decel`` rad/s^2, ``~rate_hz``, ``~scan_timeout`` s,
        ``~cmd_timeout`` s, ``~scan_frame``); ``robot_description`` (URDF text, required). The margin,
        reaction time and decelerations are live (dynamic_reconfigure).
    """

    def __init__(self):
        self.settings = s = load_settings(GuardSettings)
        self.footprint, self.laser_pose = robot_geometry(s.scan_frame, 'the guard')
        rospy.loginfo('footprint x %.3f..%.3f m, y %.3f..%.3f m; safety_margin %.2f m',
                      self.footprint.x_min, self.footprint.x_max, self.footprint.y_min,
                      self.footprint.y_max, s.safety_margin)
        self.lock = threading.Lock()
        self._cmd = None          # (linear_x, angular_z, ROS time s) of the newest input command
        self._scan = None         # (Scan, points) of the newest usable scan
        self._scan_refused = None  # why the newest scan was refused, if it was
        self._odom = None         # (linear_x, angular_z, ROS time s)
        self._sent = (0.0, 0.0)
        self._verdict = None
        self._closing = False
        self.cmd_pub = Publisher('cmd_vel', Twist, queue_size=1)
        self.verdict_pub = Publisher('~verdict', String, queue_size=1, latch=True)
        self._scan_source = SourceCheck(rospy.resolve_name('scan'), frame_id(s.scan_frame))
        self._cmd_source = SourceCheck(rospy.resolve_name('cmd_vel_in'))
        self._watchdog = SilenceWatchdog(s.scan_timeout, 1.0 / s.rate_hz, self._on_silence)
        self._scan_sub = rospy.Subscriber('scan', LaserScan, self._on_scan, queue_size=1, tcp_nodelay=True)
        self._odom_sub = rospy.Subscriber('odom', Odometry, self._on_odom, queue_size=1, tcp_nodelay=True)
        self._cmd_sub = rospy.Subscriber('cmd_vel_in', Twist, self._on_cmd, queue_size=1, tcp_nodelay=True)
        self._timer = rospy.Timer(rospy.Duration(1.0 / s.rate_hz), lambda _e: self._tick(), reset=True)
        if not clock_held():         # (in lockstep, wall time says nothing of the input's age)
            self._watchdog.start()
        self._live = LiveSettings(s, self._take_settings)
        rospy.on_shutdown(self._on_shutdown)

    def _take_settings(self, settings):
        # From dynamic_reconfigure: the next command or scan is judged by the new values.
        with self.lock:
            self.settings = settings

    # -- inputs ------------------------------------------------------------------------------------------
    def _on_scan(self, msg):
        self._watchdog.kick()
        refused = self._scan_source.observe(message_callerid(msg), msg.header.frame_id, time.monotonic(),
                                            connected_publishers(self._scan_sub))
        entry = None
        if refused is None:
            try:
                scan = scan_from_msg(msg)
                entry = (scan, scan_points(scan, self.laser_pose))
            except ScanError as error:
                refused = 'scan rejected: %s' % error
        with self.lock:
            self._scan, self._scan_refused = entry, refused
            self._decide(only_if_stricter=True)

    def _on_odom(self, msg):
        with self.lock:
            self._odom = (msg.twist.twist.linear.x, msg.twist.twist.angular.z, rospy.Time.now().to_sec())

    def _on_cmd(self, msg):
        conflict = self._cmd_source.observe(message_callerid(msg), None, time.monotonic(),
                                            connected_publishers(self._cmd_sub))
        with self.lock:
            self._cmd = (msg.linear.x, msg.angular.z, rospy.Time.now().to_sec(), conflict)
            self._decide(only_if_stricter=False)

    def _tick(self):
        with self.lock:
            self._decide(only_if_stricter=True)

    def _on_silence(self, silent_s):
        if self._scan is None and self._scan_refused is None:
            return            # no scan yet, so nothing passed yet (as the controller node: see there)
        with self.lock:
            if not self._closing:
                self._send(0.0, 0.0, GuardVerdict.VETOED, 'no scan received for %.2f s of wall time '
                           '(scan_timeout %.2f s)' % (silent_s, self.settings.scan_timeout))

    # -- the one decision path (lock held) ---------------------------------------------------------------
    def _decide(self, only_if_stricter):
        if self._closing or self._cmd is None:
            return
        s = self.settings
        now = rospy.Time.now().to_sec()
        v_cmd, w_cmd, cmd_t, conflict = self._cmd
        if conflict is not None:
            result = (0.0, 0.0, GuardVerdict.VETOED, conflict)
        elif now - cmd_t > s.cmd_timeout or now < cmd_t - s.cmd_timeout:
            result = (0.0, 0.0, GuardVerdict.VETOED, 'input command is %.2f s old (cmd_timeout %.2f s)'
                      % (now - cmd_t, s.cmd_timeout))
        elif self._scan_refused is not None:
            result = (0.0, 0.0, GuardVerdict.VETOED, self._scan_refused)
        else:
            scan = self._scan[0] if self._scan is not None else None
            problem = scan_problem(scan, None if scan is None else now - scan.stamp_s, s.scan_timeout)
            if problem is not None:
                result = (0.0, 0.0, GuardVerdict.VETOED, problem)
            else:
                v0, w0 = self._sent
                if self._odom is not None and abs(now - self._odom[2]) <= s.scan_timeout:
                    v0, w0 = self._odom[0], self._odom[1]
                r = filter_command(self._scan[1], self.footprint, v0, w0, v_cmd, w_cmd, s)
                result = (r.linear_x, r.angular_z, r.verdict, r.reason)
        v, w, verdict, reason = result
        if only_if_stricter and not (self._verdict is None or verdict > self._verdict
                                     or abs(v) < abs(self._sent[0]) - 1e-6 or abs(w) < abs(self._sent[1]) - 1e-6):
            return
        self._send(v, w, verdict, reason)

    def _send(self, v, w, verdict, reason):
        self.cmd_pub.publish(twist(v, w))
        self._sent = (v, w)
        # Each verdict is logged once, on entry, with its reason: a robot held at a wall is a standing state.
        if verdict != self._verdict:
            log = rospy.loginfo if verdict == GuardVerdict.PASS else rospy.logwarn
            log('%s -> %s: %s', self._verdict.name if self._verdict is not None else '-', verdict.name, reason)
            self._verdict = verdict
            self.verdict_pub.publish(String(data=verdict.name))


def main():
    init_node('cmd_vel_guard')
    CmdVelGuard()
    rospy.spin()
