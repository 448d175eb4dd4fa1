"""The simulator node: a pybullet world and robot behind the usual ROS topics of a mobile base."""
import os
import sys
import threading
import time
from collections import namedtuple

import rospkg
import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, JointState, LaserScan
from std_msgs.msg import String, UInt32
from std_srvs.srv import Empty, EmptyResponse
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from closed_loop import drive, robot_model, world as world_mod
from closed_loop.nodes import sensor_messages as to_msgs
from closed_loop.nodes.common import LOG_PERIOD_S, init_node, load_settings
from closed_loop.nodes.conversions import connected_publishers, message_callerid
from closed_loop.scheduler import Schedule, SchedulingSettings
from closed_loop.sensors.camera import Camera
from closed_loop.sensors.contacts import Contacts
from closed_loop.sensors.lidar import Lidar
from closed_loop.sensors.odometry import Odometry as OdometrySensor
from closed_loop.sensors.wheels import WheelEncoders
from closed_loop.sensors.world_state import WorldState
from closed_loop.simulation import SimSettings, Simulation
from closed_loop.sources import SourceCheck

#: One line per sensor: its core class (closed_loop.sensors), its publications (topic, type, queue size,
#: latched), its conversion (closed_loop.nodes.sensor_messages), whether it is sampled only while one of
#: its topics has a subscriber (like a lazy camera driver), and whether /clock goes out first (consumers
#: judge a scan's or an image's age by it). Lines are served in this order after each physics step.
SensorLine = namedtuple('SensorLine', 'sensor publications convert lazy clock_first')
SENSORS = (
    SensorLine(Contacts, (('contact', String, 10, False), ('contact_count', UInt32, 1, True)),
               to_msgs.contact_messages, False, False),
    SensorLine(OdometrySensor, (('odom', Odometry, 10, False), ('/tf', TFMessage, 20, False),
                                ('base_pose_ground_truth', Odometry, 10, False)),
               to_msgs.odometry_messages, True, False),
    SensorLine(WheelEncoders, (('joint_states', JointState, 10, False),), to_msgs.joint_messages, True, False),
    SensorLine(Lidar, (('scan', LaserScan, 5, False),), to_msgs.scan_messages, False, True),
    SensorLine(Camera, (('camera/image_raw', Image, 2, False), ('camera/camera_info', CameraInfo, 2, False)),
               to_msgs.camera_messages, True, True),
    SensorLine(WorldState, (('world_markers', MarkerArray, 1, True),), to_msgs.world_messages, False, False),
)
# How far behind the wall clock the loop may fall before it stops trying to catch up.
MAX_LAG_S = 0.25
# Time a service call waits for the loop to carry out its request.
SERVICE_WAIT_S = 5.0
# Idle sleep while paused.
PAUSED_POLL_S = 0.01


def package_path():
    """closed_loop's share folder (source tree or install space), where worlds/ and urdf/ live."""
    return rospkg.RosPack().get_path('closed_loop')


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
        odom (nav_msgs/Odometry): odom -> base_footprint from the wheels; also as TF on tf, with
            world -> odom (from the ground truth), so ``world`` is the root of the TF tree.
        base_pose_ground_truth (nav_msgs/Odometry): the true pose of base_footprint in frame ``world``.
        world_markers (visualization_msgs/MarkerArray, latched): every obstacle in frame ``world``, in its
            colour; once, or at ``~world_markers_rate_hz`` while obstacles move.
        joint_states (sensor_msgs/JointState): the wheel joints, for robot_state_publisher, at
            ``~joint_states_rate_hz``.
        contact (std_msgs/String): an obstacle's name each time the robot starts touching it.
        contact_count (std_msgs/UInt32, latched): contacts begun since start or the last reset.
    Services:
        ~reset_world, ~pause_physics, ~unpause_physics (std_srvs/Empty).
    Parameters: :class:`closed_loop.simulation.SimSettings` (world, robot, drive),
    :class:`closed_loop.scheduler.SchedulingSettings` (``~real_time_factor``, ``~max_clock_rate_hz``), and
    each sensor's settings class (``closed_loop.sensors``: LIDAR, camera, odometry, wheel encoders).
    Sensors are served from one table, :data:`SENSORS`, by one schedule on simulated time.
    """

    def __init__(self):
        self.settings = load_settings(SimSettings)
        self.scheduling = load_settings(SchedulingSettings)
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
        # The sensors this robot has, each with its settings, and their publishers.
        self.sensors = []
        self.publishers = {}
        for line in SENSORS:
            settings = load_settings(line.sensor.settings_class) if line.sensor.settings_class else None
            sensor = line.sensor(settings, self.sim)
            if not sensor.available:
                rospy.loginfo('sim_node: no %s on this robot (or turned off)', line.sensor.__name__.lower())
                continue
            self.sensors.append((line, sensor))
            for topic, msg_type, queue, latched in line.publications:
                self.publishers[topic] = rospy.Publisher(topic, msg_type, queue_size=queue, latch=latched)
        self.contacts = next(sensor for line, sensor in self.sensors if isinstance(sensor, Contacts))
        rospy.loginfo('sim_node: world %r from %s; robot %s; real_time_factor %g; sensors %s', world.name, path,
                      self.sim.model.source, self.scheduling.real_time_factor,
                      ', '.join(type(sensor).__name__ for _, sensor in self.sensors))
        self._lock = threading.Lock()
        self._pending_command = None
        self._requests = []
        self._paused = False
        self._stopped = threading.Event()
        self.clock_pub = rospy.Publisher('/clock', Clock, queue_size=10)
        self._cmd_source = SourceCheck(rospy.resolve_name('cmd_vel'))
        self.cmd_sub = rospy.Subscriber('cmd_vel', Twist, self._on_cmd_vel, queue_size=10)
        rospy.Service('~reset_world', Empty, lambda _: self._request('reset'))
        rospy.Service('~pause_physics', Empty, lambda _: self._request('pause'))
        rospy.Service('~unpause_physics', Empty, lambda _: self._request('unpause'))
        rospy.on_shutdown(self._stopped.set)
        self.publishers['contact_count'].publish(UInt32(0))

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
                for _line, sensor in self.sensors:
                    sensor.reset()
                self.publishers['contact_count'].publish(UInt32(0))
                rospy.loginfo('sim_node: world reset')
            elif what == 'pause':
                self._paused = True
                rospy.loginfo('sim_node: paused at t = %.3f s', self.sim.time_s)
            elif what == 'unpause':
                self._paused = False
                rospy.loginfo('sim_node: unpaused')
            done.set()

    # -- the loop: the only code that calls the simulation ----------------------------------------------------
    def wanted(self, topic):
        """True if ``topic`` has a subscriber (messages nobody listens to are not built)."""
        return self.publishers[topic].get_num_connections() > 0

    def run(self):
        s = self.scheduling
        sim = self.sim
        schedule = Schedule(sim.dt_s)
        lines = {}
        for line, sensor in self.sensors:
            name = type(sensor).__name__
            schedule.add(name, sensor.period_s, sensor.offset_s)
            lines[name] = (line, sensor)
        wall_ref, sim_ref = time.monotonic(), sim.time_s
        clock_period_s = 1.0 / s.max_clock_rate_hz
        next_clock_wall = time.monotonic()
        self._publish_clock()
        while not self._stopped.is_set() and not rospy.is_shutdown():
            self._take_inputs()
            if self._paused:
                time.sleep(PAUSED_POLL_S)
                wall_ref, sim_ref = time.monotonic(), sim.time_s
                continue
            t = sim.step()
            due = [lines[name] for name in schedule.due(t)]
            now_wall = time.monotonic()
            # /clock on a schedule of max_clock_rate_hz in wall time, with half a period of tolerance: at
            # real time every step is sent (steps come one period apart, give or take the sleep's
            # jitter); faster, at most that rate (every node on simulated time pays for each message, and
            # sending every step would cost more than the physics); after a stall, no burst.
            if any(line.clock_first for line, _ in due) or now_wall >= next_clock_wall - 0.5 * clock_period_s:
                self._publish_clock()
                next_clock_wall = max(next_clock_wall + clock_period_s, now_wall)
            stamp = rospy.Time.from_sec(t)
            for line, sensor in due:
                if line.lazy and not any(self.wanted(topic) for topic, _, _, _ in line.publications):
                    continue
                for topic, msg in line.convert(self, sensor, sensor.sample(sim), stamp):
                    self.publishers[topic].publish(msg)
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
        self.clock_pub.publish(Clock(clock=rospy.Time.from_sec(self.sim.time_s)))


def main():
    init_node('sim_node')
    SimNode().run()
