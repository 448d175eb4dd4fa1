"""The simulator node: a pybullet world and robot behind the usual ROS topics of a mobile base."""
import os
import sys
import threading
import time
from collections import namedtuple

import rospkg
import rospy
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, JointState, LaserScan
from std_msgs.msg import Float32, String, UInt32
from std_srvs.srv import Empty, EmptyResponse, Trigger, TriggerResponse
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from closed_loop.sim import world as world_mod, world_robots
from closed_loop import description, robot_model
from closed_loop.nodes import sensor_messages as to_msgs
from closed_loop.nodes import sim_lockstep
from closed_loop.nodes.common import Publisher, init_node, load_settings
from closed_loop.nodes.robot_port import RobotPort
from closed_loop.sim.scheduler import ClockSchedule, Schedule, SchedulingSettings
from closed_loop.sim.sensors.camera import Camera
from closed_loop.sim.sensors.clearance import Clearance
from closed_loop.sim.sensors.contacts import Contacts
from closed_loop.sim.sensors.lidar import Lidar
from closed_loop.sim.sensors.odometry import Odometry as OdometrySensor
from closed_loop.sim.sensors.wheels import WheelEncoders
from closed_loop.sim.sensors.world_state import WorldState
from closed_loop.sim.simulation import RobotSetup, SimSettings, Simulation

#: One line per sensor: its core class (closed_loop.sim.sensors), its publications (topic, type, queue size,
#: latched), its conversion (closed_loop.nodes.sensor_messages), whether it is sampled only while one of
#: its topics has a subscriber (like a lazy camera driver), whether /clock goes out first (consumers
#: judge a scan's or an image's age by it), and whether it is the world's rather than each robot's (served
#: once, with the first robot). Lines are served in this order after each physics step, robot by robot.
SensorLine = namedtuple('SensorLine', 'sensor publications convert lazy clock_first shared')
SENSORS = (
    SensorLine(Contacts, (('contact', String, 10, False), ('contact_count', UInt32, 1, True)),
               to_msgs.contact_messages, False, False, False),
    SensorLine(Clearance, (('clearance', Float32, 10, False),), to_msgs.clearance_messages, True, False, False),
    SensorLine(OdometrySensor, (('odom', Odometry, 10, False), ('/tf', TFMessage, 20, False),
                                ('base_pose_ground_truth', Odometry, 10, False)),
               to_msgs.odometry_messages, True, False, False),
    SensorLine(WheelEncoders, (('joint_states', JointState, 10, False),), to_msgs.joint_messages,
               True, False, False),
    SensorLine(Lidar, (('scan', LaserScan, 5, False),), to_msgs.scan_messages, False, True, False),
    SensorLine(Camera, (('camera/image_raw', Image, 2, False), ('camera/camera_info', CameraInfo, 2, False)),
               to_msgs.camera_messages, True, True, False),
    SensorLine(WorldState, (('world_markers', MarkerArray, 1, True),), to_msgs.world_messages,
               False, False, True),
)
# How far behind the wall clock the loop may fall before it stops trying to catch up.
MAX_LAG_S = 0.25
# Time a service call waits for the loop to carry out its request.
SERVICE_WAIT_S = 5.0
# Idle sleep while paused.
PAUSED_POLL_S = 0.01


class LoadError(Exception):
    """A world or robot the simulator cannot load (the message says what)."""


def same_profile(a, b):
    """True if profile references ``a`` and ``b`` name the same profile (a file of the user's by its path, however
    it is written: ``$(find PKG)/...``, ``PKG/...`` or a path)."""
    if a == b or not all(isinstance(p, str) and p.endswith(('.yaml', '.yml')) for p in (a, b)):
        return a == b
    try:
        return description.resolve(a, 'robot_profile', package_relative=True) == \
            description.resolve(b, 'robot_profile', package_relative=True)
    except description.DescriptionError:
        return False


def package_path():
    """closed_loop's share folder (source tree or install space), where worlds/ and urdf/ live."""
    return rospkg.RosPack().get_path('closed_loop')


class SimNode:
    """Runs :class:`closed_loop.sim.simulation.Simulation` and publishes what the robot senses.

    Subscribes:
        cmd_vel (geometry_msgs/Twist): linear.x (m/s) and angular.z (rad/s); a command with NaN/Inf in
            any field is rejected with a throttled warning and brakes the robot. With no command for
            ``~cmd_vel_timeout`` s the robot brakes to zero. A command beyond ``~max_linear_speed`` or
            ``~max_angular_speed`` is clipped with a throttled warning giving the value and the limit;
            a second node publishing on cmd_vel is reported (throttled, naming both).
    Publishes:
        clock (rosgraph_msgs/Clock): simulated time, after every physics step at real time (at most
            ``~max_clock_rate_hz`` per wall second on average when faster), and before every scan and
            camera frame.
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
        clearance (std_msgs/Float32): the least distance (m) between the robot's collision shapes and any
            obstacle, by the physics (ground truth, for judging), while someone listens.
    Services:
        ~reset_world, ~pause_physics, ~unpause_physics (std_srvs/Empty); ~load_episode (std_srvs/Trigger: the
        world and the settings read again from the parameters, a new simulation paused at t = 0, for the next
        episode of a kept graph: ``closed_loop.batch.kept_graph``).
    Parameters: :class:`closed_loop.sim.simulation.SimSettings` (world, robot, drive),
    :class:`closed_loop.sim.scheduler.SchedulingSettings` (``~real_time_factor``, ``~max_clock_rate_hz``), and
    each sensor's settings class (``closed_loop.sim.sensors``: LIDAR, camera, odometry, wheel encoders).
    Sensors are served from one table, :data:`SENSORS`, by one schedule on simulated time.
    """

    def __init__(self):
        self.settings = load_settings(SimSettings)
        self.scheduling = load_settings(SchedulingSettings)
        try:
            world, setups, path = self._load_world()
        except LoadError as error:
            rospy.logfatal('sim_node: %s', error)
            sys.exit(1)
        self.sim = Simulation(world, self.settings, robots=setups)
        self.launch_nodes = sim_lockstep.LaunchNodes(self.scheduling.lockstep_watchers) if self.scheduling.lockstep else None
        self.ports = [RobotPort(self, index, setup, SENSORS) for index, setup in enumerate(setups)]
        if world.left_out:
            rospy.logwarn('sim_node: world %s: left out or approximated: %s', path, '; '.join(world.left_out))
        rospy.loginfo('sim_node: world %r from %s; %s; real_time_factor %g', world.name, path,
                      '; '.join(port.describe() for port in self.ports), self.scheduling.real_time_factor)
        self._lock = threading.Lock()
        self._requests = []
        self._paused = self.scheduling.paused
        if self._paused:
            rospy.loginfo('sim_node: paused at t = 0 until ~unpause_physics')
        self._stopped = threading.Event()
        self.clock_pub = self.publisher('/clock', Clock, 10)
        self.missed_pub = sim_lockstep.missed_publisher() if self.scheduling.lockstep else None
        rospy.Service('~reset_world', Empty, lambda _: self._request('reset'))
        rospy.Service('~pause_physics', Empty, lambda _: self._request('pause'))
        rospy.Service('~unpause_physics', Empty, lambda _: self._request('unpause'))
        rospy.Service('~load_episode', Trigger, lambda _: TriggerResponse(*self._request('load')))
        rospy.on_shutdown(self._stopped.set)

    def _load_world(self):
        """(world, robot setups with their starts, the world file's path) of ``~world`` and ``~start`` as the
        parameters have them now; :class:`LoadError` says what is wrong."""
        try:
            path = world_mod.resolve_world(self.settings.world, os.path.join(package_path(), 'worlds'))
            world = world_mod.load_world(path, check_starts=False)   # which robots; starts checked below
            setups = self._robot_setups(world)
            # Every start must be free for its robot's footprint, not a generic disc.
            footprints = {setup.name: robot_model.load_robot_model(setup.urdf, setup.settings.names).footprint
                          for setup in setups}
            world = world_mod.load_world(path, footprints if world.robots else footprints[''],
                                         check_starts=self.settings.start_pose is None)
            if self.settings.start_pose is not None:
                world = world_robots.with_start(world, self.settings.start_pose, footprints.get(''),
                                                world_mod.WorldError, '~start')
        except robot_model.RobotModelError as error:
            raise LoadError(str(error))
        except world_mod.WorldError as error:
            raise LoadError('cannot load the world: %s' % error)
        starts = {spec.name: spec.start for spec in world.robots} or {'': world.robot_start}
        return world, [RobotSetup(setup.name, setup.settings, setup.urdf, starts[setup.name]) for setup in setups], path

    def _load_episode(self):
        """``~load_episode``, in the loop: the world and every setting read again from the parameters, a new
        simulation at t = 0, paused; the same robots (their descriptions and topics) as before. Returns
        (success, message)."""
        old = self.settings, self.scheduling
        try:
            self.settings, self.scheduling = load_settings(SimSettings), load_settings(SchedulingSettings)
            if self.scheduling.lockstep != old[1].lockstep:
                raise LoadError('lockstep %s: this graph\'s simulator runs with lockstep %s'
                                % (self.scheduling.lockstep, old[1].lockstep))
            world, setups, path = self._load_world()
            if [s.name for s in setups] != [port.name for port in self.ports]:
                raise LoadError('world %s has robots %s, this graph %s: it needs a graph of its own' % (
                    path, [s.name for s in setups], [port.name for port in self.ports]))
        except (LoadError, ValueError) as error:
            self.settings, self.scheduling = old
            rospy.logerr('sim_node: load_episode: %s', error)
            return False, str(error)
        self.sim.close()
        self.sim = Simulation(world, self.settings, robots=setups)
        for port, setup in zip(self.ports, setups):
            port.attach(self, setup.settings)
            port.forget_sources()
            port.reset()
        self._paused = True
        if self.launch_nodes is not None:
            self.launch_nodes.forget()
        self._publish_clock(rospy.Time(0))
        rospy.loginfo('sim_node: episode loaded: world %r from %s, paused at t = 0', world.name, path)
        return True, 'world %r at t = 0, paused' % world.name

    def _robot_setups(self, world):
        """One RobotSetup per robot (start filled in later). A one-robot world: the node's own settings
        and ``robot_description``. A multi-robot world: robot NAME's settings from ``/NAME/sim/`` (then the
        node's own), its URDF from ``/NAME/robot_description``, which the robot's launch (robot.launch)
        loads from the profile the world names."""
        if not world.robots:
            urdf = rospy.get_param('robot_description', None)
            if not isinstance(urdf, str) or not urdf.strip():
                urdf = os.path.join(package_path(), 'urdf', 'closed_loop.urdf')
                rospy.logwarn('sim_node: no robot_description on the parameter server; using %s', urdf)
            return [RobotSetup('', self.settings, urdf, None)]
        setups = []
        for spec in world.robots:
            namespace = '/%s/' % spec.name
            urdf = rospy.get_param(namespace + 'robot_description', None)
            if not isinstance(urdf, str) or not urdf.strip():
                rospy.logfatal('sim_node: world robot %r: no %srobot_description (run launch/robot.launch '
                               'name:=%s robot:=%s)', spec.name, namespace, spec.name, spec.profile)
                sys.exit(1)
            profile = rospy.get_param(namespace + 'robot_profile', spec.profile)
            if not same_profile(profile, spec.profile):
                rospy.logfatal('sim_node: world robot %r: the world says profile %r, %srobot_profile says %r',
                               spec.name, spec.profile, namespace, profile)
                sys.exit(1)
            settings = load_settings(SimSettings, (namespace + 'sim/', '~'), namespace + 'robot_description')
            setups.append(RobotSetup(spec.name, settings, urdf, None))
        return setups

    # -- inputs (other threads): store, and let the loop act -----------------------------------------------
    def _request(self, what):
        """Queue request ``what`` for the loop and wait for it: EmptyResponse, or for ``load`` (success, message)."""
        done, result = threading.Event(), []
        with self._lock:
            self._requests.append((what, (done, result)))
        if not done.wait(SERVICE_WAIT_S):
            rospy.logwarn('sim_node: %s request not carried out within %g s', what, SERVICE_WAIT_S)
            return (False, 'not carried out within %g s' % SERVICE_WAIT_S) if what == 'load' else EmptyResponse()
        return result[0] if what == 'load' else EmptyResponse()

    def _take_inputs(self):
        """Drive by the commands heard, and carry out the requests (True if the world was reset or loaded)."""
        for port in self.ports:
            port.take_command()
        return self._take_requests()

    def _take_requests(self):
        """Carry out the service requests (True if the world was reset or an episode loaded)."""
        with self._lock:
            requests, self._requests = self._requests, []
        reset = False
        for what, (done, result) in requests:
            if what == 'load':
                result.append(self._load_episode())
                reset = reset or result[0][0]
            elif what == 'reset':
                self.sim.reset_world()
                for port in self.ports:
                    port.reset()
                reset = True
                rospy.loginfo('sim_node: world reset')
            elif what == 'pause':
                self._paused = True
                rospy.loginfo('sim_node: paused at t = %.3f s', self.sim.time_s)
            elif what == 'unpause':
                self._paused = False
                rospy.loginfo('sim_node: unpaused')
            done.set()
        return reset

    # -- the loop: the only code that calls the simulation ----------------------------------------------------
    def _schedule(self):
        """The schedule of every port's sensors on simulated time, and {task name: (port, line, sensor)}."""
        schedule = Schedule(self.sim.dt_s)
        tasks = {}
        for port in self.ports:
            for line, sensor in port.sensors:
                name = '%s/%s' % (port.name, type(sensor).__name__)
                schedule.add(name, sensor.period_s, sensor.offset_s)
                tasks[name] = (port, line, sensor)
        return schedule, tasks

    def run(self):
        if self.scheduling.lockstep:
            sim_lockstep.run(self)
        else:
            self._run_real_time()
        self.sim.close()

    def _run_real_time(self):
        s = self.scheduling
        sim = self.sim
        schedule, tasks = self._schedule()
        wall_ref, sim_ref = time.monotonic(), sim.time_s
        clock = ClockSchedule(s, sim.dt_s, time.monotonic())
        self._publish_clock()
        while not self._stopped.is_set() and not rospy.is_shutdown():
            if self._take_inputs() and sim is not self.sim:      # an episode loaded: a new simulation
                sim = self.sim
                schedule, tasks = self._schedule()
            if self._paused:
                time.sleep(PAUSED_POLL_S)
                wall_ref, sim_ref = time.monotonic(), sim.time_s
                continue
            t = sim.step()
            due = [tasks[name] for name in schedule.due(t)]
            # Every node on simulated time pays for each /clock message: faster than real time, sending
            # every step would cost more than the physics (closed_loop.sim.scheduler.ClockSchedule).
            clock_due = clock.due(t, time.monotonic())
            if clock_due or any(line.clock_first for _, line, _ in due):
                self._publish_clock()
            stamp = rospy.Time.from_sec(t)
            for port, line, sensor in due:
                port.serve(line, sensor, stamp)
            if s.real_time_factor > 0:
                target = wall_ref + (t - sim_ref) / s.real_time_factor
                delay = target - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                elif delay < -MAX_LAG_S:
                    rospy.logwarn_throttle(10.0, 'sim_node: cannot keep real_time_factor %g; running slower'
                                           % s.real_time_factor)
                    wall_ref, sim_ref = time.monotonic(), t

    # -- outputs -----------------------------------------------------------------------------------------------
    def publisher(self, topic, msg_type, queue_size, latch=False):
        """A publisher of the simulator's (in lockstep, written through to the launch's nodes: sim_lockstep)."""
        publisher = Publisher(topic, msg_type, queue_size=queue_size, latch=latch)
        return publisher if self.launch_nodes is None else sim_lockstep.write_through(publisher, self.launch_nodes)

    def _publish_clock(self, stamp=None):
        stamp = rospy.Time.from_sec(self.sim.time_s) if stamp is None else stamp
        self.clock_pub.publish(Clock(clock=stamp))
        if self.launch_nodes is not None:
            sim_lockstep.set_own_time(stamp)


def main():
    init_node('sim_node')
    SimNode().run()
