"""The simulator node: a pybullet world and robot behind the usual ROS topics of a mobile base."""
import math
import os
import sys
import threading
import time

import rospkg
import rospy
from geometry_msgs.msg import Quaternion, TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, JointState, LaserScan
from std_msgs.msg import String, UInt32
from std_srvs.srv import Empty, EmptyResponse
from tf2_msgs.msg import TFMessage

from closed_loop import drive, image_encoding, robot_model, world as world_mod
from closed_loop.geometry import yaw_quaternion
from closed_loop.nodes.common import init_node, load_settings
from closed_loop.nodes.conversions import connected_publishers, message_callerid
from closed_loop.simulation import SimSettings, Simulation
from closed_loop.sources import SourceCheck

ODOM_FRAME = 'odom'
WORLD_FRAME = 'world'
# How far behind the wall clock the loop may fall before it stops trying to catch up.
MAX_LAG_S = 0.25
# Time a service call waits for the loop to carry out its request.
SERVICE_WAIT_S = 5.0
# How often a repeated warning may reappear in the log (s).
LOG_PERIOD_S = 2.0
# Idle sleep while paused.
PAUSED_POLL_S = 0.01
# A small diagonal covariance for odometry (m^2, rad^2), so consumers that weigh it do not divide by 0.
ODOM_POSE_VARIANCE = 1e-3
ODOM_TWIST_VARIANCE = 1e-3


def package_path():
    """closed_loop's share folder (source tree or install space), where worlds/ and urdf/ live."""
    return rospkg.RosPack().get_path('closed_loop')


def _stamp(t_s):
    return rospy.Time.from_sec(t_s)


def _quaternion_yaw(yaw):
    return Quaternion(*yaw_quaternion(yaw))


class SimNode:
    """Runs :class:`closed_loop.simulation.Simulation` and publishes what the robot senses.

    Subscribes:
        cmd_vel (geometry_msgs/Twist): linear.x (m/s) and angular.z (rad/s); a command with NaN/Inf in
            any field is rejected with a throttled warning and brakes the robot. With no command for
            ``~cmd_vel_timeout`` s the robot brakes to zero. A command beyond ``~max_linear_speed`` or
            ``~max_angular_speed`` is clipped with a throttled warning giving the value and the limit;
            a second node publishing on cmd_vel is reported (throttled, naming both).
    Publishes:
        clock (rosgraph_msgs/Clock): simulated time, after every physics step at real time (at most
            ``~max_clock_rate_hz`` per wall second when faster), and before every scan and camera frame.
        scan (sensor_msgs/LaserScan): frame base_scan; REP 117 (+inf no return, -inf closer than range_min).
        camera/image_raw (sensor_msgs/Image, rgb8) and camera/camera_info (sensor_msgs/CameraInfo),
            frame camera_optical_frame; off with ``~camera:=false``.
        odom (nav_msgs/Odometry): odom -> base_footprint from the wheels; also as TF on tf.
        base_pose_ground_truth (nav_msgs/Odometry): the true pose of base_footprint in frame ``world``.
        joint_states (sensor_msgs/JointState): the wheel joints, for robot_state_publisher, at
            ``~joint_states_rate_hz``.
        contact (std_msgs/String): an obstacle's name each time the robot starts touching it.
        contact_count (std_msgs/UInt32, latched): contacts begun since start or the last reset.
    Services:
        ~reset_world, ~pause_physics, ~unpause_physics (std_srvs/Empty).
    Parameters: see :class:`closed_loop.simulation.SimSettings` (``~world``, ``~real_time_factor``, ...).
    """

    def __init__(self):
        self.settings = load_settings(SimSettings)
        urdf = rospy.get_param('robot_description', None)
        if not isinstance(urdf, str) or not urdf.strip():
            urdf = os.path.join(package_path(), 'urdf', 'closed_loop.urdf')
            rospy.logwarn('sim_node: no robot_description on the parameter server; using %s', urdf)
        try:
            model = robot_model.load_robot_model(urdf, self.settings.names)
        except robot_model.RobotModelError as error:
            rospy.logfatal('sim_node: %s', error)
            sys.exit(1)
        try:
            path = world_mod.resolve_world(self.settings.world, os.path.join(package_path(), 'worlds'))
            # The start must be free for this robot's footprint, not a generic disc.
            world = world_mod.load_world(path, model.footprint)
        except world_mod.WorldError as error:
            rospy.logfatal('sim_node: cannot load the world: %s', error)
            sys.exit(1)
        self.sim = Simulation(world, self.settings, urdf)
        rospy.loginfo('sim_node: world %r from %s; robot %s; real_time_factor %g; camera %s', world.name, path,
                      self.sim.model.source, self.settings.real_time_factor, 'on' if self.sim.has_camera else 'off')
        self._lock = threading.Lock()
        self._pending_command = None
        self._requests = []
        self._paused = False
        self._stopped = threading.Event()
        self.clock_pub = rospy.Publisher('/clock', Clock, queue_size=10)
        self.scan_pub = rospy.Publisher('scan', LaserScan, queue_size=5)
        self.odom_pub = rospy.Publisher('odom', Odometry, queue_size=10)
        self.truth_pub = rospy.Publisher('base_pose_ground_truth', Odometry, queue_size=10)
        self.joint_pub = rospy.Publisher('joint_states', JointState, queue_size=10)
        self.tf_pub = rospy.Publisher('/tf', TFMessage, queue_size=20)
        self.contact_pub = rospy.Publisher('contact', String, queue_size=10)
        self.contact_count_pub = rospy.Publisher('contact_count', UInt32, queue_size=1, latch=True)
        if self.settings.camera and not self.sim.has_camera:
            rospy.loginfo('sim_node: the robot has no camera (~camera_frame is empty); no images')
        if self.sim.has_camera:
            self.image_pub = rospy.Publisher('camera/image_raw', Image, queue_size=2)
            self.info_pub = rospy.Publisher('camera/camera_info', CameraInfo, queue_size=2)
        self._cmd_source = SourceCheck(rospy.resolve_name('cmd_vel'))
        self.cmd_sub = rospy.Subscriber('cmd_vel', Twist, self._on_cmd_vel, queue_size=10)
        rospy.Service('~reset_world', Empty, lambda _: self._request('reset'))
        rospy.Service('~pause_physics', Empty, lambda _: self._request('pause'))
        rospy.Service('~unpause_physics', Empty, lambda _: self._request('unpause'))
        rospy.on_shutdown(self._stopped.set)
        self.contact_count_pub.publish(UInt32(0))

    # -- inputs (other threads): store, and let the loop act -----------------------------------------------
    def _on_cmd_vel(self, msg):
        conflict = self._cmd_source.observe(message_callerid(msg), None, time.monotonic(),
                                            connected_publishers(self.cmd_sub))
        if conflict is not None:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'sim_node: %s' % conflict.replace(
                'stopping until only one remains', 'the base obeys each message as it comes'))
        try:
            twist = drive.validate_twist((msg.linear.x, msg.linear.y, msg.linear.z),
                                         (msg.angular.x, msg.angular.y, msg.angular.z))
        except drive.CommandError as error:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'sim_node: rejected cmd_vel: %s; braking' % error)
            twist = drive.STOP
        for clipped in drive.clipped_fields(twist, self.settings.max_linear_speed,
                                            self.settings.max_angular_speed):
            rospy.logwarn_throttle(LOG_PERIOD_S, 'sim_node: cmd_vel from %s: %s'
                                   % (message_callerid(msg) or 'an unknown publisher', clipped))
        with self._lock:
            self._pending_command = twist

    def _request(self, what):
        done = threading.Event()
        with self._lock:
            self._requests.append((what, done))
        if not done.wait(SERVICE_WAIT_S):
            rospy.logwarn('sim_node: %s request not carried out within %g s', what, SERVICE_WAIT_S)
        return EmptyResponse()

    def _take_inputs(self):
        with self._lock:
            command, self._pending_command = self._pending_command, None
            requests, self._requests = self._requests, []
        if command is not None:
            self.sim.command(command)
        for what, done in requests:
            if what == 'reset':
                self.sim.reset_world()
                self.contact_count_pub.publish(UInt32(0))
                rospy.loginfo('sim_node: world reset')
            elif what == 'pause':
                self._paused = True
                rospy.loginfo('sim_node: paused at t = %.3f s', self.sim.time_s)
            elif what == 'unpause':
                self._paused = False
                rospy.loginfo('sim_node: unpaused')
            done.set()

    # -- the loop: the only code that calls the simulation ----------------------------------------------------
    def run(self):
        s = self.settings
        sim = self.sim
        scan_period = 1.0 / s.scan_rate_hz
        odom_period = 1.0 / s.odom_rate_hz
        joints_period = 1.0 / s.joint_states_rate_hz
        next_joints = 0.0
        camera_period = 1.0 / s.camera_rate_hz
        half_step = 0.5 * sim.dt_s
        camera = sim.has_camera
        next_scan = 0.0
        next_odom = 0.0
        # Render half a period after the scans, so a frame never delays the scan that follows it.
        next_camera = 0.5 * camera_period
        wall_ref, sim_ref = time.monotonic(), sim.time_s
        clock_min_wall_s = 1.0 / s.max_clock_rate_hz
        last_clock_wall = time.monotonic()
        self._publish_clock()
        while not self._stopped.is_set() and not rospy.is_shutdown():
            self._take_inputs()
            if self._paused:
                time.sleep(PAUSED_POLL_S)
                wall_ref, sim_ref = time.monotonic(), sim.time_s
                continue
            t = sim.step()
            sensing = t >= next_scan - half_step or (camera and t >= next_camera - half_step)
            now_wall = time.monotonic()
            if sensing or now_wall - last_clock_wall >= clock_min_wall_s:
                # Every node on simulated time pays for each /clock message; faster than real time,
                # publishing every step would cost more than the physics.
                self._publish_clock()
                last_clock_wall = now_wall
            for name in sim.new_contacts():
                rospy.logwarn('sim_node: contact with %r at t = %.3f s', name, t)
                self.contact_pub.publish(String(name))
                self.contact_count_pub.publish(UInt32(sim.contact_count))
            if t >= next_odom - half_step:
                next_odom += odom_period
                self._publish_state(t)
            if t >= next_joints - half_step:
                next_joints += joints_period
                self._publish_joints(_stamp(t))
            if t >= next_scan - half_step:
                next_scan += scan_period
                self._publish_scan(t, sim.scan())
            if camera and t >= next_camera - half_step:
                next_camera += camera_period
                # Like a lazy camera driver: no subscriber, no rendering.
                if self.image_pub.get_num_connections() + self.info_pub.get_num_connections() > 0:
                    self._publish_camera(t, sim.render_camera())
            if s.real_time_factor > 0:
                target = wall_ref + (t - sim_ref) / s.real_time_factor
                delay = target - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                elif delay < -MAX_LAG_S:
                    rospy.logwarn_throttle(10.0, 'sim_node: cannot keep real_time_factor %g; running slower'
                                           % s.real_time_factor)
                    wall_ref, sim_ref = time.monotonic(), t
        sim.close()

    # -- outputs -----------------------------------------------------------------------------------------------
    def _publish_clock(self):
        self.clock_pub.publish(Clock(clock=_stamp(self.sim.time_s)))

    def _publish_state(self, t):
        sim = self.sim
        stamp = _stamp(t)
        # (joint states go out on their own period, see _publish_joints)
        odo = sim.odometry
        # Messages nobody listens to are not built (faster than real time this is most of the ROS cost).
        if self.odom_pub.get_num_connections() + self.tf_pub.get_num_connections() > 0:
            self._publish_odometry(stamp, odo)
        if self.truth_pub.get_num_connections() > 0:
            self._publish_truth(stamp)

    def _publish_joints(self, stamp):
        sim = self.sim
        if self.joint_pub.get_num_connections() > 0:
            joints = JointState()
            joints.header.stamp = stamp
            joints.name, joints.position, joints.velocity = sim.wheel_joint_states()
            self.joint_pub.publish(joints)

    def _publish_odometry(self, stamp, odo):
        odom = Odometry()
        odom.header.stamp = stamp
        odom.header.frame_id = ODOM_FRAME
        odom.child_frame_id = self.settings.base_frame
        odom.pose.pose.position.x, odom.pose.pose.position.y = odo.x, odo.y
        odom.pose.pose.orientation = _quaternion_yaw(odo.yaw)
        odom.twist.twist.linear.x = odo.twist.linear_x
        odom.twist.twist.angular.z = odo.twist.angular_z
        for i in range(6):
            odom.pose.covariance[7 * i] = ODOM_POSE_VARIANCE
            odom.twist.covariance[7 * i] = ODOM_TWIST_VARIANCE
        self.odom_pub.publish(odom)

        tf = TransformStamped()
        tf.header.stamp = stamp
        tf.header.frame_id = ODOM_FRAME
        tf.child_frame_id = self.settings.base_frame
        tf.transform.translation.x, tf.transform.translation.y = odo.x, odo.y
        tf.transform.rotation = odom.pose.pose.orientation
        self.tf_pub.publish(TFMessage([tf]))

    def _publish_truth(self, stamp):
        pose, (linear, angular) = self.sim.ground_truth()
        truth = Odometry()
        truth.header.stamp = stamp
        truth.header.frame_id = WORLD_FRAME
        truth.child_frame_id = self.settings.base_frame
        p = truth.pose.pose
        p.position.x, p.position.y, p.position.z = pose.position
        p.orientation = Quaternion(*pose.orientation)
        # nav_msgs/Odometry carries the twist in the child frame.
        yaw = pose.yaw
        truth.twist.twist.linear.x = math.cos(yaw) * linear[0] + math.sin(yaw) * linear[1]
        truth.twist.twist.linear.y = -math.sin(yaw) * linear[0] + math.cos(yaw) * linear[1]
        truth.twist.twist.linear.z = linear[2]
        truth.twist.twist.angular.z = angular[2]
        self.truth_pub.publish(truth)

    def _publish_scan(self, t, ranges):
        s = self.settings
        layout = self.sim.layout
        msg = LaserScan()
        msg.header.stamp = _stamp(t)
        msg.header.frame_id = self.settings.scan_frame
        msg.angle_min = layout.angle_min
        msg.angle_max = layout.angle_max
        msg.angle_increment = layout.angle_increment
        msg.scan_time = 1.0 / s.scan_rate_hz
        # A LIDAR spinning once per scan_time spends this long per ray.
        msg.time_increment = msg.scan_time * abs(layout.angle_increment) / (2.0 * math.pi)
        msg.range_min = s.range_min
        msg.range_max = s.range_max
        msg.ranges = ranges.tolist()
        self.scan_pub.publish(msg)

    def _publish_camera(self, t, rgb):
        stamp = _stamp(t)
        height, width, step, data = image_encoding.array_to_image(rgb, 'rgb8')
        image = Image(height=height, width=width, encoding='rgb8', is_bigendian=0, step=step, data=data)
        image.header.stamp = stamp
        image.header.frame_id = self.settings.camera_optical_frame
        self.image_pub.publish(image)
        k = self.sim.intrinsics
        info = CameraInfo()
        info.header = image.header
        info.height, info.width = height, width
        info.distortion_model = 'plumb_bob'
        info.D = [0.0] * 5
        info.K = [k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0]
        info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
        info.P = [k.fx, 0.0, k.cx, 0.0, 0.0, k.fy, k.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
        self.info_pub.publish(info)


def main():
    init_node('sim_node')
    SimNode().run()
