"""Differential drive: command validation, limits, ramps, the watchdog, wheel kinematics, odometry."""
import math

import pytest

from closed_loop.sim.drive import (STOP, VelocityCommand, CommandError, CommandWatchdog, DeadReckoning,
                               body_twist, limit_twist, ramp, validate_twist, wheel_speeds)

# The robot's wheel geometry (urdf/closed_loop.urdf); any positive values would do for the algebra.
WHEEL_RADIUS_M = 0.05
WHEEL_SEPARATION_M = 0.28

COMPONENTS = [('linear', 0), ('linear', 1), ('linear', 2), ('angular', 0), ('angular', 1),
              ('angular', 2)]
BAD_VALUES = [float('nan'), float('inf'), float('-inf')]


def pair(twist):
    """A VelocityCommand as a tuple, for approximate comparison."""
    return twist.linear_x, twist.angular_z


def twist_with(group, index, value):
    """A Twist as two (x, y, z) tuples, all finite except ``group``[``index``] = ``value``."""
    linear, angular = [0.1, 0.2, 0.3], [0.4, 0.5, 0.6]
    (linear if group == 'linear' else angular)[index] = value
    return tuple(linear), tuple(angular)


# --- validate_twist ---------------------------------------------------------------------------

@pytest.mark.parametrize('value', BAD_VALUES, ids=['nan', 'inf', '-inf'])
@pytest.mark.parametrize('group,index', COMPONENTS,
                         ids=['%s.%s' % (g, 'xyz'[i]) for g, i in COMPONENTS])
def test_validate_twist_rejects_non_finite_components_naming_the_field(group, index, value):
    linear, angular = twist_with(group, index, value)
    with pytest.raises(CommandError) as caught:
        validate_twist(linear, angular)
    field = '%s.%s' % (group, 'xyz'[index])
    message = str(caught.value)
    assert message.startswith(field + ' ')
    # Only the bad field is named: a message naming another component would mislead.
    others = ['%s.%s' % (g, 'xyz'[i]) for g, i in COMPONENTS if (g, i) != (group, index)]
    assert not any(other in message for other in others)


def test_validate_twist_names_the_first_bad_component():
    with pytest.raises(CommandError, match=r'^linear\.y '):
        validate_twist((0.0, float('nan'), 0.0), (0.0, 0.0, float('inf')))


def test_command_error_is_a_value_error():
    # Callers that guard conversions with ``except ValueError`` must catch bad commands too.
    assert issubclass(CommandError, ValueError)


def test_validate_twist_keeps_linear_x_and_angular_z_only():
    result = validate_twist((0.7, -0.2, 0.3), (0.4, 0.5, -1.25))
    assert result == VelocityCommand(0.7, -1.25)
    assert isinstance(result.linear_x, float) and isinstance(result.angular_z, float)


def test_validate_twist_accepts_integers_as_floats():
    assert validate_twist((1, 0, 0), (0, 0, -2)) == VelocityCommand(1.0, -2.0)


# --- limit_twist ------------------------------------------------------------------------------

def test_limit_twist_leaves_commands_within_limits_alone():
    assert limit_twist(VelocityCommand(0.3, -1.0), 0.5, 2.0) == VelocityCommand(0.3, -1.0)


@pytest.mark.parametrize('target,expected', [
    (VelocityCommand(2.0, 0.0), VelocityCommand(0.5, 0.0)),
    (VelocityCommand(-2.0, 0.0), VelocityCommand(-0.5, 0.0)),
    (VelocityCommand(0.0, 9.0), VelocityCommand(0.0, 2.0)),
    (VelocityCommand(0.0, -9.0), VelocityCommand(0.0, -2.0)),
    (VelocityCommand(0.5, -2.0), VelocityCommand(0.5, -2.0)),
    (VelocityCommand(-3.0, 3.0), VelocityCommand(-0.5, 2.0)),
])
def test_limit_twist_clips_each_axis_to_its_own_limit(target, expected):
    assert limit_twist(target, 0.5, 2.0) == expected


# --- ramp -------------------------------------------------------------------------------------

def test_ramp_accelerates_by_at_most_the_limit_in_both_directions():
    # Different linear and angular limits, so swapping them is caught.
    assert pair(ramp(STOP, VelocityCommand(1.0, 0.0), 2.0, 6.0, 0.1)) == pytest.approx((0.2, 0.0))
    assert ramp(STOP, VelocityCommand(-1.0, 0.0), 2.0, 6.0, 0.1).linear_x == pytest.approx(-0.2)
    assert ramp(STOP, VelocityCommand(0.0, 3.0), 2.0, 6.0, 0.1).angular_z == pytest.approx(0.6)
    assert ramp(STOP, VelocityCommand(0.0, -3.0), 2.0, 6.0, 0.1).angular_z == pytest.approx(-0.6)


def test_ramp_brakes_at_the_same_limit():
    result = ramp(VelocityCommand(1.0, -2.0), STOP, 2.0, 6.0, 0.1)
    assert result.linear_x == pytest.approx(0.8)
    assert result.angular_z == pytest.approx(-1.4)


def test_ramp_reverses_through_zero_at_the_limit():
    assert ramp(VelocityCommand(0.1, 0.0), VelocityCommand(-1.0, 0.0), 2.0, 6.0, 0.1).linear_x == \
        pytest.approx(-0.1)


def test_ramp_arrives_exactly_and_stays():
    target = VelocityCommand(0.5, -1.3)
    current = STOP
    for _ in range(100):
        current = ramp(current, target, 2.0, 6.0, 0.01)
    # Exact equality: a ramp that creeps or overshoots by rounding would never settle on the target.
    assert current == target
    assert ramp(VelocityCommand(0.49, -1.28), target, 2.0, 6.0, 0.01) == target


def test_ramp_takes_as_long_as_the_acceleration_says():
    # 1.0 m/s at 2.0 m/s^2 takes 0.5 s, ten steps of 0.05 s (plus at most one for rounding).
    current = STOP
    for _ in range(9):
        current = ramp(current, VelocityCommand(1.0, 0.0), 2.0, 6.0, 0.05)
    assert current.linear_x == pytest.approx(0.9)
    for _ in range(2):
        current = ramp(current, VelocityCommand(1.0, 0.0), 2.0, 6.0, 0.05)
    assert current.linear_x == 1.0


# --- CommandWatchdog --------------------------------------------------------------------------

def test_watchdog_without_a_command_is_expired_and_stops():
    dog = CommandWatchdog(0.5)
    assert dog.expired(0.0)
    assert dog.target(0.0) == STOP


def test_watchdog_follows_a_fresh_command_until_the_timeout():
    dog = CommandWatchdog(0.5)
    command = VelocityCommand(0.3, 0.1)
    dog.accept(command, 10.0)
    assert dog.target(10.0) == command
    assert dog.target(10.25) == command
    # Exactly at the timeout the command still holds; any later it has expired.
    assert not dog.expired(10.5)
    assert dog.target(10.5) == command
    assert dog.expired(10.5 + 1e-9)
    assert dog.target(10.5 + 1e-9) == STOP


def test_watchdog_a_new_command_restarts_the_timeout():
    dog = CommandWatchdog(0.5)
    dog.accept(VelocityCommand(0.3, 0.0), 1.0)
    dog.accept(VelocityCommand(-0.2, 0.0), 1.4)
    assert dog.target(1.8) == VelocityCommand(-0.2, 0.0)
    assert dog.target(1.91) == STOP


def test_watchdog_treats_a_clock_going_backwards_as_expired():
    dog = CommandWatchdog(0.5)
    dog.accept(VelocityCommand(0.3, 0.0), 5.0)
    assert dog.expired(4.99)
    assert dog.target(4.99) == STOP


def test_watchdog_clear_forgets_the_command():
    dog = CommandWatchdog(0.5)
    dog.accept(VelocityCommand(0.3, 0.0), 5.0)
    dog.clear()
    assert dog.expired(5.0)
    assert dog.target(5.0) == STOP


# --- wheel kinematics -------------------------------------------------------------------------

def test_wheel_speeds_straight_and_turning():
    assert wheel_speeds(VelocityCommand(0.5, 0.0), WHEEL_SEPARATION_M, WHEEL_RADIUS_M) == \
        pytest.approx((10.0, 10.0))
    # Counter-clockwise (REP 103): the right wheel runs forward, the left backward.
    assert wheel_speeds(VelocityCommand(0.0, 1.0), WHEEL_SEPARATION_M, WHEEL_RADIUS_M) == \
        pytest.approx((-2.8, 2.8))


@pytest.mark.parametrize('twist', [VelocityCommand(0.5, 0.0), VelocityCommand(0.0, -1.5), VelocityCommand(0.3, 0.7),
                                   VelocityCommand(-0.2, 2.0), STOP])
def test_wheel_speeds_and_body_twist_round_trip(twist):
    left, right = wheel_speeds(twist, WHEEL_SEPARATION_M, WHEEL_RADIUS_M)
    back = body_twist(left, right, WHEEL_SEPARATION_M, WHEEL_RADIUS_M)
    assert back.linear_x == pytest.approx(twist.linear_x, abs=1e-12)
    assert back.angular_z == pytest.approx(twist.angular_z, abs=1e-12)


def test_body_twist_from_unequal_wheels():
    assert pair(body_twist(8.0, 12.0, WHEEL_SEPARATION_M, WHEEL_RADIUS_M)) == \
        pytest.approx((0.5, 0.05 * 4.0 / 0.28))


# --- DeadReckoning -------------------------------------------------------------------------------

def integrate(odometry, twist, duration_s, steps):
    for _ in range(steps):
        odometry.integrate(twist, duration_s / steps)


def test_odometry_straight_line():
    odometry = DeadReckoning()
    integrate(odometry, VelocityCommand(0.5, 0.0), 2.0, 20)
    assert (odometry.x, odometry.y, odometry.yaw) == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)
    assert odometry.twist == VelocityCommand(0.5, 0.0)


def test_odometry_straight_line_follows_the_heading():
    odometry = DeadReckoning()
    integrate(odometry, VelocityCommand(0.0, 1.0), math.pi / 2, 10)
    integrate(odometry, VelocityCommand(0.5, 0.0), 2.0, 20)
    assert (odometry.x, odometry.y) == pytest.approx((0.0, 1.0), abs=1e-9)


def test_odometry_turn_in_place():
    odometry = DeadReckoning()
    integrate(odometry, VelocityCommand(0.0, 1.0), math.pi / 2, 7)
    assert (odometry.x, odometry.y) == pytest.approx((0.0, 0.0), abs=1e-12)
    assert odometry.yaw == pytest.approx(math.pi / 2)
    integrate(odometry, VelocityCommand(0.0, -1.0), math.pi, 9)
    assert odometry.yaw == pytest.approx(-math.pi / 2)


def test_odometry_yaw_stays_within_plus_minus_pi():
    odometry = DeadReckoning()
    integrate(odometry, VelocityCommand(0.0, 1.0), 1.5 * math.pi, 30)
    assert odometry.yaw == pytest.approx(-0.5 * math.pi)


def test_odometry_full_circle_returns_to_the_start():
    odometry = DeadReckoning()
    # Radius 0.5 m counter-clockwise: the centre is at (0, 0.5), half-way is (0, 1).
    twist = VelocityCommand(0.5, 1.0)
    integrate(odometry, twist, math.pi, 50)
    assert (odometry.x, odometry.y) == pytest.approx((0.0, 1.0), abs=1e-9)
    assert abs(odometry.yaw) == pytest.approx(math.pi)
    integrate(odometry, twist, math.pi, 50)
    assert (odometry.x, odometry.y, odometry.yaw) == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


def test_odometry_quarter_arc_uses_the_exact_arc():
    # One large step must land on the circle, not on the tangent (which would give x = 0.5 pi / 2).
    odometry = DeadReckoning()
    odometry.integrate(VelocityCommand(0.5, 1.0), math.pi / 2)
    assert (odometry.x, odometry.y, odometry.yaw) == pytest.approx((0.5, 0.5, math.pi / 2))


def test_odometry_reset():
    odometry = DeadReckoning()
    integrate(odometry, VelocityCommand(0.5, 1.0), 1.0, 5)
    odometry.reset()
    assert (odometry.x, odometry.y, odometry.yaw) == (0.0, 0.0, 0.0)
    assert odometry.twist == STOP
