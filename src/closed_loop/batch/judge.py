"""The judge: what a scenario's robot did, decided on ground truth, with one set of rules for an in-process
episode (``closed_loop.batch.episode``) and a ROS graph (the ``scenario_judge`` node). Free of ROS.

It is given, on simulated time: the robot's true state at its own period (:meth:`Judge.due`,
:meth:`Judge.observe`: pose, forward speed, yaw rate, the command the base was given, and the controller's
mode where it has one), each contact as it begins, and the least clearance between the robot's collision
shapes and any obstacle. It says when the scenario is over (:attr:`Judge.ended`) and gives the
:class:`Verdict`.

The rules. The robot is *at rest* when its speed and yaw rate are under ``rest_speed`` and
``rest_yaw_rate`` and the command is zero (no command counts as zero: the base brakes without one); it
stays at rest while the command stays zero, it keeps within ``rest_speed`` x ``rest_hold`` (m) of where it
came to rest and its yaw rate stays under ``rest_rock_yaw_rate`` (a base held at zero rocks on its wheels
and creeps round a few hundredths of a radian without going anywhere). The
scenario ends: at the first contact, with ``end_on_contact``; when the controller says REACHED or FAILED
and the robot is at rest; when it has been at rest for ``rest_hold`` within ``success_radius`` of the
goal; when it has been at rest for ``rest_hold`` anywhere, with ``end_at_rest`` (a controller that stops
for good; a navigator that waits sets it false); at ``time_limit``. The outcome: ``collided`` with any
contact, whatever else; ``reached`` when the controller said REACHED within ``success_radius`` of the goal,
or the robot came to rest there; ``failed`` when the controller said FAILED, or REACHED elsewhere;
``stopped`` when it came to rest elsewhere; ``timed_out`` otherwise. What of a scenario test's expectations a
verdict breaks: :func:`problems` (the ``scenario_test`` node's check).
"""
import dataclasses
import math
from typing import Optional

from closed_loop.recording import TOPIC_NAME
from closed_loop.settings import SettingsError, param

OUTCOMES = ('reached', 'stopped', 'failed', 'timed_out', 'collided', 'error')
#: The BARN benchmark's clock (its harness, since February 2024): from when the robot is this far (m) from where
#: it started, until it is within this distance (m) of the goal.
BENCHMARK_START_M, BENCHMARK_GOAL_M = 0.1, 1.0
REACHED, FAILED = 'REACHED', 'FAILED'


@dataclasses.dataclass
class JudgeSettings:
    """How a scenario is judged (the ``scenario_judge`` node's ``~parameters``; an episode's from its spec)."""
    success_radius: float = param(0.4, 'm', 'the goal counts as reached with ground truth this close to it',
                                  minimum=0.0, exclusive_minimum=True)
    time_limit: float = param(60.0, 's', 'the scenario ends at this simulated time', minimum=0.0,
                              exclusive_minimum=True)
    rest_speed: float = param(0.005, 'm/s', 'at rest: ground-truth speed under this (and the yaw rate under '
                              'rest_yaw_rate, under a zero command)', minimum=0.0, exclusive_minimum=True)
    rest_yaw_rate: float = param(0.01, 'rad/s', 'at rest: ground-truth yaw rate under this', minimum=0.0,
                                 exclusive_minimum=True)
    rest_rock_yaw_rate: float = param(0.1, 'rad/s', 'once at rest, it stays at rest while the command stays zero, '
                                      'its yaw rate stays under this and it keeps within rest_speed x rest_hold '
                                      'of where it came to rest (a base held at zero rocks on its wheels)',
                                      minimum=0.0)
    rest_hold: float = param(1.0, 's', 'at rest this long ends the scenario (see end_at_rest)', minimum=0.0)
    first_command_wait: float = param(3.0, 's', 'a robot no command to move has reached yet (none, or only zeros) '
                                      'is not judged at rest before this simulated time (a graph\'s controller may '
                                      'answer its first scan late at a high real_time_factor)', minimum=0.0)
    end_at_rest: bool = param(True, '', 'true: at rest for rest_hold anywhere ends it (stopped); false: only '
                              'within success_radius of the goal (a navigator that waits and goes on)')
    end_on_contact: bool = param(False, '', 'end at the first contact (outcome collided)')
    period: float = param(0.1, 's', 'ground truth is judged at this period of simulated time', minimum=0.01,
                          maximum=1.0)


@dataclasses.dataclass
class StartSettings:
    """How a scenario in a ROS graph starts (the ``scenario_judge`` node's ``~parameters``): the simulator
    waits, paused at t = 0, until the controller is up, so that a controller that takes a while to start
    (a C++ node loading, a launch file of several nodes) meets the same world as an in-process episode's."""
    unpause: str = param('', '', "the simulator's unpause service (scenario.launch: /sim/unpause_physics, with the "
                         "simulator started paused), called once the controller is up; empty: none (the judge), "
                         "required (start_when_ready)")
    ready_timeout: float = param(30.0, 's', 'wall time to wait for a node that publishes cmd_vel, and for its '
                                 'connections, before starting the simulation anyway (a warning says what was '
                                 'missing)', minimum=0.0)
    settle: float = param(0.2, 's', "wall time between the controller's connections being made (from what it "
                          'subscribes to, to what reads its cmd_vel) and the start', minimum=0.0)
    wait_for: str = param('', '', 'more topics, separated by spaces, that must have a publisher before the start '
                          "(scenario.launch's bag: the scenario recorder's ~recording, once it is connected)")

    def check_together(self):
        for topic in self.wait_for.split():
            if not TOPIC_NAME.match(topic):
                raise SettingsError('~wait_for: expected topic names separated by spaces, got %r' % (topic[:200],))


@dataclasses.dataclass
class Verdict:
    """What the robot did. ``time_s``: when it came to rest or ended; ``final_pose``: ground truth (x, y, yaw)
    in the world frame; ``goal_error_m``: its distance to the goal (None without one); ``commands``: how many
    commands the base was given; ``missed_ticks``: a lockstepped graph's instants at which a node stayed busy
    past the simulator's wait and the scenario went on without it (0 in process, and for a graph that missed
    none); ``why``: one line; ``benchmark_time_s``: the BARN benchmark's time (BENCHMARK_START_M from the start
    to within BENCHMARK_GOAL_M of the goal), None where it never came so near the goal."""
    outcome: str
    mode: Optional[str] = None
    time_s: float = 0.0
    contacts: int = 0
    min_clearance_m: float = math.inf
    final_pose: tuple = (math.nan, math.nan, math.nan)
    goal_error_m: Optional[float] = None
    path_m: float = 0.0
    peak_decel_mps2: float = 0.0
    commands: int = 0
    why: str = ''
    missed_ticks: int = 0
    benchmark_time_s: Optional[float] = None

    def to_dict(self):
        """Plain values (JSON: an infinite clearance is null)."""
        data = dataclasses.asdict(self)
        data['final_pose'] = list(self.final_pose)
        if not math.isfinite(self.min_clearance_m):
            data['min_clearance_m'] = None
        return data

    @classmethod
    def from_dict(cls, data):
        data = dict(data)
        data['final_pose'] = tuple(data['final_pose'])
        if data.get('min_clearance_m') is None:
            data['min_clearance_m'] = math.inf
        return cls(**data)


#: A track's row: the robot at one judged instant (``Judge(keep_track=True)``).
TRACK_FIELDS = ('t', 'x', 'y', 'yaw', 'speed', 'command_v', 'command_w', 'mode', 'clearance')


def track_from_dict(data):
    """(trajectory, contact_log) from :meth:`Judge.track_dict`'s values (None for what is not there)."""
    rows = data.get('trajectory')
    if rows is not None:
        rows = [tuple(row[:-1]) + (math.inf if row[-1] is None else row[-1],) for row in rows]
    log = data.get('contact_log')
    return rows, None if log is None else [tuple(row) for row in log]


class Judge:
    """See the module's docstring. ``goal``: (x, y) in the world frame, or None. ``keep_track``: keep
    :attr:`track`, a row per judged instant (:data:`TRACK_FIELDS`: the clearance is the latest given, +inf
    beyond the lookout), and :attr:`contact_log`, a row per contact begun (t, x, y, yaw, [obstacle names]),
    for a picture of the episode (``closed_loop.batch.pictures``)."""

    def __init__(self, settings, goal=None, keep_track=False):
        self.settings = settings
        self.track = [] if keep_track else None
        self.contact_log = [] if keep_track else None
        self._clearance_now = math.inf
        self.goal = None if goal is None else (float(goal[0]), float(goal[1]))
        self.contacts = 0
        self.commands = 0
        self.moves = 0               # the commands among them that were not zero
        self.clearance = math.inf
        self.path_m = 0.0
        self.peak_decel = 0.0
        self.mode = None
        self.ended = False
        self.ended_s = None
        self._next_s = 0.0
        self._last = None            # (t, x, y, speed) of the last observation
        self._pose = None
        self._rest_since = None
        self._rest_pose = None       # (x, y) where it came to rest, while it is at rest
        self._rest_end = False       # ended by resting (not by time or contact)
        self._at_rest = None         # (clearance, path, track length) when it came to rest
        self._first_xy = None        # where it was first observed
        self._moved_s = self._near_goal_s = None     # the benchmark's clock: started, stopped

    def due_from(self):
        """The simulated time (s) from which :meth:`due` is true (inf once the scenario is over)."""
        return math.inf if self.ended else self._next_s - 1e-9

    def due(self, t_s):
        """True when ground truth at ``t_s`` is to be observed (every ``period`` s of simulated time)."""
        return not self.ended and t_s >= self._next_s - 1e-9

    def on_contact(self, t_s, count=1, names=(), pose=None):
        """``count`` contacts began at ``t_s``, with the obstacles ``names`` (where known), the robot at ``pose``
        (x, y, yaw; default: as last observed)."""
        self.contacts += count
        if count and self.contact_log is not None:
            x, y, yaw = pose or self._pose or (math.nan, math.nan, math.nan)
            self.contact_log.append((t_s, x, y, yaw, list(names)))
        if count and self.settings.end_on_contact and not self.ended:
            self._end(t_s)

    def on_command(self, command):
        """The base was given a command, (m/s, rad/s)."""
        self.commands += 1
        if command[0] != 0.0 or command[1] != 0.0:
            self.moves += 1

    def on_clearance(self, clearance_m):
        self.clearance = min(self.clearance, clearance_m)
        self._clearance_now = clearance_m

    def goal_error(self, x, y):
        return None if self.goal is None else math.hypot(self.goal[0] - x, self.goal[1] - y)

    def observe(self, t_s, x, y, yaw, speed, yaw_rate, command=None, mode=None):
        """The robot's ground truth at ``t_s``: pose (m, rad) in the world frame, forward speed (m/s, signed),
        yaw rate (rad/s), the command the base has (m/s, rad/s; None: none), the controller's mode (None:
        none). Returns True once the scenario is over."""
        s = self.settings
        self._next_s = t_s + s.period
        self.mode = mode if mode is not None else self.mode
        if self._last is not None:
            t0, x0, y0, speed0 = self._last
            self.path_m += math.hypot(x - x0, y - y0)
            if t_s > t0:
                self.peak_decel = max(self.peak_decel, (abs(speed0) - abs(speed)) / (t_s - t0))
        self._last = (t_s, x, y, speed)
        self._pose = (x, y, yaw)
        self._first_xy = self._first_xy or (x, y)
        if self._moved_s is None and math.hypot(x - self._first_xy[0], y - self._first_xy[1]) >= BENCHMARK_START_M:
            self._moved_s = t_s
        error = self.goal_error(x, y)
        if self._near_goal_s is None and error is not None and error <= BENCHMARK_GOAL_M and not self.ended:
            self._near_goal_s = t_s
        if self.track is not None:
            v, w = command if command is not None else (0.0, 0.0)
            self.track.append((t_s, x, y, yaw, speed, v, w, mode, self._clearance_now))
        zero = command is None or (command[0] == 0.0 and command[1] == 0.0)
        at_rest = zero and (abs(speed) < s.rest_speed and abs(yaw_rate) < s.rest_yaw_rate
                            or self._held(x, y, yaw_rate))
        self._rest_pose = (self._rest_pose or (x, y)) if at_rest else None
        if at_rest and self._rest_since is None:
            # What the episode was when it came to rest: if it ends so, it ended then, and what the robot
            # did while it was held at rest (a creep of millimetres) is not part of it.
            self._at_rest = (self.clearance, self.path_m, len(self.track) if self.track is not None else 0)
        self._rest_since = (self._rest_since if self._rest_since is not None else t_s) if at_rest else None
        near_goal = error is not None and error <= s.success_radius
        if self.ended:
            return True
        if self.mode in (REACHED, FAILED) and at_rest:
            self._end(t_s)
        elif self._rest_since is not None and t_s - self._rest_since >= s.rest_hold - 1e-9 \
                and (near_goal or s.end_at_rest) and (self.moves or t_s >= s.first_command_wait - 1e-9):
            self._rest_end = True
            self.clearance, self.path_m, kept = self._at_rest
            if self.track is not None:
                del self.track[kept:]
            self._end(self._rest_since)
        elif t_s >= s.time_limit - 1e-9:
            self._end(t_s)
        return self.ended

    def _held(self, x, y, yaw_rate):
        """True if the robot, at rest before, still is (near where it came to rest, rocking at most)."""
        if self._rest_pose is None:
            return False
        x0, y0 = self._rest_pose
        hold = self.settings.rest_hold
        return (math.hypot(x - x0, y - y0) < self.settings.rest_speed * hold
                and abs(yaw_rate) < self.settings.rest_rock_yaw_rate)

    def _end(self, t_s):
        self.ended, self.ended_s = True, t_s

    def verdict(self, t_s, final_pose=None):
        """The :class:`Verdict` at ``t_s`` (the end, or now for a scenario cut short); ``final_pose``: ground
        truth (x, y, yaw) then (default: the last observed)."""
        pose = final_pose or self._pose or (math.nan, math.nan, math.nan)
        error = self.goal_error(pose[0], pose[1])
        near_goal = error is not None and error <= self.settings.success_radius
        if self.contacts:
            outcome = 'collided'
        elif self.mode == REACHED:
            outcome = 'reached' if near_goal else 'failed'
        elif self.mode == FAILED:
            outcome = 'failed'
        elif self._rest_end:
            outcome = 'reached' if near_goal else 'stopped'
        else:
            outcome = 'timed_out'
        time_s = self.ended_s if self.ended_s is not None else t_s
        near = self._near_goal_s
        benchmark = None if near is None or near > time_s + 1e-9 else near - (self._moved_s or 0.0)
        return Verdict(outcome, self.mode, time_s, self.contacts, self.clearance, tuple(pose), error,
                       self.path_m, self.peak_decel, self.commands, self.describe(outcome, time_s, pose, error),
                       benchmark_time_s=benchmark)

    def track_dict(self):
        """The track and the contact log as plain values (JSON: a clearance beyond the lookout is null)."""
        return {'trajectory': [list(row[:-1]) + [row[-1] if math.isfinite(row[-1]) else None] for row in self.track],
                'contact_log': [list(row) for row in self.contact_log]}

    def describe(self, outcome, time_s, pose, error):
        """The verdict in one line: what, where, when, how close it came, contacts."""
        line = '%s at (%.2f, %.2f) after %.1f s: least clearance %s, %d contact%s' % (
            outcome, pose[0], pose[1], time_s,
            'over the lookout' if not math.isfinite(self.clearance) else '%.3f m' % self.clearance,
            self.contacts, '' if self.contacts == 1 else 's')
        if error is not None:
            line += ', goal %.2f m away' % error
        if self.mode is not None:
            line += ', mode %s' % self.mode
        if not self.commands:
            line += '; no command ever reached the base'
        return line


def problems(verdict, expect):
    """What of ``expect`` (outcomes, max_contacts, min_clearance, within: what a scenario test asks) the verdict (a
    dict) breaks, as phrases; [] when all holds."""
    found = []
    if verdict['outcome'] not in expect['outcomes']:
        found.append('outcome %s, expected %s' % (verdict['outcome'], ' or '.join(expect['outcomes'])))
    if verdict['contacts'] > expect['max_contacts']:
        found.append('%d contacts, at most %d allowed' % (verdict['contacts'], expect['max_contacts']))
    clearance = verdict['min_clearance_m'] if verdict['min_clearance_m'] is not None else math.inf
    if expect['min_clearance'] is not None and clearance < expect['min_clearance']:
        found.append('least clearance %.3f m, at least %.3f m required' % (clearance, expect['min_clearance']))
    if expect['within'] is not None and verdict['time_s'] > expect['within']:
        found.append('after %.1f s, within %.1f s required' % (verdict['time_s'], expect['within']))
    return found
