"""When the simulator node steps physics and samples each sensor: the schedule on simulated time, and the
node's scheduling settings (real-time factor, /clock rate). Free of ROS."""
from dataclasses import dataclass

from closed_loop.settings import param

#: In lockstep, the simulated time (s) from the start in which /clock goes out at every step and the simulator learns
#: at which steps of a second a command follows it, and what each controller answers (closed_loop.nodes.sim_lockstep):
#: a second of a timer's ticks, for one started in the first 0.2 s.
LEARN_S = 1.2


@dataclass
class SchedulingSettings:
    """The simulator node's scheduling ``~parameters``."""
    real_time_factor: float = param(1.0, '', 'simulated seconds per wall second; 0 = as fast as possible',
                                    minimum=0.0)
    max_clock_rate_hz: float = param(100.0, 'Hz', '/clock is published after a physics step at most this '
                                     'often per wall second on average (every step at real time; '
                                     'throttled when faster), and always before a scan or camera frame',
                                     minimum=1.0)
    paused: bool = param(False, '', 'start with physics paused at t = 0 (/clock at 0, no sensor data) until '
                         '~unpause_physics is called (scenario.launch: its judge does, once the controller is up)')
    lockstep: bool = param(False, '', 'simulated time goes on only once every node of the launch has done all that '
                           'the last instant (its sensor messages, then /clock) asked of it, as fast as they answer; '
                           'real_time_factor is then not used (docs/own_controller.md, "Lockstep")')
    lockstep_timeout: float = param(2.0, 's', 'in lockstep, the CPU time a node may compute for at one instant (a '
                                    'node kept from the CPU by a busy machine is waited for, up to 10 times this of '
                                    'wall time); then the instant counts as missed (~missed_ticks), the base acts on '
                                    'the commands it has, and that node is not waited for until it is next seen idle',
                                    minimum=0.01, maximum=60.0)
    clock_every_step: bool = param(False, '', 'in lockstep, /clock goes out at every physics step; false: at every step '
                                   'with sensor messages, and at the others only if a node commanded at one in the '
                                   'first %g s of simulated time (a timer off the sensors\' instants)' % LEARN_S)
    lockstep_watchers: str = param('rviz', '', 'in lockstep, nodes of the launch that only watch, not waited for '
                                   '(space-separated names, relative to the simulator\'s namespace): they get what '
                                   'is published as any node outside the launch does')
    command_delay: float = param(0.01, 's', 'in lockstep, a command heard at an instant reaches the wheels this much '
                                 'simulated time later, in whole physics steps and at least one (an in-process '
                                 "episode's command_delay_s); in real time, commands act at the next step",
                                 minimum=0.0, maximum=1.0)


class Schedule:
    """Which named tasks are due after each physics step.

    A task has a period (s of simulated time; None: every step) and an offset within it. ``due(t_s)``
    returns the tasks due at simulated time ``t_s`` in the order they were added, each at most once per
    call, and advances each by whole periods; a task counts as due half a physics step early, so that a
    period that is a whole number of steps never slips a step through rounding.
    """

    def __init__(self, step_s):
        self._half_step_s = 0.5 * step_s
        self._tasks = []  # [name, period or None, next due time]

    def add(self, name, period_s=None, offset_s=0.0):
        self._tasks.append([name, period_s, offset_s])

    def periodic_due(self, t_s):
        """True if a task with a period (not one of every step) will be due at ``t_s``; nothing advances."""
        return any(period is not None and t_s >= next_s - self._half_step_s for _, period, next_s in self._tasks)

    def due(self, t_s):
        names = []
        for task in self._tasks:
            name, period, next_s = task
            if period is None:
                names.append(name)
            elif t_s >= next_s - self._half_step_s:
                task[2] = next_s + period
                names.append(name)
        return names


class ClockSchedule:
    """Whether /clock goes out after a physics step (besides before every scan and camera frame).

    At a real-time factor, on simulated time: one message per ``real_time_factor / max_clock_rate_hz``
    simulated seconds (every step at real time with the defaults), so that a loop catching up after a
    stall sends what it owes and the wall-clock rate is ``max_clock_rate_hz`` on average. As fast as
    possible (factor 0), on the wall clock: at most ``max_clock_rate_hz`` per wall second, with half a
    period of tolerance, and no burst after a stall.
    """

    def __init__(self, settings, step_s, now_wall_s):
        self._on_sim_time = settings.real_time_factor > 0
        if self._on_sim_time:
            self._schedule = Schedule(step_s)
            self._schedule.add('clock', max(settings.real_time_factor / settings.max_clock_rate_hz, step_s))
        self._period_s = 1.0 / settings.max_clock_rate_hz
        self._next_wall_s = now_wall_s

    def due(self, t_s, now_wall_s):
        if self._on_sim_time:
            return bool(self._schedule.due(t_s))
        if now_wall_s < self._next_wall_s - 0.5 * self._period_s:
            return False
        self._next_wall_s = max(self._next_wall_s + self._period_s, now_wall_s)
        return True


def command_delay_steps(delay_s, step_s):
    """How many physics steps after it is sent a command reaches the wheels: ``delay_s`` in whole steps, at least
    one (the step it was sent in is already under way). One rule for the simulator node in lockstep and for an
    in-process episode."""
    return max(1, int(round(delay_s / step_s)))
