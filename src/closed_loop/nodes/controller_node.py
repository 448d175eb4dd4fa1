"""The controller node: one ROS host for every controller core (``closed_loop.controllers``).

``rosrun closed_loop stop_on_obstacle`` (and each shipped controller's script) is this node driving that
core; the episode runner drives the same core without ROS, so the graph and a batch episode agree by
construction.
"""
import math
import threading
import time

import rospy
import tf2_ros
from geometry_msgs.msg import PointStamped, PoseStamped, Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, LaserScan
from std_msgs.msg import String

from closed_loop import robot_model
from closed_loop.commands import CommandError
from closed_loop.controllers import STOP, Context, ControllerError, Log, Odom, controller_class
from closed_loop.geometry import Pose2D, quaternion_yaw
from closed_loop.nodes.common import (LOG_PERIOD_S, LiveSettings, Publisher, StopsOnShutdown, clock_held,
                                      frame_id, goal_param, init_node, load_settings, robot_geometry, stamp_to_sec)
from closed_loop.nodes.conversions import connected_publishers, message_callerid, scan_from_msg, twist
from closed_loop.nodes.drawing_messages import PUBLICATIONS, to_message
from closed_loop.sources import SourceCheck
from closed_loop.watchdog import SilenceWatchdog

ODOM_FRAME = 'odom'
#: How long a goal's transform into odom is waited for (s of ROS time).
GOAL_WAIT_S = 2.0


class RosLog(Log):
    """A core's log lines into rospy's log; errors (a bad scan, at the scan's rate) at most once per
    LOG_PERIOD_S for each kind of line."""

    def __init__(self):
        self._last = {}

    def info(self, text):
        rospy.loginfo(text)

    def warn(self, text):
        rospy.logwarn(text)

    def error(self, text):
        key = text.split(':')[0]
        now = time.monotonic()
        if now - self._last.get(key, -math.inf) >= LOG_PERIOD_S:
            self._last[key] = now
            rospy.logerr(text)


class ControllerNode(StopsOnShutdown):
    """Drives a controller core behind the topics of a ROS controller.

    Subscriptions: ``scan`` (sensor_msgs/LaserScan; taken only from one publisher and in ``~scan_frame``: while
    a second node publishes on ``scan``, or a scan comes in another frame, every scan is refused, an error
    names the publishers, and the core sees no scan, so it stops). For a core that uses them: ``odom``
    (nav_msgs/Odometry), ``move_base_simple/goal`` (geometry_msgs/PoseStamped, as rviz's "2D Nav Goal" sends
    it, in any frame TF brings into odom), ``red_centroid`` (geometry_msgs/PointStamped from vision_node) and
    ``camera/camera_info`` (sensor_msgs/CameraInfo).

    Publications: ``cmd_vel`` (geometry_msgs/Twist): the core's command from each tick of a timer on the ROS
    clock (``1 / ~rate_hz``), at once where a scan brings new danger, zero from the wall-clock watchdog (no
    scan for ``~scan_timeout`` s: a dead simulator stops ``/clock`` and with it the timer) and on shutdown.
    ``~mode`` (std_msgs/String, latched): the core's mode, on every change, each logged once with why (as a
    warning for the modes the core names). The core's drawings, each on ``~NAME`` (``~window``, ``~map``,
    ``~tracks``: visualization_msgs/MarkerArray; ``~plan``: nav_msgs/Path; ``~belief``: std_msgs/String, JSON; ``~goal``: geometry_msgs/PoseStamped, latched), built only while
    someone listens.

    Parameters: the core's settings classes, each field a ``~parameter`` (docs/nodes.md), the live ones
    served by dynamic_reconfigure (``dynparam set /NODE NAME VALUE``; a change the settings class refuses is
    refused with the reason); for a core that takes a goal, ``~goal_x`` and ``~goal_y`` (m, in odom: both or
    neither); ``robot_description`` (the laser's and the camera's pose, and the footprint).
    """

    def __init__(self, cls):
        self.cls = cls
        self.settings = load_settings(cls.settings_class)
        extras = [load_settings(c) for c in cls.extra_settings_classes]
        goal = goal_param() if cls.uses_goal else None
        self.frames = {'base': frame_id(robot_model.BASE_FRAME), 'odom': frame_id(ODOM_FRAME)}
        self.lock = threading.Lock()
        self.odom = None
        self._closing = False
        self._scan_seen = False
        self._started_wall = time.monotonic()
        self.core = cls(self.settings, self._context(goal), *extras)
        self.cmd_pub = Publisher('cmd_vel', Twist, queue_size=1)
        self._mode_pub = Publisher('~mode', String, queue_size=1, latch=True)
        self._outputs = {}
        for name, kind in cls.outputs.items():
            msg_type, latched = PUBLICATIONS[kind]
            self._outputs[name] = (Publisher('~' + name, msg_type, queue_size=1, latch=latched), latched)
        self._report()
        self._source = SourceCheck(rospy.resolve_name('scan'), frame_id(self.settings.scan_frame))
        self._watchdog = SilenceWatchdog(self.settings.scan_timeout, self.settings.watchdog_period_s,
                                         self._on_silence)
        self._scan_sub = rospy.Subscriber('scan', LaserScan, self._on_scan, queue_size=1, tcp_nodelay=True)
        if cls.uses_odom:
            rospy.Subscriber('odom', Odometry, self._on_odom, queue_size=1, tcp_nodelay=True)
        self._tf = None          # made at the first goal (listening to /tf costs every node's TF message)
        self._goal_msg = None     # (PoseStamped, when it came) of a goal not yet brought into odom
        if cls.uses_goal:
            rospy.Subscriber('move_base_simple/goal', PoseStamped, self._on_goal, queue_size=1, tcp_nodelay=True)
        if cls.uses_camera:
            rospy.Subscriber('camera/camera_info', CameraInfo, self._on_camera_info, queue_size=1,
                             tcp_nodelay=True)
            rospy.Subscriber('red_centroid', PointStamped, self._on_red, queue_size=1, tcp_nodelay=True)
        # reset=True: a ROS clock that jumps back (sim restart) restarts the timer instead of killing its thread.
        self._timer = rospy.Timer(rospy.Duration(1.0 / self.settings.rate_hz), lambda _e: self._tick(), reset=True)
        if not clock_held():         # (in lockstep, wall time says nothing of the input's age)
            self._watchdog.start()
        self._live = LiveSettings(self.settings, self._take_settings)
        rospy.on_shutdown(self._on_shutdown)

    # -- start-up ---------------------------------------------------------------------------------------------------
    def _context(self, goal):
        scan_frame = self.settings.scan_frame
        if self.cls.needs_footprint:
            footprint, laser_pose = robot_geometry(scan_frame, self.cls.name)
        else:
            footprint, laser_pose = None, Pose2D(0.0, 0.0, 0.0)
            urdf = rospy.get_param('robot_description', None)
            try:
                if not isinstance(urdf, str) or not urdf.strip():
                    raise robot_model.RobotModelError('no robot_description')
                laser_pose = robot_model.frame_pose_2d(urdf, scan_frame)
                footprint = robot_model.footprint(urdf)
            except robot_model.RobotModelError as error:
                rospy.logwarn('taking 0 rad as forward in frame %r: %s', scan_frame, error)
        camera_pose = None
        if self.cls.uses_camera:
            try:
                camera_pose = robot_model.frame_pose_2d(rospy.get_param('robot_description', ''),
                                                        robot_model.CAMERA_FRAME)
            except robot_model.RobotModelError:
                rospy.loginfo("no %s in robot_description: the belief is the LIDAR's alone",
                              robot_model.CAMERA_FRAME)
        return Context(laser_pose, footprint, goal, camera_pose, RosLog())

    def _take_settings(self, settings):
        # From dynamic_reconfigure: the next scan and the next tick decide with the new values.
        with self.lock:
            self.settings = settings
            self.core.reconfigure(settings)

    # -- inputs: store, and let the core decide ---------------------------------------------------------------------
    def _now(self):
        return rospy.Time.now().to_sec()

    def _on_scan(self, msg):
        self._watchdog.kick()
        self._scan_seen = True
        refused = self._source.observe(message_callerid(msg), msg.header.frame_id, time.monotonic(),
                                       connected_publishers(self._scan_sub))
        if refused is not None:
            rospy.logerr_throttle(LOG_PERIOD_S, 'scan refused, stopping: %s', refused)
        scan = None if refused is not None else scan_from_msg(msg)
        with self.lock:
            if not self._closing:
                self._send(self.core.on_scan(self._now(), scan, self.odom))

    def _on_odom(self, msg):
        p, t = msg.pose.pose, msg.twist.twist
        q = p.orientation
        odom = Odom(p.position.x, p.position.y, quaternion_yaw((q.x, q.y, q.z, q.w)), t.linear.x, t.angular.z,
                    stamp_to_sec(msg.header.stamp))
        with self.lock:
            self.odom = odom

    def _tick(self):
        if self._goal_msg is not None:
            self._try_goal()
        with self.lock:
            if not self._closing:
                self._send(self.core.on_tick(self._now(), self.odom))

    def _on_silence(self, silent_s):
        # Before the first scan nothing has been sent that a stop would end; a stop then would only say how long
        # the graph took to start in wall time (and a lockstepped scenario would depend on it): it waits, with a
        # line in the log.
        if not self._scan_seen:
            rospy.loginfo_throttle(LOG_PERIOD_S * 5, 'waiting for the first scan on %s' % rospy.resolve_name('scan'))
            return
        with self.lock:
            if not self._closing:
                self._send(self.core.on_silence(self._now(), silent_s))

    def _on_camera_info(self, msg):
        if len(msg.K) != 9:
            return
        with self.lock:
            self.core.on_camera_info(msg.K[0], msg.K[2], msg.width)

    def _on_red(self, msg):
        with self.lock:
            self.core.on_detection(msg.point.x, stamp_to_sec(msg.header.stamp), self.odom)

    def _on_goal(self, msg):
        # TF is listened to from the first goal on (a listener pays for every TF message of the graph); a goal whose
        # frame cannot be brought into odom yet is tried again at each tick, for GOAL_WAIT_S of ROS time.
        if self._tf is None:
            self._tf = tf2_ros.Buffer()
            self._tf_listener = tf2_ros.TransformListener(self._tf)
        with self.lock:
            self._goal_msg = (msg, self._now())
        self._try_goal()

    def _try_goal(self):
        """Take the pending goal if its frame can be brought into odom now (at its stamp, else the latest)."""
        with self.lock:
            if self._goal_msg is None:
                return
            msg, since = self._goal_msg
        source = msg.header.frame_id or self.frames['odom']
        t = error = None
        for stamp in (msg.header.stamp, rospy.Time(0)):
            try:
                t = self._tf.lookup_transform(self.frames['odom'], source, stamp)
                break
            except (tf2_ros.LookupException, tf2_ros.ConnectivityException, tf2_ros.ExtrapolationException) as e:
                error = e
        if t is None:
            if self._now() - since >= GOAL_WAIT_S:
                with self.lock:
                    self._goal_msg = None
                rospy.logerr('goal ignored: cannot bring frame %r into %s within %g s: %s', source, self.frames['odom'],
                             GOAL_WAIT_S, error)
            return
        r = t.transform.rotation
        yaw = quaternion_yaw((r.x, r.y, r.z, r.w))
        px, py = msg.pose.position.x, msg.pose.position.y
        goal = (t.transform.translation.x + math.cos(yaw) * px - math.sin(yaw) * py,
                t.transform.translation.y + math.sin(yaw) * px + math.cos(yaw) * py)
        with self.lock:
            if self._goal_msg is None or self._goal_msg[0] is not msg:
                return                                  # a newer goal came meanwhile
            self._goal_msg = None
            try:
                self.core.set_goal(goal, self._now())
            except ControllerError as error:
                rospy.logerr('goal ignored: %s', error)
                return
            self._report()
        rospy.loginfo('new goal (%.2f, %.2f) in %s (from %s)', goal[0], goal[1], self.frames['odom'], source)

    # -- outputs (lock held) -----------------------------------------------------------------------------------------
    def _send(self, command):
        """Publish the core's command (None: nothing to send now), then what it reports."""
        if command is not None:
            try:
                self.cmd_pub.publish(twist(*command))
            except CommandError as error:       # a core's bug must not move the robot
                rospy.logerr_throttle(LOG_PERIOD_S, '%s gave an invalid command (%s): sending zero',
                                      self.cls.name, error)
                self.cmd_pub.publish(twist(*STOP))
        self._report()

    def _report(self):
        for old, new, _now_s, why in self.core.take_transitions():
            log = rospy.logwarn if new in self.cls.warn_modes else rospy.loginfo
            log('mode %s -> %s: %s', old or '-', new, why)     # the line's own stamp says when
            self._mode_pub.publish(String(data=new))
        starting = not self._scan_seen and time.monotonic() - self._started_wall < self.settings.scan_timeout
        if self.core.fault is not None and not starting:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped: %s', self.core.fault)
        if self._outputs:
            wanted = {name for name, (pub, latched) in self._outputs.items()
                      if latched or pub.get_num_connections() > 0}
            stamp = rospy.Time.now()
            for name, value in self.core.drawings(wanted).items():
                self._outputs[name][0].publish(to_message(value, self.frames, stamp))


def main(name):
    """Start the node that hosts controller ``name`` (``closed_loop.controllers``) and serve until shutdown."""
    cls = controller_class(name)
    init_node(name)
    ControllerNode(cls)
    rospy.spin()
