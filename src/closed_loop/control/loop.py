"""What every controller's loop has, whatever it decides: its timer's rate, how old its input may be, and
the laser frame it trusts (:class:`LoopSettings`), and the rule for input too old to act on. Free of ROS."""
import dataclasses
import math

from closed_loop import robot_model
from closed_loop.settings import MIN_RATE_HZ, param

#: Scans older than this are never acted on, whatever ``~scan_timeout`` says.
MAX_SCAN_TIMEOUT_S = 5.0
#: A time compared with a threshold counts as there within this much (s): a ROS host's clock is whole nanoseconds,
#: 1 ns either side of an instant (a callback's before it, a timer's after), and an in-process host's sums of steps
#: carry float error (0.1 s ten times is 0.9999999999999999 s), so without it one decision can fall a tick apart
#: between the two hosts.
TIME_TOLERANCE_S = 1e-6


def lasted(elapsed_s, limit_s):
    """True once ``elapsed_s`` has reached ``limit_s`` (within :data:`TIME_TOLERANCE_S`)."""
    return elapsed_s >= limit_s - TIME_TOLERANCE_S


def outlasted(elapsed_s, limit_s):
    """True once ``elapsed_s`` is past ``limit_s`` (by more than :data:`TIME_TOLERANCE_S`)."""
    return elapsed_s > limit_s + TIME_TOLERANCE_S


@dataclasses.dataclass
class LoopSettings:
    """The ``~parameters`` of every controller's loop; a controller's settings class extends it."""
    rate_hz: float = param(10.0, 'Hz', 'control timer rate (ROS clock)', minimum=MIN_RATE_HZ)
    scan_timeout: float = param(0.5, 's', 'stop when the newest scan (or odometry, for a controller that uses '
                                'it) is older than this, or none has arrived', minimum=0.0,
                                maximum=MAX_SCAN_TIMEOUT_S, exclusive_minimum=True)
    scan_frame: str = param(robot_model.SCAN_FRAME, '', "the laser's frame_id: scans in any other frame are "
                            'refused (stop)')

    @property
    def watchdog_period_s(self):
        """How often the silence watchdog looks: a control period, or half the timeout if that is shorter."""
        return min(1.0 / self.rate_hz, 0.5 * self.scan_timeout)


def stale_input(now_s, stamps, scan_timeout_s):
    """Why the newest inputs cannot be acted on, or None: ``stamps`` is ((name, stamp s or None), ...); an
    input missing, older than ``scan_timeout_s``, stamped later than that (the clock jumped back), or of
    unknown age is refused."""
    for name, stamp in stamps:
        if stamp is None:
            return 'no %s yet' % name
        age = now_s - stamp
        if math.isnan(age):
            return '%s age unknown' % name
        if age > scan_timeout_s:
            return '%s is %.2f s old (scan_timeout %.2f s)' % (name, age, scan_timeout_s)
        if age < -scan_timeout_s:
            return '%s is stamped %.2f s in the future (clock jumped back?)' % (name, -age)
    return None
