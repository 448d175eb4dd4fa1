"""Episodes in one process: the simulator's core and a controller's core (``closed_loop.controllers``)
stepped in lockstep, deterministic, free of ROS; for benchmarks and batches of scenarios
(``closed_loop.batch.sweep``).

An :class:`EpisodeSpec` names everything an episode depends on: the world (a shipped name, a file, or
``{'generator': ClutterSettings fields}``), the robot profile, the controller and its settings (checked by
the settings class its node uses), the LIDAR's noise and seed, the goal, the time limit. :func:`run_episode`
gives an :class:`EpisodeResult`; the same spec gives the same result and trajectory, bit for bit, in any
process (nothing in it reads a clock, and the noise has its own seeded generator).

Timing, as the graph has it, on simulated time: physics at ``physics_rate_hz``; a LIDAR scan every period,
handed to the controller at its stamp (in the graph it arrives a few milliseconds of wall time later,
within the physics step); the controller's timer at its ``rate_hz``, ``timer_phase_s`` (default 0.05 s,
half a LIDAR period: the mean of a phase the node's start-up puts anywhere) after each scan; a command, from the timer or at once from
a scan (new danger), reaches the wheels ``command_delay_s`` later. That delay is one physics step: the
reaction benchmark (``bench_loop``) measures scan-to-zero-command delivery of a few milliseconds at real
time, and the simulator applies a command at its next physics step. The camera is on only for a controller
that looks at it (the fusion controller), its frames half a period after the scans, as the simulator node
has them. The LIDAR is cast with the planar caster (``closed_loop.sim.planar_rays``): exact, and many times
cheaper in clutter.

Everything judged comes from ground truth: contacts every physics step, the least clearance between the
robot's collision shapes and any obstacle at the controller's rate, the path, the deceleration.
"""
import dataclasses
import math
import time
from typing import Optional

import cv2

from closed_loop.sim import clutter
from closed_loop.commands import validate_command
from closed_loop.control.vision import VisionSettings, detect_red
from closed_loop.controllers import Context, ControllerError, Odom, controller_class
from closed_loop.geometry import quaternion_yaw
from closed_loop.sim.profiles import PACKAGE_ROOT, load_profile
from closed_loop.sim.rig import Rig
from closed_loop.control.scan import Scan
from closed_loop.sim.sensors.camera import Camera
from closed_loop.sim.sensors.lidar import Lidar
from closed_loop.settings import SettingsError, check
from closed_loop.sim.world import load_world, parse_world, resolve_world

#: A goal counts as reached when ground truth ends this close to it (m), with no contact.
SUCCESS_RADIUS_M = 0.4
#: Clearance to obstacles is looked for up to this far (m); beyond, it reads as this.
CLEARANCE_LOOKOUT_M = 2.0
#: At rest: ground-truth speeds under these (m/s, rad/s), under a zero command, for REST_HOLD_S.
REST_MPS, REST_RADPS, REST_HOLD_S = 1e-3, 1e-3, 1.0
OUTCOMES = ('reached', 'stopped', 'failed', 'timed_out', 'collided', 'error')


class EpisodeError(ValueError):
    """An unusable episode spec; the message names the field and what was expected."""


@dataclasses.dataclass(frozen=True)
class EpisodeSpec:
    """Everything one episode depends on. ``world``: a world name, a world file, or ``{'generator': {...}}``
    (``closed_loop.sim.clutter.ClutterSettings`` fields); ``robot``: a profile name; ``controller``: a
    controller name; ``settings``: its ``~parameters`` over the profile's; ``sim``: the simulator's and its
    sensors' over the profile's; ``scan_noise``: the LIDAR's noise (m, std) and ``seed`` its seed;
    ``goal``: (x, y) in the world frame for a controller that takes one (default: the world's ``goal:``,
    else its own default); ``time_limit_s``: simulated seconds; ``keep_trajectory``: keep a row per tick;
    ``end_on_contact``: end the episode at the physics step of its first contact (outcome 'collided',
    one contact), where a sweep asks only whether there was one."""
    world: object = 'wall'
    robot: str = 'closed_loop'
    controller: str = 'stop_on_obstacle'
    settings: dict = dataclasses.field(default_factory=dict)
    sim: dict = dataclasses.field(default_factory=dict)
    scan_noise: float = 0.0
    seed: int = 0
    goal: Optional[tuple] = None
    time_limit_s: float = 30.0
    keep_trajectory: bool = False
    end_on_contact: bool = False
    command_delay_s: float = 0.01
    timer_phase_s: float = 0.05

    def to_dict(self):
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data, where='episode'):
        """A spec from plain values (a sweep row, a YAML mapping); unknown or ill-typed fields are refused."""
        if not isinstance(data, dict):
            raise EpisodeError('%s: expected a mapping of episode fields, got %r' % (where, data))
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(data) - names)
        if unknown:
            raise EpisodeError('%s.%s: not an episode field (expected one of %s)'
                               % (where, unknown[0], ', '.join(sorted(names))))
        values = dict(data)
        if isinstance(values.get('goal'), list):
            values['goal'] = tuple(values['goal'])
        return cls(**values)


@dataclasses.dataclass
class EpisodeResult:
    """What one episode did. ``outcome``: 'reached' (the controller said REACHED and ground truth is within
    SUCCESS_RADIUS_M of the goal), 'stopped' (at rest under a zero command for REST_HOLD_S), 'failed'
    (FAILED, or REACHED by odometry only), 'timed_out', 'collided' (any contact; it wins over the others),
    or 'error' (the episode raised: ``error`` says what). ``time_s``: when it came to rest, reached, or
    ended. ``final_pose``: ground truth (x, y, yaw) in the world frame. ``trajectory`` (on request): per
    tick (t, x, y, yaw, speed, command v, command w, mode)."""
    outcome: str
    mode: Optional[str] = None
    time_s: float = 0.0
    contacts: int = 0
    min_clearance_m: float = math.inf
    final_pose: tuple = (math.nan, math.nan, math.nan)
    goal_error_m: Optional[float] = None
    path_m: float = 0.0
    peak_decel_mps2: float = 0.0
    wall_s: float = 0.0
    decision_ms: list = dataclasses.field(default_factory=list)
    #: Other costs the controller measured, {name: [ms, ...]} (the fusion controller's ``fusion_ms``).
    timings: dict = dataclasses.field(default_factory=dict)
    trajectory: Optional[list] = None
    error: Optional[str] = None


def load_episode_world(spec_world, profile):
    """The :class:`closed_loop.sim.world.World` a spec's ``world`` names."""
    if isinstance(spec_world, dict):
        if set(spec_world) != {'generator'} or not isinstance(spec_world['generator'], dict):
            raise EpisodeError("world: expected a world name, a file, or {'generator': {...}}, got %r"
                               % (spec_world,))
        try:
            settings = clutter.ClutterSettings(**dict({'profile': profile.name}, **spec_world['generator']))
        except TypeError as error:
            raise EpisodeError('world.generator: %s' % error)
        try:
            raw = clutter.generate(settings.check(), load_profile(settings.profile))
        except clutter.ClutterError as error:
            raise EpisodeError('world.generator.%s' % error)
        return parse_world(raw, raw['name'], footprint=profile.footprint)
    return load_world(resolve_world(spec_world, '%s/worlds' % PACKAGE_ROOT), footprint=profile.footprint)


def controller_settings(cls, values):
    """The controller's settings classes built from ``values`` ({name: value}), each checked as its node
    checks it; a name no class has is refused."""
    classes = (cls.settings_class,) + tuple(cls.extra_settings_classes)
    known = {f.name: c for c in classes for f in dataclasses.fields(c)}
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise EpisodeError('settings.%s: not a parameter of %s' % (unknown[0], cls.name))
    built = []
    for c in classes:
        try:
            built.append(check(c(**{k: v for k, v in values.items() if known[k] is c})))
        except SettingsError as error:
            raise EpisodeError('settings: %s' % error)
    return built


def _to_odom(start, x, y):
    """A world point in the odom frame, which starts at the robot's start pose."""
    dx, dy = x - start.x, y - start.y
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    return c * dx + s * dy, -s * dx + c * dy


@dataclasses.dataclass
class Prepared:
    """What :func:`prepare` makes of a spec, everything but the simulation."""
    profile: object
    controller_class: type
    world: object
    settings: object
    sim_params: dict
    goal_odom: Optional[tuple]
    goal_world: Optional[tuple]
    extra_settings: list = dataclasses.field(default_factory=list)


def prepare(spec, cache=None):
    """Check ``spec`` and resolve it (profile, controller, world, settings, goal) without simulating;
    raise :class:`EpisodeError` naming the field that is wrong. ``cache``: a dict kept between calls, so
    many specs over a few worlds and robots load each once."""
    cache = {} if cache is None else cache
    key = ('robot', spec.robot)
    try:
        if key not in cache:
            cache[key] = load_profile(spec.robot)
    except (TypeError, ValueError) as error:
        raise EpisodeError('robot: %s' % error)
    profile = cache[key]
    try:
        cls = controller_class(spec.controller)
    except ControllerError as error:
        raise EpisodeError(str(error))
    key = ('world', repr(spec.world), spec.robot)
    try:
        if key not in cache:
            cache[key] = load_episode_world(spec.world, profile)
    except EpisodeError:
        raise
    except (TypeError, ValueError) as error:
        raise EpisodeError('world: %s' % error)
    world = cache[key]
    if not isinstance(spec.settings, dict) or not isinstance(spec.sim, dict):
        raise EpisodeError('settings, sim: expected mappings of ~parameters')
    settings, *extra = controller_settings(cls, dict(profile.node_params(cls.name), **spec.settings))
    sim_params = dict(profile.node_params('sim'), camera=cls.uses_camera, ray_caster='planar',
                      scan_noise_stddev=spec.scan_noise, noise_seed=spec.seed)
    sim_params.update(spec.sim)
    try:
        Rig.check_params(sim_params)
    except SettingsError as error:
        raise EpisodeError('sim: %s' % error)
    for name, low in (('time_limit_s', 0.0), ('command_delay_s', 0.0), ('timer_phase_s', 0.0)):
        value = getattr(spec, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or value < low:
            raise EpisodeError('%s: expected a number of s, at least %g, got %r' % (name, low, value))
    for name in ('keep_trajectory', 'end_on_contact'):
        if not isinstance(getattr(spec, name), bool):
            raise EpisodeError('%s: expected true or false, got %r' % (name, getattr(spec, name)))
    start = world.robot_start
    goal_world = tuple(spec.goal) if spec.goal is not None else world.goal
    if goal_world is not None and (len(goal_world) != 2 or not all(
            isinstance(v, (int, float)) and math.isfinite(v) for v in goal_world)):
        raise EpisodeError('goal: expected [x, y] in m, got %r' % (spec.goal,))
    goal = _to_odom(start, *goal_world) if goal_world is not None else None
    if goal is None and extra and getattr(extra[0], 'goal_distance', 0.0) > 0.0:
        d = extra[0].goal_distance
        goal = (d, 0.0)
        goal_world = (start.x + d * math.cos(start.yaw), start.y + d * math.sin(start.yaw))
    return Prepared(profile, cls, world, settings, sim_params, goal, goal_world, extra)


def run_episode(spec, cache=None):
    """Run ``spec`` (an :class:`EpisodeSpec`); an unusable spec raises :class:`EpisodeError`."""
    started = time.monotonic()
    p = prepare(spec, cache)
    laser_pose = p.profile.laser_pose(p.settings.scan_frame)
    rig = Rig(p.world, p.sim_params, p.profile.urdf)
    try:
        try:
            camera_pose = p.profile.laser_pose(rig.sim.model.names.camera_frame)
        except ValueError:
            camera_pose = None
        controller = p.controller_class(p.settings, Context(laser_pose, p.profile.footprint, p.goal_odom,
                                                            camera_pose), *p.extra_settings)
        controller.record_timings = True
        result = _loop(spec, rig, controller, p.goal_world)
    finally:
        rig.close()
    result.decision_ms = getattr(controller, 'decision_ms', [])
    result.timings = dict(getattr(controller, 'timings', {}))
    result.wall_s = time.monotonic() - started
    return result


def _loop(spec, rig, controller, goal_world):
    sim = rig.sim
    lidar = rig.sensors[Lidar]
    layout, ls = lidar.layout, lidar.settings
    dt = sim.dt_s
    steps_per_scan = max(1, int(round(lidar.period_s / dt)))
    steps_per_tick = max(1, int(round(1.0 / controller.settings.rate_hz / dt)))
    phase = int(round(spec.timer_phase_s / dt)) % steps_per_tick
    delay = max(1, int(round(spec.command_delay_s / dt)))
    camera = rig.sensors.get(Camera) if controller.uses_camera else None
    if camera is not None:
        steps_per_frame = max(1, int(round(camera.period_s / dt)))
        frame_phase = int(round(camera.offset_s / dt)) % steps_per_frame
        vision = VisionSettings()
        controller.on_camera_info(camera.intrinsics.fx, camera.intrinsics.cx, camera.intrinsics.width)
    pending = []                      # (step, command), in order
    contacts, touching, clearance, path_m, peak_decel = 0, set(), math.inf, 0.0, 0.0
    pose, _ = sim.ground_truth()
    last_xy, last_speed, last_t = pose.position[:2], 0.0, 0.0
    trajectory = [] if spec.keep_trajectory else None
    command, rest_since, ended_s = (0.0, 0.0), None, None
    last = int(round(spec.time_limit_s / dt))
    for k in range(last + 1):
        now = sim.time_s
        sent = odom = None
        scan_due, frame_due = k % steps_per_scan == 0, camera is not None and k % steps_per_frame == frame_phase
        if scan_due or frame_due or k % steps_per_tick == phase:
            odo = sim.odometry
            odom = Odom(odo.x, odo.y, odo.yaw, odo.twist.linear_x, odo.twist.angular_z, now)
        if scan_due:
            scan = Scan(now, lidar.frame, layout.angle_min, layout.angle_max, layout.angle_increment, 0.0,
                        lidar.period_s, ls.range_min, ls.range_max, lidar.sample(sim))
            sent = controller.on_scan(now, scan, odom)
        if frame_due:
            # What vision_node does in the graph: a red_centroid only for a frame with red in it.
            found = detect_red(cv2.cvtColor(camera.sample(sim), cv2.COLOR_RGB2BGR), vision)
            if found.detected:
                controller.on_detection(found.centroid_px[0], now, odom)
        if k % steps_per_tick == phase:
            sent = controller.on_tick(now, odom)
            controller.take_transitions()       # what the node logs; an episode keeps only the mode
            pose, (linear, angular) = sim.ground_truth()
            x, y = pose.position[:2]
            yaw = quaternion_yaw(pose.orientation)
            speed = linear[0] * math.cos(yaw) + linear[1] * math.sin(yaw)       # forward, signed
            clearance = min(clearance, sim.clearance(CLEARANCE_LOOKOUT_M))
            path_m += math.hypot(x - last_xy[0], y - last_xy[1])
            if now > last_t:
                peak_decel = max(peak_decel, (abs(last_speed) - abs(speed)) / (now - last_t))
            last_xy, last_speed, last_t = (x, y), speed, now
            if trajectory is not None:
                trajectory.append((now, x, y, yaw, speed, command[0], command[1], controller.mode))
            at_rest = abs(speed) < REST_MPS and abs(angular[2]) < REST_RADPS and command == (0.0, 0.0)
            rest_since = (rest_since if rest_since is not None else now) if at_rest else None
            if controller.finished and at_rest:
                ended_s = now
                break
            if rest_since is not None and controller.ends_at_rest and now - rest_since >= REST_HOLD_S:
                ended_s = rest_since
                break
        if sent is not None:
            pending.append((k + delay, validate_command(*sent)))
        while pending and pending[0][0] <= k:
            _, cmd = pending.pop(0)
            command = (cmd.linear_x, cmd.angular_z)
            sim.command(cmd)
        if k == last:
            break           # judged at the time limit, not a step past it
        sim.step()
        now_touching = sim.contacts_with_obstacles()
        contacts += len(now_touching - touching)      # a contact counts once, when it begins
        touching = now_touching
        if contacts and spec.end_on_contact:
            ended_s = sim.time_s
            break
    pose, _ = sim.ground_truth()
    final = (pose.position[0], pose.position[1], quaternion_yaw(pose.orientation))
    error = None if goal_world is None else math.hypot(goal_world[0] - final[0], goal_world[1] - final[1])
    if contacts:
        outcome = 'collided'
    elif controller.mode == 'REACHED':
        outcome = 'reached' if error is not None and error <= SUCCESS_RADIUS_M else 'failed'
    elif controller.mode == 'FAILED':
        outcome = 'failed'
    elif ended_s is not None:
        outcome = 'stopped'
    else:
        outcome = 'timed_out'
    return EpisodeResult(outcome, controller.mode, ended_s if ended_s is not None else sim.time_s, contacts,
                         clearance, final, error, path_m, peak_decel, trajectory=trajectory)
