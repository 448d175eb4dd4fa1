"""What an episode is, checked: :class:`EpisodeSpec` (everything an episode depends on), :func:`prepare` (the spec
resolved, or :class:`EpisodeError` naming the field that is wrong), :class:`EpisodeResult`, and the judge's
settings for a spec. Shared by the two ways an episode runs (``closed_loop.batch.episode``): in process
(``closed_loop.batch.lockstep``) and as a ROS graph (``closed_loop.batch.graph_episode``)."""
import dataclasses
import math
import os
import re
from typing import Optional

from closed_loop.sim import barn_score, generators
from closed_loop.controllers import ControllerError, controller_class, controller_classes
from closed_loop.sim.profiles import PACKAGE_ROOT, load_profile
from closed_loop.batch import workspace
from closed_loop.batch.judge import JudgeSettings, Verdict
from closed_loop.sim.rig import Rig
from closed_loop.settings import SettingsError, check
from closed_loop.sim.world import WorldError, load_world, parse_world, resolve_world
from closed_loop.sim.world_robots import with_start
from closed_loop.yaml_check import quote

#: A goal counts as reached when ground truth ends this close to it (m), with no contact.
SUCCESS_RADIUS_M = JudgeSettings().success_radius


#: The keys of a graph episode's controller mapping, and what a package name and an arg name look like.
CONTROLLER_KEYS = ('launch', 'args', 'node', 'mode_topic', 'end_at_rest', 'workspace', 'fresh_graph')
PACKAGE = re.compile(r'^[A-Za-z][A-Za-z0-9_]*$')
ARG_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*$')


class EpisodeError(ValueError):
    """An unusable episode spec; the message names the field and what was expected."""


@dataclasses.dataclass(frozen=True)
class EpisodeSpec:
    """Everything one episode depends on. ``world``: a world name, a world file, or ``{'generator': {...}}``
    (``closed_loop.sim.generators``: a method and its settings); ``robot``: a profile name; ``controller``: a
    controller name; ``settings``: its ``~parameters`` over the profile's; ``sim``: the simulator's and its
    sensors' over the profile's; ``scan_noise``: the LIDAR's noise (m, std) and ``seed`` its seed;
    ``goal``: (x, y) in the world frame for a controller that takes one (default: the world's ``goal:``,
    else its own default); ``time_limit_s``: simulated seconds; ``keep_trajectory``: keep a row per tick;
    ``end_on_contact``: end the episode at the physics step of its first contact (outcome 'collided',
    one contact), where a sweep asks only whether there was one. A ``controller`` that is a mapping makes a
    graph episode (``closed_loop.batch.graph_episode``): ``{launch: PKG/path.launch, args: {...}}`` or
    ``{node: NAME}`` (``workspace: PATH``: the launch file's package as that catkin workspace has it,
    ``closed_loop.batch.workspace``), its simulator in lockstep with it (``real_time_factor`` None), or in real time at that many
    simulated s per wall s, for a node that cannot be lockstepped. ``command_delay_s`` is when a command reaches
    the wheels, in process and in a lockstepped graph alike."""
    world: object = 'wall'
    robot: str = 'closed_loop'
    controller: object = 'stop_on_obstacle'
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
    real_time_factor: Optional[float] = None

    def to_dict(self):
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data, where='episode'):
        """A spec from plain values (a sweep row, a YAML mapping); unknown or ill-typed fields are refused."""
        if not isinstance(data, dict):
            raise EpisodeError('%s: expected a mapping of episode fields, got %s' % (where, quote(data)))
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
class EpisodeResult(Verdict):
    """What one episode did: the judge's :class:`closed_loop.batch.judge.Verdict` (the outcome, 'reached',
    'stopped', 'failed', 'timed_out' or 'collided', by the rules written there; or 'error', when the
    episode could not run: ``error`` says why), the costs measured, and on request (``keep_trajectory``)
    the trajectory, a row per judged instant (t, x, y, yaw, speed, command v, command w, mode, clearance:
    ``closed_loop.batch.judge.TRACK_FIELDS``), and the contacts, a row each (t, x, y, yaw, [obstacles])."""
    wall_s: float = 0.0
    #: How long it ran in simulated time (s): its time limit, or when the judge ended it (at rest a while after
    #: ``time_s``, or at a contact); 0 for a graph episode, whose simulator runs apart.
    simulated_s: float = 0.0
    decision_ms: list = dataclasses.field(default_factory=list)
    #: Other costs the controller measured, {name: [ms, ...]} (the fusion controller's ``fusion_ms``).
    timings: dict = dataclasses.field(default_factory=dict)
    trajectory: Optional[list] = None
    contact_log: Optional[list] = None
    error: Optional[str] = None
    #: A graph episode's folder of logs (None in process).
    logs: Optional[str] = None


def load_episode_world(spec_world, profile, check_starts=True):
    """The :class:`closed_loop.sim.world.World` a spec's ``world`` names (its starts checked free for the
    profile's footprint unless not ``check_starts``)."""
    if isinstance(spec_world, dict):
        raw = generated_world(spec_world, profile)
        return parse_world(raw, raw['name'], footprint=profile.footprint, check_starts=check_starts)
    return load_world(resolve_world(spec_world, '%s/worlds' % PACKAGE_ROOT), footprint=profile.footprint,
                      check_starts=check_starts)


def generated_world(spec_world, profile):
    """The world dict of a spec's ``{'generator': {...}}`` (``closed_loop.sim.generators``) for ``profile``."""
    if set(spec_world) != {'generator'} or not isinstance(spec_world['generator'], dict):
        raise EpisodeError("world: expected a world name, a file, or {'generator': {...}}, got %s"
                           % (quote(spec_world),))
    try:
        settings = generators.settings_from(spec_world['generator'], profile.name)
        return generators.generate(settings, profile if settings.profile == profile.name else None)
    except generators.GeneratorError as error:
        raise EpisodeError('world.generator.%s' % error)


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
    #: A graph episode's controller (``closed_loop.batch.graph_episode``), or None in process.
    graph: Optional[dict] = None


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
    graph = None
    if isinstance(spec.controller, dict):
        graph = parse_controller(spec.controller, controller_classes())
        name = graph.get('node')
    else:
        name = spec.controller
    try:
        cls = controller_class(name) if name is not None else None
    except ControllerError as error:
        raise EpisodeError(str(error))
    if not isinstance(spec.settings, dict) or not isinstance(spec.sim, dict):
        raise EpisodeError('settings, sim: expected mappings of ~parameters')
    if cls is not None:
        settings, *extra = controller_settings(cls, dict(profile.node_params(cls.name), **spec.settings))
    elif spec.settings:
        raise EpisodeError("settings: a launch file's controller takes args (controller.args), not settings")
    else:
        settings, extra = None, []
    sim_params = dict(profile.node_params('sim'), camera=bool(cls and cls.uses_camera), ray_caster='planar',
                      scan_noise_stddev=spec.scan_noise, noise_seed=spec.seed)
    sim_params.update(spec.sim)
    try:
        start = Rig.check_params(sim_params)[0].start_pose
    except SettingsError as error:
        raise EpisodeError('sim: %s' % error)
    # A start of the episode's own stands in for the world's, which is then not checked (a Gazebo world or a
    # map has none: its origin, which may be in a wall).
    key = ('world', repr(spec.world), spec.robot, start is None)
    try:
        if key not in cache:
            cache[key] = load_episode_world(spec.world, profile, check_starts=start is None)
    except EpisodeError:
        raise
    except (TypeError, ValueError) as error:
        raise EpisodeError('world: %s' % error)
    world = cache[key]
    if start is not None:               # sim: {start: 'x y yaw'}: where the robot starts, in place of the world's
        try:
            world = with_start(world, start, profile.footprint, WorldError, 'sim.start')
        except WorldError as error:
            raise EpisodeError(str(error))
    for name, low in (('time_limit_s', 0.0), ('command_delay_s', 0.0), ('timer_phase_s', 0.0)):
        value = getattr(spec, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) \
                or value < low:
            raise EpisodeError('%s: expected a number of s, at least %g, got %s' % (name, low, quote(value)))
    for name in ('keep_trajectory', 'end_on_contact'):
        if not isinstance(getattr(spec, name), bool):
            raise EpisodeError('%s: expected true or false, got %s' % (name, quote(getattr(spec, name))))
    rtf = spec.real_time_factor
    if rtf is not None and (isinstance(rtf, bool) or not isinstance(rtf, (int, float)) or not 0.1 <= rtf <= 20.0):
        raise EpisodeError('real_time_factor: expected a number from 0.1 to 20 (simulated s per wall s), got %s'
                           % (quote(rtf),))
    start = world.robot_start
    goal_world = tuple(spec.goal) if spec.goal is not None else world.goal
    if goal_world is not None and (len(goal_world) != 2 or not all(
            isinstance(v, (int, float)) and math.isfinite(v) for v in goal_world)):
        raise EpisodeError('goal: expected [x, y] in m, got %s' % (quote(spec.goal),))
    goal = _to_odom(start, *goal_world) if goal_world is not None else None
    if goal is None and extra and getattr(extra[0], 'goal_distance', 0.0) > 0.0:
        d = extra[0].goal_distance
        goal = (d, 0.0)
        goal_world = (start.x + d * math.cos(start.yaw), start.y + d * math.sin(start.yaw))
    return Prepared(profile, cls, world, settings, sim_params, goal, goal_world, extra, graph)


def judge_settings(spec, controller_class):
    """The judge's settings for ``spec``: its time limit and end on contact, and whether the controller ends
    at rest (a stop controller) or waits and goes on (a navigator)."""
    return JudgeSettings(success_radius=SUCCESS_RADIUS_M, time_limit=spec.time_limit_s,
                         end_at_rest=controller_class.ends_at_rest if controller_class else True,
                         end_on_contact=spec.end_on_contact)


def result_from_verdict(verdict, **extra):
    """An :class:`EpisodeResult` with the :class:`closed_loop.batch.judge.Verdict`'s fields."""
    fields = {f.name: getattr(verdict, f.name) for f in dataclasses.fields(Verdict)}
    return EpisodeResult(**dict(fields, **extra))


def benchmark_score(spec, result):
    """The BARN benchmark's score of the episode ``spec`` that gave ``result`` (``closed_loop.sim.barn_score``),
    in a world of the benchmark's method (``{'generator': {'method': 'barn', ...}}``); None in any other."""
    world = spec.world
    generator = world.get('generator') if isinstance(world, dict) else None
    if not isinstance(generator, dict) or generator.get('method') != 'barn':
        return None
    optimal = barn_score.optimal_s(generators.settings_from(generator, spec.robot))
    return barn_score.score(result.contacts, result.benchmark_time_s, optimal)


def parse_controller(value, node_names):
    """A graph controller from an episode's ``controller`` mapping: ``{launch: PKG/path.launch or /abs/path,
    args: {NAME: VALUE}}`` or ``{node: NAME}`` (one of ``node_names``), with optional ``mode_topic`` (the
    controller's mode, for the judge), ``end_at_rest`` and ``fresh_graph``; raises EpisodeError naming the field."""
    unknown = sorted(set(value) - set(CONTROLLER_KEYS))
    if unknown:
        raise EpisodeError('controller.%s: expected one of %s' % (unknown[0], ', '.join(CONTROLLER_KEYS)))
    if ('launch' in value) == ('node' in value):
        raise EpisodeError('controller: expected a launch file (launch: PKG/path.launch) or a node of this package '
                           '(node: NAME), one of them, got %s' % (quote(value),))
    if 'node' in value and value['node'] not in node_names:
        raise EpisodeError('controller.node: expected one of %s, got %s' % (', '.join(sorted(node_names)), quote(value['node'])))
    if 'launch' in value:
        launch = value['launch']
        if not isinstance(launch, str) or not launch.endswith(('.launch', '.xml')):
            raise EpisodeError('controller.launch: expected PKG/path/file.launch or an absolute path, got %s' % (quote(launch),))
        if '$(' in launch:
            raise EpisodeError('controller.launch: %r has "$(" in it, which roslaunch would take for a substitution'
                               % (launch,))
        parts = launch.split('/')
        if not os.path.isabs(launch) and (not PACKAGE.match(parts[0]) or len(parts) < 2 or '..' in parts):
            raise EpisodeError('controller.launch: expected PKG/path/file.launch (a package name, then a path in '
                               'it) or an absolute path, got %s' % (quote(launch),))
    args = value.get('args') or {}
    if not isinstance(args, dict) or 'node' in value and args:
        raise EpisodeError('controller.args: expected a mapping of a launch file\'s args, got %s' % (quote(args),))
    for name, arg in args.items():
        if not isinstance(name, str) or not ARG_NAME.match(name):
            raise EpisodeError('controller.args: %s is not an arg name' % (quote(name),))
        if not isinstance(arg, (str, int, float, bool)) or '$(' in str(arg):
            raise EpisodeError('controller.args.%s: expected a string, number or boolean (no $(...) substitution), '
                               'got %s' % (name, quote(arg)))
    if 'workspace' in value:
        place = value['workspace']
        if not isinstance(place, str) or not os.path.isabs(os.path.expanduser(place)):
            raise EpisodeError('controller.workspace: expected the absolute path of a catkin workspace, got %s'
                               % (quote(place),))
        try:
            workspace.prefix_of(place)
        except workspace.WorkspaceError as error:
            raise EpisodeError('controller.workspace: %s' % error)
    if not isinstance(value.get('mode_topic', ''), str) or not isinstance(value.get('end_at_rest', True), bool):
        raise EpisodeError('controller: mode_topic is a topic name and end_at_rest true or false')
    if not isinstance(value.get('fresh_graph', False), bool):
        raise EpisodeError('controller.fresh_graph: expected true (each episode in a graph of its own) or false, got %s'
                           % (quote(value['fresh_graph']),))
    return value
