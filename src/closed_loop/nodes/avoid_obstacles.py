"""avoid_obstacles: the reactive navigator (logic in closed_loop.control.navigator) behind the usual topics."""
import math
import threading
import time

import rospy
import tf2_ros
from geometry_msgs.msg import Point, PoseStamped, Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan
from std_msgs.msg import ColorRGBA, String
from visualization_msgs.msg import Marker, MarkerArray

from closed_loop import robot_model
from closed_loop.control.decisions import SilenceWatchdog
from closed_loop.geometry import quaternion_yaw
from closed_loop.control.guard import scan_points
from closed_loop.control.local_planner import NavigatorError
from closed_loop.control.navigator import GoalSettings, Navigator, NavigatorSettings, in_danger, stale_input
from closed_loop.nodes.common import (LOG_PERIOD_S, LiveSettings, StopsOnShutdown, frame_id, init_node,
                                      load_settings, robot_geometry, stamp_to_sec)
from closed_loop.nodes.conversions import connected_publishers, message_callerid, scan_from_msg, twist
from closed_loop.control.scan import ScanError, validate_scan
from closed_loop.sources import SourceCheck


ODOM_FRAME = 'odom'
PLAN_COLOURS = {'goal': (0.1, 0.85, 0.2, 1.0), 'avoid': (1.0, 0.75, 0.0, 1.0), 'turn': (1.0, 0.75, 0.0, 1.0),
                'stop': (0.95, 0.1, 0.1, 1.0)}
SAFE_COLOUR, UNSAFE_COLOUR = (0.3, 0.6, 1.0, 0.8), (0.95, 0.1, 0.1, 0.5)
AIM_COLOUR = (0.6, 0.2, 0.9, 1.0)   # purple: no other display of the shipped rviz config uses it
TF_WAIT_S = 0.5


class AvoidObstacles(StopsOnShutdown):
    """Goes to a goal around obstacles, with the robot's footprint, or holds its start heading.

    The scan and odometry callbacks store; a timer on the ROS clock decides through
    :class:`closed_loop.control.navigator.Navigator` and publishes. A scan that makes the command being followed
    unsafe (its predicted path now comes within ``~safety_margin``) is acted on at once. A missing or
    stale scan or odometry (older than ``~scan_timeout``), a scan from a second publisher or in another
    frame than ``~scan_frame``, or no scan for ``~scan_timeout`` s of wall time (a dead simulator) means
    zero.

    Subscriptions: ``scan`` (sensor_msgs/LaserScan), ``odom`` (nav_msgs/Odometry: the pose in odom and the
    speeds), ``move_base_simple/goal`` (geometry_msgs/PoseStamped, as rviz's "2D Nav Goal" sends it; any
    frame TF can bring into odom).
    Publications: ``cmd_vel`` (geometry_msgs/Twist; zero on shutdown), ``~mode`` (std_msgs/String,
    latched: GOAL_SEEKING, AVOIDING, RECOVERING, REACHED or FAILED, ``closed_loop.control.navigator.NavState``),
    ``~plan`` (visualization_msgs/MarkerArray: the chosen arc, coloured by what it is, every candidate's
    end, blue if safe, red if not, and the point the arcs were scored toward), ``~goal``
    (geometry_msgs/PoseStamped, latched: the goal being followed, in odom).
    Parameters: :class:`closed_loop.control.navigator.NavigatorSettings` (limits, margins, weights; live with
    dynamic_reconfigure), ``~goal_distance`` (:class:`GoalSettings`), ``~goal_x`` and ``~goal_y`` (m, in
    odom: both or neither), ``robot_description`` (the footprint and the laser's pose).
    """

    def __init__(self):
        self.settings = s = load_settings(NavigatorSettings)
        self.goal_settings = load_settings(GoalSettings)
        self._goal_param = self._goal_from_params()
        self.footprint, self.laser_pose = robot_geometry(s.scan_frame, 'the navigator')
        self.odom_frame = frame_id(ODOM_FRAME)
        self.base_frame = frame_id(robot_model.BASE_FRAME)
        self.lock = threading.Lock()
        self.navigator = None      # made at the first odometry, which gives the start pose
        self.scan = None
        self.odom = None           # (x, y, yaw, v, w, stamp s)
        self.sent = (0.0, 0.0)
        self.mode = None
        self._closing = False
        self._started_wall = time.monotonic()
        self.cmd_pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        self.mode_pub = rospy.Publisher('~mode', String, queue_size=1, latch=True)
        self.plan_pub = rospy.Publisher('~plan', MarkerArray, queue_size=1)
        self.goal_pub = rospy.Publisher('~goal', PoseStamped, queue_size=1, latch=True)
        self._source = SourceCheck(rospy.resolve_name('scan'), frame_id(s.scan_frame))
        self._tf = tf2_ros.Buffer()
        self._tf_listener = tf2_ros.TransformListener(self._tf)
        self._watchdog = SilenceWatchdog(s.scan_timeout, min(1.0 / s.rate_hz, 0.5 * s.scan_timeout),
                                         self._on_silence)
        self._scan_sub = rospy.Subscriber('scan', LaserScan, self._on_scan, queue_size=1)
        self._odom_sub = rospy.Subscriber('odom', Odometry, self._on_odom, queue_size=1)
        self._goal_sub = rospy.Subscriber('move_base_simple/goal', PoseStamped, self._on_goal, queue_size=1)
        self._timer = rospy.Timer(rospy.Duration(1.0 / s.rate_hz), lambda _e: self.control(), reset=True)
        self._watchdog.start()
        self._live = LiveSettings(s, self._take_settings)
        rospy.on_shutdown(self._on_shutdown)

    def _goal_from_params(self):
        has_x, has_y = rospy.has_param('~goal_x'), rospy.has_param('~goal_y')
        if has_x != has_y:
            rospy.logfatal('%s: bad parameter: give both ~goal_x and ~goal_y, or neither', rospy.get_name())
            raise SystemExit(2)
        if not has_x:
            return None
        goal = rospy.get_param('~goal_x'), rospy.get_param('~goal_y')
        if not all(isinstance(g, (int, float)) and not isinstance(g, bool) and math.isfinite(g) for g in goal):
            rospy.logfatal('%s: bad parameter ~goal_x, ~goal_y: expected finite numbers (m), got %r'
                           % (rospy.get_name(), goal))
            raise SystemExit(2)
        return float(goal[0]), float(goal[1])

    def _take_settings(self, settings):
        with self.lock:
            self.settings = settings
            if self.navigator is not None:
                self.navigator.reconfigure(settings)

    # -- inputs: store (and act at once on new danger) ---------------------------------------------------------
    def _on_scan(self, msg):
        self._watchdog.kick()
        refused = self._source.observe(message_callerid(msg), msg.header.frame_id, time.monotonic(),
                                       connected_publishers(self._scan_sub))
        scan = None
        if refused is not None:
            rospy.logerr_throttle(LOG_PERIOD_S, 'scan refused, stopping: %s', refused)
        else:
            try:
                scan = scan_from_msg(msg)
                validate_scan(scan)
            except ScanError as error:
                rospy.logerr_throttle(LOG_PERIOD_S, 'scan rejected: %s', error)
                scan = None
        with self.lock:
            self.scan = scan
            urgent = scan is None or self._in_danger(scan)
        if urgent:
            self.control()

    def _in_danger(self, scan):
        """True if the command being followed is no longer safe on ``scan`` (lock held)."""
        return in_danger(self.sent, scan_points(scan, self.laser_pose), self.settings, self.footprint)

    def _on_odom(self, msg):
        p = msg.pose.pose
        q = p.orientation
        odom = (p.position.x, p.position.y, quaternion_yaw((q.x, q.y, q.z, q.w)), msg.twist.twist.linear.x,
                msg.twist.twist.angular.z, stamp_to_sec(msg.header.stamp))
        with self.lock:
            self.odom = odom
            if self.navigator is None and all(math.isfinite(value) for value in odom):
                self._start(odom)

    def _start(self, odom):
        """The navigator, from the first odometry: the start pose, and the goal (lock held)."""
        x, y, yaw = odom[:3]
        goal = self._goal_param
        if goal is None and self.goal_settings.goal_distance > 0:
            d = self.goal_settings.goal_distance
            goal = (x + d * math.cos(yaw), y + d * math.sin(yaw))
        self.navigator = self.make_navigator((x, y, yaw), goal)
        self._publish_goal(goal)
        rospy.loginfo('start at (%.2f, %.2f, %.2f rad) in %s; %s', x, y, yaw, self.odom_frame,
                      'goal (%.2f, %.2f)' % goal if goal is not None else 'no goal: holding the start heading')

    def make_navigator(self, start, goal):
        """The core this node drives (a subclass may drive another with the same interface)."""
        return Navigator(self.settings, start, goal, on_transition=self._on_transition)

    def after_step(self, step):
        """Called after each decision is sent (lock held); a subclass publishes more from it."""

    def _on_goal(self, msg):
        try:
            t = self._tf.lookup_transform(self.odom_frame, msg.header.frame_id or self.odom_frame,
                                          msg.header.stamp, rospy.Duration(TF_WAIT_S))
        except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as error:
            try:
                t = self._tf.lookup_transform(self.odom_frame, msg.header.frame_id, rospy.Time(0),
                                              rospy.Duration(TF_WAIT_S))
            except (tf2_ros.LookupException, tf2_ros.ConnectivityException,
                    tf2_ros.ExtrapolationException) as error2:
                rospy.logerr('goal ignored: cannot bring frame %r into %s: %s (%s)', msg.header.frame_id,
                             self.odom_frame, error2, error)
                return
        yaw = quaternion_yaw((t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
                              t.transform.rotation.w))
        px, py = msg.pose.position.x, msg.pose.position.y
        gx = t.transform.translation.x + math.cos(yaw) * px - math.sin(yaw) * py
        gy = t.transform.translation.y + math.sin(yaw) * px + math.cos(yaw) * py
        with self.lock:
            if self.navigator is None:
                rospy.logwarn('goal ignored: no odometry yet')
                return
            try:
                self.navigator.set_goal((gx, gy), rospy.Time.now().to_sec())
            except NavigatorError as error:
                rospy.logerr('goal ignored: %s', error)
                return
        self._publish_goal((gx, gy))
        rospy.loginfo('new goal (%.2f, %.2f) in %s (from %s)', gx, gy, self.odom_frame, msg.header.frame_id)

    def _publish_goal(self, goal):
        """The goal being followed on ``~goal`` (latched, in odom); none (holding the heading): not sent."""
        if goal is None:
            return
        msg = PoseStamped()
        msg.header.frame_id, msg.header.stamp = self.odom_frame, rospy.Time.now()
        msg.pose.position.x, msg.pose.position.y = goal
        msg.pose.orientation.w = 1.0
        self.goal_pub.publish(msg)

    # -- the one decision path --------------------------------------------------------------------------------
    def control(self):
        with self.lock:
            if self._closing:
                return
            now = rospy.Time.now().to_sec()
            problem = self._input_problem(now)
            if problem is not None:
                self._send(0.0, 0.0)
                # Before the first scan and odometry (for up to scan_timeout of wall time), waiting is start-up.
                if self.scan is not None or time.monotonic() - self._started_wall >= self.settings.scan_timeout:
                    rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped: %s', problem)
                return
            x, y, yaw, v, w, _stamp = self.odom
            try:
                step = self.navigator.update(now, (x, y, yaw), v, w, self.scan, self.laser_pose, self.footprint)
            except (NavigatorError, ScanError) as error:
                self._send(0.0, 0.0)
                rospy.logerr_throttle(LOG_PERIOD_S, 'stopped: %s', error)
                return
            self._send(step.linear_x, step.angular_z)
            self._publish_mode(step.state, step.reason)
            if step.plan is not None and self.plan_pub.get_num_connections() > 0:
                self.plan_pub.publish(self._plan_markers(step.plan))
            self.after_step(step)

    def _input_problem(self, now):
        s = self.settings
        if self.navigator is None or self.odom is None:
            return 'no odometry yet'
        if self.scan is None:
            return 'no usable scan'
        return stale_input(now, self.scan.stamp_s, self.odom[5], s.scan_timeout)

    def _send(self, v, w):
        self.cmd_pub.publish(twist(v, w))
        self.sent = (v, w)

    def _publish_mode(self, state, why):
        if state != self.mode:
            self.mode = state
            self.mode_pub.publish(String(data=state.name))

    def _on_transition(self, old, new, now_s, why):
        log = rospy.logwarn if new.name in ('RECOVERING', 'FAILED') else rospy.loginfo
        log('mode %s -> %s at %.2f s: %s', old.name, new.name, now_s, why)

    def _on_silence(self, silent_s):
        with self.lock:
            if self._closing:
                return
            self._send(0.0, 0.0)
        rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped: no scan received for %.2f s of wall time (scan_timeout '
                               '%.2f s)', silent_s, self.settings.scan_timeout)

    # -- what rviz shows ------------------------------------------------------------------------------------
    def _plan_markers(self, plan):
        stamp = rospy.Time.now()
        chosen = Marker(ns='chosen', id=0, type=Marker.LINE_STRIP, action=Marker.ADD)
        chosen.header.frame_id, chosen.header.stamp = self.base_frame, stamp
        chosen.pose.orientation.w = 1.0
        chosen.scale.x = 0.03
        chosen.color = ColorRGBA(*PLAN_COLOURS.get(plan.kind, PLAN_COLOURS['goal']))
        chosen.points = [Point(0.0, 0.0, 0.05)] + [Point(float(x), float(y), 0.05) for x, y, _ in plan.path]
        ends = Marker(ns='candidates', id=1, type=Marker.POINTS, action=Marker.ADD)
        ends.header = chosen.header
        ends.pose.orientation.w = 1.0
        ends.scale.x = ends.scale.y = 0.04
        s = self.settings
        for v, w, _clearance, safe in plan.candidates:
            # Where the candidate would take the robot in one horizon, drawn as a dot.
            if abs(w) < 1e-6:
                x, y = v * s.horizon, 0.0
            else:
                x, y = v / w * math.sin(w * s.horizon), v / w * (1.0 - math.cos(w * s.horizon))
            ends.points.append(Point(x, y, 0.05))
            ends.colors.append(ColorRGBA(*(SAFE_COLOUR if safe else UNSAFE_COLOUR)))
        # The point the arcs were scored toward: a way round the obstacles to the goal (closed_loop.control.wavefront).
        aim = Marker(ns='aim', id=2, type=Marker.SPHERE, action=Marker.ADD)
        aim.header = chosen.header
        aim.pose.position = Point(float(plan.aim_xy[0]), float(plan.aim_xy[1]), 0.05)
        aim.pose.orientation.w = 1.0
        aim.scale.x = aim.scale.y = aim.scale.z = 0.15
        aim.color = ColorRGBA(*AIM_COLOUR)
        return MarkerArray(markers=[chosen, ends, aim])


def main():
    init_node('avoid_obstacles')
    AvoidObstacles()
    rospy.spin()
