"""Message <-> plain value conversions for the scan and velocity nodes."""
from geometry_msgs.msg import Twist

from closed_loop.commands import validate_command
from closed_loop.nodes.common import stamp_to_sec
from closed_loop.control.scan import Scan


def scan_from_msg(msg):
    """A core :class:`closed_loop.control.scan.Scan` copied from a ``sensor_msgs/LaserScan``.

    Nothing is checked here; call :func:`closed_loop.control.scan.validate_scan` (the geometry functions do).
    """
    return Scan(stamp_s=stamp_to_sec(msg.header.stamp), frame_id=msg.header.frame_id,
                angle_min=msg.angle_min, angle_max=msg.angle_max,
                angle_increment=msg.angle_increment, time_increment=msg.time_increment,
                scan_time=msg.scan_time, range_min=msg.range_min, range_max=msg.range_max,
                ranges=msg.ranges)


def message_callerid(msg):
    """The caller id (node name) of the publisher a received message came from, or None if unknown."""
    header = getattr(msg, '_connection_header', None) or {}
    return header.get('callerid')


def connected_publishers(subscriber):
    """Caller ids of the publishers ``subscriber`` (a rospy.Subscriber) is connected to now.

    rospy keeps them on its connections (``callerid_pub``, from each publisher's connection header);
    an unknown layout gives [] and the per-message caller ids still count.
    """
    impl = getattr(subscriber, 'impl', None)
    connections = list(getattr(impl, 'connections', None) or [])
    return [c.callerid_pub for c in connections if getattr(c, 'callerid_pub', 'unknown') != 'unknown']


def twist(linear_x, angular_z):
    """A ``geometry_msgs/Twist`` with forward speed (m/s) and yaw rate (rad/s), all else zero.

    Raises :class:`closed_loop.commands.CommandError` on NaN, inf or non-numbers, so an invalid
    command is never published.
    """
    command = validate_command(linear_x, angular_z)
    msg = Twist()
    msg.linear.x = command.linear_x
    msg.angular.z = command.angular_z
    return msg


def twist_from_command(command):
    """A ``geometry_msgs/Twist`` from a :class:`closed_loop.commands.VelocityCommand`."""
    return twist(command.linear_x, command.angular_z)
