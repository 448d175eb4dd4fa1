"""What the visualisation markers show, as plain numbers: the commanded velocity as an arrow, its zone
colour, and the text for the obstacle distance. The cmd_vel_marker node turns these into Markers."""
import math
from dataclasses import dataclass

from closed_loop.control.decisions import Zone
from closed_loop.settings import MIN_RATE_HZ, param

# The colour zones are stop_on_obstacle's zones, named by their enum.
CLEAR, SLOW, STOP = Zone.CLEAR.name, Zone.SLOW.name, Zone.STOP.name
# RGBA in [0, 1]: green, amber, red, as traffic lights.
ZONE_COLOURS = {CLEAR: (0.1, 0.85, 0.2, 1.0), SLOW: (1.0, 0.75, 0.0, 1.0), STOP: (0.95, 0.1, 0.1, 1.0)}


@dataclass
class MarkerSettings:
    """cmd_vel_marker's ``~parameters``."""
    rate_hz: float = param(10.0, 'Hz', 'marker publishing rate', minimum=MIN_RATE_HZ)
    horizon: float = param(1.0, 's', 'the arrow ends where the command would take the robot in this time '
                           '(so its length is proportional to linear.x and it bends with angular.z)',
                           minimum=0.0, exclusive_minimum=True)
    slow_speed: float = param(0.2, 'm/s', 'when the mode is not a zone, commands up to this speed are coloured SLOW',
                              minimum=0.0)
    command_timeout: float = param(0.5, 's', 'no cmd_vel for this long: the arrow is removed',
                                   minimum=0.0, exclusive_minimum=True)
    frame_id: str = param('base_footprint', '', 'frame the markers are drawn in')
    text_height: float = param(0.15, 'm', 'height of the distance text', minimum=0.0, exclusive_minimum=True)


def zone_from_command(linear_x, slow_speed):
    """A colour zone for a command when the controller's mode does not say one: stopped, slow (or
    reversing, which calls for care), or cruising."""
    if linear_x == 0.0:
        return STOP
    return SLOW if linear_x < 0.0 or linear_x <= slow_speed else CLEAR


def normalise_zone(name):
    """A controller's mode as a colour zone when it is one of CLEAR / SLOW / STOP (any case), else None:
    then the colour comes from the command (:func:`zone_from_command`). The marker knows no controller's
    own mode names (EXPLORING, BACKING_UP, ...): it shows them as text."""
    name = (name or '').strip().upper()
    return name if name in ZONE_COLOURS else None


def arrow_end(linear_x, angular_z, horizon_s):
    """(x, y) in m, in the robot's frame, where constant (linear_x m/s, angular_z rad/s) takes the robot
    after ``horizon_s`` s. Turning in place gives (0, 0): the caller draws the turn some other way."""
    if abs(angular_z) < 1e-9:
        return linear_x * horizon_s, 0.0
    radius = linear_x / angular_z
    theta = angular_z * horizon_s
    return radius * math.sin(theta), radius * (1.0 - math.cos(theta))


def distance_text(distance_m):
    """How the obstacle distance reads next to the robot (REP 117 meanings kept: inf clear, NaN unknown)."""
    if distance_m is None:
        return 'obstacle: ?'
    if math.isnan(distance_m):
        return 'obstacle: no valid reading'
    if math.isinf(distance_m):
        return 'obstacle: none in range'
    return 'obstacle: %.2f m' % distance_m
