"""Differential drive: command validation, limits, the command watchdog, wheel kinematics, odometry.

Everything here is plain numbers in SI units (REP 103): linear speeds in m/s along +x, angular speeds in
rad/s counter-clockwise about +z, times in seconds of simulated time.
"""
import math

# One velocity-command type in the package: commands.VelocityCommand (linear_x m/s, angular_z rad/s,
# finite by construction) is also the body twist the drive works with.
from closed_loop.commands import STOP, CommandError, VelocityCommand


def validate_twist(linear, angular):
    """Check a Twist's six components, given as (x, y, z) tuples; return the usable :class:`VelocityCommand`.

    Raises CommandError naming the first NaN or infinite component (``linear.x``, ``angular.z``, ...).
    Components a differential drive cannot follow (linear.y/z, angular.x/y) are checked for NaN/Inf too,
    because a message carrying them is corrupt, but are otherwise ignored.
    """
    for group, values in (('linear', linear), ('angular', angular)):
        for axis, value in zip('xyz', values):
            if not math.isfinite(value):
                raise CommandError('%s.%s is %r; a velocity command must be finite' % (group, axis, value))
    return VelocityCommand(float(linear[0]), float(angular[2]))


def clamp(value, limit):
    """``value`` limited to [-limit, limit]."""
    return max(-limit, min(limit, value))


def clipped_fields(twist, max_linear_mps, max_angular_rps):
    """What :func:`limit_twist` would clip, one sentence per field with the value and the limit."""
    found = []
    if abs(twist.linear_x) > max_linear_mps:
        found.append('linear.x %g m/s clipped to the limit %g m/s (~max_linear_speed)'
                     % (twist.linear_x, math.copysign(max_linear_mps, twist.linear_x)))
    if abs(twist.angular_z) > max_angular_rps:
        found.append('angular.z %g rad/s clipped to the limit %g rad/s (~max_angular_speed)'
                     % (twist.angular_z, math.copysign(max_angular_rps, twist.angular_z)))
    return found


def limit_twist(target, max_linear_mps, max_angular_rps):
    """Clip a commanded twist to the robot's speed limits."""
    if abs(target.linear_x) <= max_linear_mps and abs(target.angular_z) <= max_angular_rps:
        return target       # (called at every physics step: no new command when nothing is clipped)
    return VelocityCommand(clamp(target.linear_x, max_linear_mps), clamp(target.angular_z, max_angular_rps))


def ramp(current, target, max_linear_accel_mps2, max_angular_accel_rps2, dt_s):
    """Move ``current`` toward ``target`` by at most the acceleration limits over ``dt_s`` seconds.

    The same limits apply when braking, so a stop is a smooth deceleration, as on a real base.
    """
    if current == target:
        return target
    def step(now, goal, rate):
        delta = goal - now
        room = rate * dt_s
        return goal if abs(delta) <= room else now + math.copysign(room, delta)
    return VelocityCommand(step(current.linear_x, target.linear_x, max_linear_accel_mps2),
                     step(current.angular_z, target.angular_z, max_angular_accel_rps2))


class CommandWatchdog:
    """Remembers the last valid command and when it arrived; forgets it after ``timeout_s``.

    ``target(now_s)`` is the command to follow at ``now_s``: the last one while it is fresh, else a stop.
    Time is simulated time; a clock that goes backwards (a reset) counts as expired.
    """

    def __init__(self, timeout_s):
        self.timeout_s = timeout_s
        self._command = STOP
        self._received_s = None

    def accept(self, command, now_s):
        self._command = command
        self._received_s = now_s

    def clear(self):
        self._command = STOP
        self._received_s = None

    def expired(self, now_s):
        if self._received_s is None:
            return True
        age = now_s - self._received_s
        return age < 0.0 or age > self.timeout_s

    def target(self, now_s):
        return STOP if self.expired(now_s) else self._command


def wheel_speeds(twist, wheel_separation_m, wheel_radius_m):
    """(left, right) wheel angular speeds in rad/s for a body twist."""
    half = 0.5 * wheel_separation_m * twist.angular_z
    return ((twist.linear_x - half) / wheel_radius_m, (twist.linear_x + half) / wheel_radius_m)


def body_twist(left_rps, right_rps, wheel_separation_m, wheel_radius_m):
    """The body twist that wheel speeds (rad/s) produce, without slip."""
    return VelocityCommand(0.5 * wheel_radius_m * (left_rps + right_rps),
                     wheel_radius_m * (right_rps - left_rps) / wheel_separation_m)


class DeadReckoning:
    """Dead reckoning from wheel speeds: pose (x, y, yaw) in the odom frame, which starts at the origin."""

    def __init__(self):
        self.reset()

    def reset(self):
        self.x = self.y = self.yaw = 0.0
        self.twist = STOP

    def integrate(self, twist, dt_s):
        """Advance by ``dt_s`` at constant ``twist`` (exact arc, so turning in place is exact too)."""
        v, w = twist.linear_x, twist.angular_z
        if abs(w) < 1e-9:
            self.x += v * dt_s * math.cos(self.yaw)
            self.y += v * dt_s * math.sin(self.yaw)
        else:
            yaw_next = self.yaw + w * dt_s
            self.x += v / w * (math.sin(yaw_next) - math.sin(self.yaw))
            self.y -= v / w * (math.cos(yaw_next) - math.cos(self.yaw))
            self.yaw = yaw_next
        self.yaw = math.atan2(math.sin(self.yaw), math.cos(self.yaw))
        self.twist = twist
