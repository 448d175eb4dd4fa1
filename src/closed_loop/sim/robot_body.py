"""One differential-drive robot in a :class:`closed_loop.sim.simulation.Simulation`: its body, wheels, drive
and odometry (:class:`Robot`), what to build it from (:class:`RobotSetup`), and what its sensors see of
the simulation (:class:`RobotView`). The simulation owns the pybullet client, the world and ``step()``;
a robot makes its pybullet calls through it. Free of ROS.
"""
import math
import tempfile
from dataclasses import dataclass


from closed_loop.sim.quiet import import_pybullet, native_output
from closed_loop.sim import drive
from closed_loop.sim.contact_room import BodyExtent, ContactRoom
from closed_loop import description, robot_model
from closed_loop.geometry import quaternion_yaw, yaw_quaternion

pybullet = import_pybullet()

# Spawn the robot this far above the ground so no wheel starts inside it.
SPAWN_CLEARANCE_M = 0.002
# Wheels grip; the casters (collision spheres of base_link) slide.
WHEEL_LATERAL_FRICTION = 1.0
CASTER_LATERAL_FRICTION = 0.0
# base_footprint has no inertial in the URDF (KDL rejects one on the root); pybullet would assume 1 kg.
ROOT_LINK_MASS_KG = 0.001
ROOT_LINK_INERTIA_KGM2 = 1e-7
#: Collision groups: every group (pybullet's default mask), and the first of the bits that mark each robot's
#: own LIDAR housing (robot i: 1 << (OWN_SENSOR_GROUP_BIT + i), above Bullet's own filter bits), which
#: that robot's rays leave out so a LIDAR never sees itself, while other robots' LIDARs see the housing.
ALL_GROUPS = -1
OWN_SENSOR_GROUP_BIT = 8
#: A contact point this near (m; negative: inside) is a touch. Bullet reports points up to its breaking
#: threshold apart (millimetres, not a touch).
CONTACT_TOUCH_M = 0.001


@dataclass(frozen=True)
class BodyPose:
    """A body's pose in the world as pybullet gives it: a position in 3-D and an orientation quaternion."""
    position: tuple     # (x, y, z) m
    orientation: tuple  # quaternion (x, y, z, w)

    @property
    def yaw(self):
        return quaternion_yaw(self.orientation)


@dataclass(frozen=True)
class RobotSetup:
    """One robot to put in the simulation: ``name`` ('' for the only robot of a one-robot world), its
    SimSettings (drive limits, frames, wheels), its URDF (text or a path; None: urdf/closed_loop.urdf)
    and its start pose (an object with x, y, yaw)."""
    name: str
    settings: object    # closed_loop.sim.simulation.SimSettings
    urdf: object
    start: object


class Robot:
    """One differential-drive robot in a :class:`Simulation`: its body, wheels, drive and odometry.

    The wheels are velocity-controlled joints in the physics; the commanded body twist is validated by the
    caller, limited and ramped here, and braked to zero by the command watchdog.
    """

    def __init__(self, sim, setup):
        self.sim = sim
        self.name = setup.name
        self.settings = s = setup.settings
        self.start = setup.start
        self.model = robot_model.load_robot_model(setup.urdf or robot_model.default_urdf_path(), s.names)
        # The track the kinematics use: the wheels' geometric one, times the multiplier (skid steer).
        self.track_m = self.model.wheel_separation_m * s.wheel_separation_multiplier
        self.watchdog = drive.CommandWatchdog(s.cmd_vel_timeout)
        self.odometry = drive.DeadReckoning()
        self._twist = drive.STOP
        self._wheel_targets = None
        self._room = None       # the ContactRoom, made at the first contact check; False: none (see there)
        self._build()

    def _call(self, fn, *args, **kwargs):
        return self.sim._call(fn, *args, **kwargs)

    def _build(self):
        p = pybullet
        start = self.start
        # pybullet reads URDF from a file only; the text (robot_description) is the source, its meshes' package://
        # made paths.
        with tempfile.NamedTemporaryFile('w', suffix='.urdf', prefix='closed_loop-robot-') as urdf_file:
            urdf_file.write(description.for_pybullet(self.model.urdf_text, self.model.source))
            urdf_file.flush()
            with native_output():       # pybullet's importer warns on stdout (a link with no inertia)
                self.robot_id = self._call(p.loadURDF, urdf_file.name,
                                           basePosition=[start.x, start.y, SPAWN_CLEARANCE_M],
                                           baseOrientation=yaw_quaternion(start.yaw),
                                           flags=p.URDF_USE_INERTIA_FROM_FILE)
        self._links = {}
        self._joints = {}
        for index in range(self._call(p.getNumJoints, self.robot_id)):
            info = self._call(p.getJointInfo, self.robot_id, index)
            self._joints[info[1].decode()] = index
            self._links[info[12].decode()] = index
        names = self.model.names
        self._left_wheels = [self._joints[j] for j in names.left_wheel_joints]
        self._right_wheels = [self._joints[j] for j in names.right_wheel_joints]
        self._wheels = self._left_wheels + self._right_wheels
        self._call(p.changeDynamics, self.robot_id, -1, mass=ROOT_LINK_MASS_KG,
                   localInertiaDiagonal=[ROOT_LINK_INERTIA_KGM2] * 3)
        # The body slides where it touches the ground (a caster), and so does a caster on a link of its own,
        # fixed to the body.
        for link in self._fixed_to(names.body_link):
            self._call(p.changeDynamics, self.robot_id, link, lateralFriction=CASTER_LATERAL_FRICTION,
                       spinningFriction=0.0, rollingFriction=0.0)
        for wheel in self._wheels:
            # Anisotropic friction is in the wheel link's frame, whose y is the axle in the package's URDFs.
            self._call(p.changeDynamics, self.robot_id, wheel, lateralFriction=WHEEL_LATERAL_FRICTION,
                       anisotropicFriction=[1.0, self.settings.wheel_sideways_friction, 1.0])
        # Joints other than the wheels must not carry pybullet's default velocity motors.
        self._drive_wheels(0.0, 0.0)
        own = 1 << (OWN_SENSOR_GROUP_BIT + len(self.sim.robots))
        self.ray_mask = ALL_GROUPS & ~own
        if names.scan_frame in self._links:
            self._call(p.setCollisionFilterGroupMask, self.robot_id, self._links[names.scan_frame], own, ALL_GROUPS)

    def _fixed_to(self, link_name):
        """The pybullet indices of link ``link_name`` and of the links fixed below it (by fixed joints only)."""
        found, todo = [], [self._links[link_name]]
        children = {}
        for index in self._links.values():
            info = self._call(pybullet.getJointInfo, self.robot_id, index)
            if info[2] == pybullet.JOINT_FIXED:
                children.setdefault(info[16], []).append(index)
        while todo:
            link = todo.pop()
            found.append(link)
            todo.extend(children.get(link, ()))
        return found

    def cast_rays(self, ray_from, ray_to):
        """:meth:`Simulation.cast_rays` for this robot's sensors: its own LIDAR housing is left out."""
        return self.sim.cast_rays_masked(ray_from, ray_to, self.ray_mask)

    def reaches_height(self, z_low, z_high):
        """False if no part of this robot that its sensors' rays can hit (its LIDAR housing aside) comes between
        the heights ``z_low`` and ``z_high`` (m), as its links' bounding boxes say; True if one may."""
        housing = self._links.get(self.model.names.scan_frame)
        for link in [-1] + [index for index in self._links.values() if index != housing]:
            low, high = self._call(pybullet.getAABB, self.robot_id, link)
            if low[2] <= z_high and high[2] >= z_low:
                return True
        return False

    # -- commands and stepping ----------------------------------------------------------------------
    def command(self, twist):
        """Follow a validated :class:`drive.VelocityCommand` from now until the watchdog expires."""
        self.watchdog.accept(twist, self.sim.time_s)

    def _drive_wheels(self, left_rps, right_rps):
        if (left_rps, right_rps) == self._wheel_targets:
            return  # the motors keep their targets; re-sending costs a call per step
        self._wheel_targets = (left_rps, right_rps)
        self._call(pybullet.setJointMotorControlArray, self.robot_id, self._wheels, pybullet.VELOCITY_CONTROL,
                   targetVelocities=[left_rps] * len(self._left_wheels) + [right_rps] * len(self._right_wheels),
                   forces=[self.settings.wheel_max_torque] * len(self._wheels))

    def before_step(self, dt_s):
        """Ramp toward the command (or zero, from the watchdog) and set the wheel motors."""
        s = self.settings
        target = drive.limit_twist(self.watchdog.target(self.sim.time_s), s.max_linear_speed, s.max_angular_speed)
        self._twist = drive.ramp(self._twist, target, s.max_linear_accel, s.max_angular_accel, dt_s)
        left, right = drive.wheel_speeds(self._twist, self.track_m, self.model.wheel_radius_m)
        self._drive_wheels(left, right)

    def after_step(self, dt_s):
        """Integrate odometry from the wheels' speeds after the physics step."""
        wl, wr = self.wheel_velocities()
        twist = drive.body_twist(wl, wr, self.track_m, self.model.wheel_radius_m)
        if self.settings.odom_yaw_rate == 'gyro':
            _, angular = self._call(pybullet.getBaseVelocity, self.robot_id)
            twist = drive.VelocityCommand(twist.linear_x, angular[2])
        self.odometry.integrate(twist, dt_s)

    def reset(self):
        """Back at its start, at rest, with odometry at zero."""
        start = self.start
        self._call(pybullet.resetBasePositionAndOrientation, self.robot_id, [start.x, start.y, SPAWN_CLEARANCE_M],
                   yaw_quaternion(start.yaw))
        self._call(pybullet.resetBaseVelocity, self.robot_id, [0, 0, 0], [0, 0, 0])
        for joint in self._joints.values():
            self._call(pybullet.resetJointState, self.robot_id, joint, 0.0, 0.0)
        self._twist = drive.STOP
        self._wheel_targets = None
        self._drive_wheels(0.0, 0.0)
        self.watchdog.clear()
        self.odometry.reset()
        if self._room:
            self._room.forget()

    # -- state ------------------------------------------------------------------------------------------
    def wheel_velocities(self):
        """(left, right) wheel speeds (rad/s), each the mean over that side's wheels."""
        states = self._call(pybullet.getJointStates, self.robot_id, self._wheels)
        n = len(self._left_wheels)
        left = [st[1] for st in states[:n]]
        right = [st[1] for st in states[n:]]
        return sum(left) / len(left), sum(right) / len(right)

    def wheel_joint_states(self):
        """(names, positions rad, velocities rad/s) of every wheel joint, left ones first."""
        states = self._call(pybullet.getJointStates, self.robot_id, self._wheels)
        names = self.model.names
        return (list(names.left_wheel_joints + names.right_wheel_joints), [st[0] for st in states],
                [st[1] for st in states])

    def ground_truth(self):
        """(pose of base_footprint in the world frame, (linear xyz, angular xyz) in the world frame)."""
        position, orientation = self._call(pybullet.getBasePositionAndOrientation, self.robot_id)
        linear, angular = self._call(pybullet.getBaseVelocity, self.robot_id)
        return BodyPose(tuple(position), tuple(orientation)), (tuple(linear), tuple(angular))

    def link_pose(self, link_name):
        """World pose of a URDF link frame (not its centre of mass)."""
        state = self._call(pybullet.getLinkState, self.robot_id, self._links[link_name],
                           computeForwardKinematics=True)
        return BodyPose(tuple(state[4]), tuple(state[5]))

    def commanded_twist(self):
        """The ramped twist the wheels are being driven at."""
        return self._twist

    def contacts_with_obstacles(self):
        """The names of the obstacles (and other robots) this robot touches now (not the ground): within
        CONTACT_TOUCH_M of it."""
        # Every body but the ground holds obstacles or another robot (called at every physics step: no lookup
        # unless there is a contact).
        # Not while the robot is provably clear of every obstacle (closed_loop.sim.contact_room), which needs
        # the obstacles standing still and no other robot.
        if self._room is None:
            self._room = False if self.sim.has_moving_obstacles or len(self.sim.robots) > 1 else ContactRoom(
                self.sim.nearest_obstacle_m, BodyExtent(self._call, pybullet, self.robot_id, len(self._joints)))
        if self._room and self._room.clear(*pybullet.getBasePositionAndOrientation(
                self.robot_id, physicsClientId=self.sim.client)):
            return set()
        # Bullet keeps a contact manifold's points while the bodies are within its breaking threshold (about
        # 0.02 m) and reports them with their distance: only those within CONTACT_TOUCH_M touch.
        ground = self.sim.ground_id
        return {self.sim.name_at(c[2], c[6]) for c in self._call(pybullet.getContactPoints, bodyA=self.robot_id)
                if c[2] != ground and c[8] <= CONTACT_TOUCH_M}

    def clearance(self, max_m):
        """Least distance (m) between this robot's collision shapes and any obstacle or other robot, looked
        for up to ``max_m`` (inf when nothing is that close; 0 or less in contact)."""
        # Only the obstacles that may be that close are asked (those whose footprint's circle comes within
        # max_m of the circle round this robot's), nearest such circle first, until the next circle is
        # farther than the least distance found; and every other robot.
        fp = self.model.footprint
        radius = fp.radius_m
        x, y = self._call(pybullet.getBasePositionAndOrientation, self.robot_id)[0][:2]
        least = float('inf')
        for uid in self.sim.other_robot_ids(self):
            least = min([least] + [c[8] for c in self._call(pybullet.getClosestPoints, self.robot_id, uid, max_m)])
        for bound, uid in self.sim.obstacles_near(x, y, max_m + radius):
            if bound - radius > least:
                break
            # Nothing farther than the least found can be the least (a compound answers for each shape within).
            reach = min(max_m, least) if least > 0.0 else max_m
            least = min([least] + [c[8] for c in self._call(pybullet.getClosestPoints, self.robot_id, uid, reach)])
        return least

    def within(self, name, distance_m):
        """True if this robot is within ``distance_m`` of the obstacle (or other robot) ``name``."""
        uid = self.sim.body_of(name)
        return any(self.sim.name_at(uid, c[6]) == name
                   for c in self._call(pybullet.getClosestPoints, self.robot_id, uid, distance_m))


class RobotView:
    """What one robot's sensors sample: that robot's state (link poses, ground truth, wheels, contacts) and
    the shared world (time, ray casts, rendering, obstacles), with the interface of a one-robot
    :class:`Simulation`, so a sensor class serves any robot of a multi-robot world unchanged."""

    _ROBOT = ('model', 'settings', 'robot_id', 'odometry', 'watchdog', 'track_m', 'name', 'command',
              'wheel_velocities', 'wheel_joint_states', 'ground_truth', 'link_pose', 'commanded_twist',
              'contacts_with_obstacles', 'within', 'cast_rays', 'reaches_height', 'clearance')

    def __init__(self, sim, robot):
        self._sim = sim
        self.robot = robot

    def __getattr__(self, name):
        return getattr(self.robot if name in self._ROBOT else self._sim, name)
