"""The simulation backend: a world and its differential-drive robots in pybullet, stepped at a fixed rate.

One :class:`Simulation` owns one pybullet client; every pybullet call goes through it, from one thread.
It owns the world, the robots (:class:`Robot`, one or several) and ``step()``, and nothing else: the
sensors (``closed_loop.sim.sensors``) sample one robot's :class:`RobotView` of it through a few primitives
(link poses, ray casts, rendering, contacts); a robot is ``closed_loop.sim.robot_body``. It knows nothing of
ROS: the node hands it commands and hands its sensors' readings to ROS.

Conventions (REP 103): metres, seconds of simulated time, radians, x forward, z up. The world frame is
the ground truth frame; odometry starts at the robot's start pose.
"""
import math
from dataclasses import dataclass

import numpy

from closed_loop.sim.quiet import import_pybullet
from closed_loop.sim import obstacles, shapes
from closed_loop import robot_model
from closed_loop.geometry import yaw_quaternion
from closed_loop.sim.robot_body import ALL_GROUPS, Robot, RobotSetup, RobotView  # noqa: F401 (RobotSetup for callers)
from closed_loop.settings import SettingsError, param

pybullet = import_pybullet()

GRAVITY_MPS2 = 9.81
# Constraint solver iterations per step. pybullet's default (50) is meant for stacks and grippers; a
# wheeled base on flat ground drives the same with 20 (within 2 mm over 5 s in obstacle_course) at 70%
# of the cost.
SOLVER_ITERATIONS = 20


#: Shapes in one static compound body at most (pybullet keeps only the first 16 of a collision shape array).
COMPOUND_MOST = 16
#: Without rendering, each obstacle body looks like an invisible cube this size (m, half side): pybullet would
#: otherwise build a look from its collision shapes (a cylinder's mesh: 0.2 ms each).
SPECK_M = 1e-3

#: pybullet DIRECT clients that closed Simulations left for the next ones of this process.
_IDLE_CLIENTS = []
MAX_IDLE_CLIENTS = 1


@dataclass
class SimSettings:
    """The simulator node's ``~parameters``; defaults here only."""
    world: str = param('wall', '', 'world name in worlds/ or a path to a world YAML file')
    start: str = param('', '', "the robot's start as 'x y yaw' (m, m, rad; the world frame) in place of the "
                       "world's (a map as it is has none: the origin); empty: the world's")
    gui: bool = param(False, '', "open pybullet's own window (needs a display)")
    physics_rate_hz: float = param(100.0, 'Hz', 'physics steps per simulated second', minimum=10.0,
                                   maximum=2000.0)
    friction_cone: bool = param(True, '', "pybullet's implicit friction cone (its default); false: the friction "
                                'pyramid, under which a skid-steer base turns at the same rate at every heading '
                                "(the Jackal profile's; docs/simulator.md)")
    cmd_vel_timeout: float = param(0.5, 's', 'brake to zero when no command arrived for this long',
                                   minimum=0.0, maximum=5.0, exclusive_minimum=True)
    max_linear_speed: float = param(1.5, 'm/s', 'linear.x is clipped to +-this', minimum=0.0,
                                    exclusive_minimum=True)
    max_angular_speed: float = param(3.0, 'rad/s', 'angular.z is clipped to +-this', minimum=0.0,
                                     exclusive_minimum=True)
    max_linear_accel: float = param(2.0, 'm/s^2', 'linear acceleration and braking limit', minimum=0.0,
                                    exclusive_minimum=True)
    max_angular_accel: float = param(6.0, 'rad/s^2', 'angular acceleration limit', minimum=0.0,
                                     exclusive_minimum=True)
    wheel_max_torque: float = param(2.0, 'N m', 'torque each wheel motor can apply', minimum=0.0,
                                    exclusive_minimum=True)
    wheel_separation_multiplier: float = param(1.0, '', "effective track / the wheels' geometric track, as "
                                               "diff_drive_controller has it (skid-steer bases slip: more than 1)",
                                               minimum=0.5, maximum=5.0)
    wheel_sideways_friction: float = param(1.0, '', "a wheel's friction along its axle, as a fraction of its "
                                           'friction when rolling (tyres slide sideways more easily; a skid-steer '
                                           'base turns by it)', minimum=0.01, maximum=1.0)
    odom_yaw_rate: str = param('wheels', '', "where odometry's yaw rate comes from: 'wheels' (the wheel speeds and "
                               "track, as diff_drive_controller) or 'gyro' (an IMU's yaw rate, as a skid-steer "
                               "base's EKF fuses it; the linear speed stays the wheels')", choices=('wheels', 'gyro'))
    # Which URDF frames and joints play which part; a robot profile (config/robots/<name>.yaml) sets them.
    base_frame: str = param(robot_model.BASE_FRAME, '', "the robot's root link on the ground (REP 105)")
    body_link: str = param(robot_model.BODY_LINK, '', 'the link whose collision shapes slide (casters)')
    scan_frame: str = param(robot_model.SCAN_FRAME, '', "the LIDAR's link; the scan's frame_id")
    camera_frame: str = param(robot_model.CAMERA_FRAME, '', "the camera's link, looking along +x; empty: "
                              'the robot has no camera')
    camera_optical_frame: str = param(robot_model.CAMERA_OPTICAL_FRAME, '', "the images' frame_id (z forward)")
    left_wheel_joints: str = param(robot_model.LEFT_WHEEL_JOINT, '', 'the left wheel joints, separated by '
                                   'spaces (several: skid steer, driven together)')
    right_wheel_joints: str = param(robot_model.RIGHT_WHEEL_JOINT, '', 'the right wheel joints')

    @property
    def start_pose(self):
        """``start`` as (x, y, yaw), or None for the world's."""
        try:
            values = tuple(float(v) for v in self.start.split())
        except ValueError:
            values = ()
        if not self.start.strip():
            return None
        if len(values) != 3 or not all(math.isfinite(v) for v in values):
            raise SettingsError("~start: expected 'x y yaw' (3 finite numbers: m, m, rad; a launch file's start:= "
                                "or start_x:= and start_y:=) or empty, got %r" % self.start)
        return values

    def check_together(self):
        self.start_pose         # (raises SettingsError for a malformed one)

    @property
    def names(self):
        """The :class:`closed_loop.robot_model.RobotNames` these settings give."""
        return robot_model.RobotNames(self.base_frame, self.body_link, self.scan_frame, self.camera_frame,
                                      self.camera_optical_frame, tuple(self.left_wheel_joints.split()),
                                      tuple(self.right_wheel_joints.split()))


def _first_robot(name):
    """A :class:`Simulation` attribute that is its first robot's (the one-robot interface)."""
    return property(lambda sim: getattr(sim.robots[0], name), doc="The first robot's ``%s``." % name)


class Simulation:
    """A world and its robots in one pybullet client, advanced by :meth:`step`.

    ``robots``: [:class:`RobotSetup`] for a multi-robot world; by default one robot, unnamed, from
    ``settings`` and ``urdf`` at the world's start. The one-robot interface (``command``, ``model``,
    ``ground_truth``, ``link_pose``, ...) is that of the first robot; :meth:`view` gives any robot's.
    ``settings`` also holds what is the world's: ``physics_rate_hz``, ``friction_cone`` and ``gui``.
    """

    def __init__(self, world, settings, urdf=None, robots=None, render=True):
        """``urdf``: the robot description, as URDF text or a file path (default: urdf/closed_loop.urdf);
        ``render``: the obstacles get their visual shapes (a camera or pybullet's window will look at them;
        without, each body gets a speck, as building the look of a shape costs more than the rest of it)."""
        self.world = world
        self.settings = settings
        self.dt_s = 1.0 / settings.physics_rate_hz
        self._render = render or settings.gui
        self._client = _IDLE_CLIENTS.pop() if _IDLE_CLIENTS and not settings.gui else \
            pybullet.connect(pybullet.GUI if settings.gui else pybullet.DIRECT)
        self._gui = settings.gui
        if self._client < 0:
            raise RuntimeError('pybullet could not start (gui=%s)' % settings.gui)
        self.time_s = 0.0
        self._world_start_s = 0.0
        self._build()
        if robots is None:
            robots = [RobotSetup('', settings, urdf, world.robot_start)]
        self.robots = []
        try:
            for setup in robots:
                self.robots.append(Robot(self, setup))
        except Exception:
            self.close()
            raise
        self._robot_ids = {robot.robot_id: robot.name for robot in self.robots}
        for robot in self.robots:
            self._bodies[robot.robot_id] = robot.name
            self._body_of[robot.name] = robot.robot_id

    # -- construction -------------------------------------------------------------------------------
    def _call(self, fn, *args, **kwargs):
        return fn(*args, physicsClientId=self._client, **kwargs)

    @property
    def client(self):
        """The pybullet client id (for a call made at every physics step, without :meth:`_call`'s wrapping)."""
        return self._client

    def _build(self):
        p = pybullet
        self._call(p.resetSimulation)
        self._call(p.setGravity, 0, 0, -GRAVITY_MPS2)
        self._call(p.setTimeStep, self.dt_s)
        self._call(p.setPhysicsEngineParameter, numSolverIterations=SOLVER_ITERATIONS,
                   enableConeFriction=int(self.settings.friction_cone))
        if self.settings.gui:
            self._call(p.configureDebugVisualizer, p.COV_ENABLE_GUI, 0)
        ground_shape = self._call(p.createCollisionShape, p.GEOM_PLANE)
        ground_visual = self._call(p.createVisualShape, p.GEOM_BOX, halfExtents=[50, 50, 0.001],
                                   rgbaColor=list(self.world.ground_color))
        self.ground_id = self._call(p.createMultiBody, 0, ground_shape, ground_visual)
        self._call(p.changeDynamics, self.ground_id, -1, lateralFriction=1.0)
        self._speck = None if self._render else self._call(p.createVisualShape, p.GEOM_BOX, halfExtents=[SPECK_M] * 3,
                                                             rgbaColor=[0, 0, 0, 0])
        #: body uid -> what it holds: a name (a moving obstacle, a robot) or the obstacles of a static group.
        self._bodies = {}
        self._body_of = {}               # obstacle or robot name -> its body's uid
        self._movers = {}                # uid -> (obstacle, path corners, cycle length m)
        owners = {}
        for group in obstacles.static_groups(self.world.obstacles, COMPOUND_MOST):
            uid = self._add_static_group(group)
            self._bodies[uid] = tuple(group)
            owners.update((o.name, uid) for o in group)
        for obstacle in self.world.obstacles:
            if obstacle.motion is not None:
                uid = self._add_mover(obstacle)
                self._bodies[uid] = obstacle.name
                owners[obstacle.name] = uid
                points, cycle_m = obstacles.motion_path(obstacle)
                self._movers[uid] = (obstacle, points, cycle_m)
        self._body_of.update(owners)
        # Each obstacle's body, centre at rest and the radius of a circle round its footprint, for
        # obstacles_near, in the world's order; a mover's centre is read when asked.
        self._extent_uids = numpy.array([owners[o.name] for o in self.world.obstacles], dtype=numpy.int64)
        self._extent_body_uids, self._extent_body = numpy.unique(self._extent_uids, return_inverse=True)
        self._extent_centres = numpy.array([o.position[:2] for o in self.world.obstacles], float).reshape(-1, 2)
        self._extent_radii = numpy.array([shapes.bounding_radius(o) for o in self.world.obstacles], float)

    def _add_static_group(self, group):
        """One static rigid body of the obstacles of ``group`` (at most COMPOUND_MOST), each a shape of its
        compound at its own pose. The physics passes over a static body at every step almost for free, and a
        few compounds for free again: among 315 posts a step costs 62 us as 20 compounds, 77 us as 315 bodies,
        55 us with none; building them, 3 ms against 190."""
        p = pybullet
        if len(group) == 1:                 # alone: a body of its own shape, as a moving obstacle's
            return self._add_mover(group[0])
        kinds, frames = [shapes.SHAPES[o.shape].pybullet_kind(o, p) for o in group], \
            dict(positions=[list(o.position) for o in group], orientations=[yaw_quaternion(o.yaw) for o in group])
        args = dict(radii=[k[1] for k in kinds], halfExtents=[k[2] for k in kinds], lengths=[k[3] for k in kinds])
        types = [k[0] for k in kinds]
        collision = self._call(p.createCollisionShapeArray, types, collisionFramePositions=frames['positions'],
                               collisionFrameOrientations=frames['orientations'], **args)
        visual = self._speck if not self._render else self._call(
            p.createVisualShapeArray, types, visualFramePositions=frames['positions'],
            visualFrameOrientations=frames['orientations'], rgbaColors=[list(o.color) for o in group], **args)
        return self._call(p.createMultiBody, 0, collision, visual, useMaximalCoordinates=True)

    def _add_mover(self, obstacle):
        """A body of its own for one obstacle (a moving one is moved to where its path has taken it before each
        step)."""
        shape, visual = shapes.SHAPES[obstacle.shape].pybullet_shapes(obstacle, self._call, pybullet)
        return self._call(pybullet.createMultiBody, 0, shape, visual if self._render else self._speck,
                          basePosition=list(obstacle.position), baseOrientation=yaw_quaternion(obstacle.yaw),
                          useMaximalCoordinates=True)

    def name_at(self, uid, point):
        """The name of what body ``uid`` holds at ``point`` (x, y, ... on its surface, m): its obstacle or robot,
        or of a static group the obstacle whose footprint is nearest the point; None for the ground or another body."""
        held = self._bodies.get(uid)
        if held is None or isinstance(held, str):
            return held
        return min(held, key=lambda o: shapes.distance(o, point[0], point[1])).name

    def body_of(self, name):
        """The uid of the body holding the obstacle or robot ``name``."""
        return self._body_of[name]

    def other_robot_ids(self, robot):
        """The body uids of the robots other than ``robot``."""
        return [uid for uid in self._robot_ids if uid != robot.robot_id]

    def view(self, index):
        """The :class:`RobotView` of robot ``index`` (its position in ``robots``)."""
        return RobotView(self, self.robots[index])

    # -- the first robot, for a one-robot world: robots[0]'s attributes, as a RobotView has them ----------------
    model = _first_robot('model')
    robot_id = _first_robot('robot_id')
    odometry = _first_robot('odometry')
    watchdog = _first_robot('watchdog')
    track_m = _first_robot('track_m')
    command = _first_robot('command')
    wheel_velocities = _first_robot('wheel_velocities')
    wheel_joint_states = _first_robot('wheel_joint_states')
    ground_truth = _first_robot('ground_truth')
    link_pose = _first_robot('link_pose')
    commanded_twist = _first_robot('commanded_twist')
    contacts_with_obstacles = _first_robot('contacts_with_obstacles')
    within = _first_robot('within')
    clearance = _first_robot('clearance')
    cast_rays = _first_robot('cast_rays')
    reaches_height = _first_robot('reaches_height')

    # -- stepping -----------------------------------------------------------------------------------------
    def step(self):
        """Advance one physics step of ``dt_s`` seconds; returns the new simulated time."""
        for robot in self.robots:
            robot.before_step(self.dt_s)
        self._move_obstacles(self.time_s + self.dt_s)
        self._call(pybullet.stepSimulation)
        self.time_s += self.dt_s
        for robot in self.robots:
            robot.after_step(self.dt_s)
        return self.time_s

    def _move_obstacles(self, t_s):
        for uid, (obstacle, points, cycle_m) in self._movers.items():
            x, y = obstacles.point_on_path(points, cycle_m, obstacle.motion.speed * (t_s - self._world_start_s))
            self._call(pybullet.resetBasePositionAndOrientation, uid, [x, y, obstacle.position[2]],
                       yaw_quaternion(obstacle.yaw))

    def reset_world(self):
        """Put every robot back at its start, at rest, with odometry at zero; moving obstacles restart."""
        for robot in self.robots:
            robot.reset()
        self._world_start_s = self.time_s
        self._move_obstacles(self.time_s)

    # -- the world, for every robot's sensors --------------------------------------------------------------
    def obstacle_positions(self):
        """[(obstacle, (x, y, z) of its centre now)] for every obstacle of the world, in the world's order:
        a moving one where its path has taken it (the pose the physics has), a static one where it stands."""
        moved = {obstacle.name: uid for uid, (obstacle, _, _) in self._movers.items()}
        out = []
        for obstacle in self.world.obstacles:
            if obstacle.name in moved:
                position, _ = self._call(pybullet.getBasePositionAndOrientation, moved[obstacle.name])
                out.append((obstacle, tuple(position)))
            else:
                out.append((obstacle, tuple(obstacle.position)))
        return out

    @property
    def obstacle_uids(self):
        """The body uids holding the world's obstacles (a static group's compound, each moving obstacle's own)."""
        return [uid for uid, held in self._bodies.items() if uid not in self._robot_ids]

    def obstacles_near(self, x, y, reach_m):
        """[(lower bound m, uid)] of the bodies holding an obstacle whose footprint comes within ``reach_m`` of
        the point (x, y), or may, nearest bound first: the bound is the distance from the point to a circle
        round the nearest such footprint, never more than the distance to the footprint itself."""
        centres = self._extent_centres
        if self._movers:
            centres = centres.copy()
            for index, uid in enumerate(self._extent_uids):
                if int(uid) in self._movers:
                    centres[index] = self._call(pybullet.getBasePositionAndOrientation, int(uid))[0][:2]
        bounds = numpy.hypot(centres[:, 0] - x, centres[:, 1] - y) - self._extent_radii
        near = numpy.flatnonzero(bounds <= reach_m)
        if not len(near):
            return []
        least = numpy.full(len(self._extent_body_uids), numpy.inf)      # each body's nearest bound
        numpy.minimum.at(least, self._extent_body[near], bounds[near])
        order = numpy.argsort(least, kind='stable')[:len(near)]
        return [(float(least[b]), int(self._extent_body_uids[b])) for b in order if least[b] <= reach_m]

    def nearest_obstacle_m(self, x, y, within_m):
        """A lower bound (m) on the distance across the ground from the point (x, y) to every obstacle's
        footprint (a static obstacle's own, a moving one's circle), or ``within_m`` when none comes nearer."""
        if self._movers:
            near = self.obstacles_near(x, y, within_m)
            return near[0][0] if near else within_m
        centres = self._extent_centres
        bounds = numpy.hypot(centres[:, 0] - x, centres[:, 1] - y) - self._extent_radii
        least = within_m
        for i in numpy.flatnonzero(bounds < within_m)[numpy.argsort(bounds[bounds < within_m])]:
            if bounds[i] >= least:
                break
            least = min(least, shapes.distance(self.world.obstacles[i], x, y))
        return least

    @property
    def has_moving_obstacles(self):
        return bool(self._movers)

    def rotation_matrix(self, quaternion):
        """The 3x3 rotation matrix of a quaternion (x, y, z, w)."""
        return numpy.array(self._call(pybullet.getMatrixFromQuaternion, quaternion)).reshape(3, 3)

    def cast_rays_masked(self, ray_from, ray_to, collision_filter_mask=ALL_GROUPS):
        """Cast rays (two (N, 3) arrays, m); (body uid of the first hit or -1, hit fraction) per ray. Only
        shapes whose collision group is in ``collision_filter_mask`` are hit."""
        hits = self._call(pybullet.rayTestBatch, ray_from.tolist(), ray_to.tolist(),
                          collisionFilterMask=collision_filter_mask)
        n = len(hits)
        return (numpy.fromiter((h[0] for h in hits), dtype=numpy.int64, count=n),
                numpy.fromiter((h[2] for h in hits), dtype=numpy.float64, count=n))

    def render(self, width, height, eye, target, up, vertical_fov_deg, near_m, far_m):
        """An RGBA image (height, width, 4) uint8 seen from ``eye`` toward ``target`` with ``up`` up."""
        view = self._call(pybullet.computeViewMatrix, list(eye), list(target), list(up))
        projection = self._call(pybullet.computeProjectionMatrixFOV, vertical_fov_deg, width / height, near_m, far_m)
        _, _, rgba, _, _ = self._call(pybullet.getCameraImage, width, height, view, projection,
                                      renderer=pybullet.ER_TINY_RENDERER, flags=pybullet.ER_NO_SEGMENTATION_MASK)
        return numpy.asarray(rgba, dtype=numpy.uint8).reshape(height, width, 4)

    def close(self):
        if self._client is not None and self._client >= 0:
            if self._gui or len(_IDLE_CLIENTS) >= MAX_IDLE_CLIENTS:
                pybullet.disconnect(physicsClientId=self._client)
            else:
                # Kept for the next Simulation of this process, which empties it first (_build: resetSimulation,
                # then everything set again): a batch of short episodes saves pybullet's connection, about 20 ms
                # each.
                _IDLE_CLIENTS.append(self._client)
            self._client = None
