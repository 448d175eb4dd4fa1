"""cmd_vel_marker: the commanded velocity as an rviz arrow, coloured by the controller's zone."""
import math
import threading
import time

import rospy
from geometry_msgs.msg import Point, Twist
from std_msgs.msg import ColorRGBA, Float32, String
from visualization_msgs.msg import Marker

from closed_loop.control import markers
from closed_loop.nodes.common import Publisher, frame_id, init_node, load_settings

ARROW_SHAFT_M = 0.04
ARROW_HEAD_M = 0.08
TEXT_ABOVE_ROBOT_M = 0.45
TURN_RING_RADIUS_M = 0.25


class CmdVelMarker:
    """Draws what the robot is being told to do, for any controller.

    Subscribes:
        cmd_vel (geometry_msgs/Twist): the command to draw.
        mode (std_msgs/String): optional; a controller's ``~mode`` (remap it). CLEAR / SLOW / STOP give
            the colour; any other mode is shown as text, and the colour comes from the command.
        obstacle_distance (std_msgs/Float32): shown as text above the robot.
    Publishes:
        cmd_vel_marker (visualization_msgs/Marker): an ARROW from the robot to where the command would take
            it in ``~horizon`` s (length proportional to linear.x, bent by angular.z), green / amber / red
            for CLEAR / SLOW / STOP; turning in place is a ring; no command for ``~command_timeout`` s
            deletes it.
        obstacle_distance_marker (visualization_msgs/Marker): TEXT_VIEW_FACING with the distance and command.
    Parameters: see :class:`closed_loop.control.markers.MarkerSettings`.
    """

    def __init__(self):
        self.settings = load_settings(markers.MarkerSettings)
        self._frame_id = frame_id(self.settings.frame_id)   # with the robot's TF prefix, if it has one
        self._lock = threading.Lock()
        self._cmd = None
        self._cmd_wall = None
        self._zone = None
        self._mode = None
        self._distance = None
        self._arrow_pub = Publisher('cmd_vel_marker', Marker, queue_size=2)
        self._text_pub = Publisher('obstacle_distance_marker', Marker, queue_size=2)
        rospy.Subscriber('cmd_vel', Twist, self._on_cmd, queue_size=5)
        rospy.Subscriber('mode', String, self._on_mode, queue_size=5)
        rospy.Subscriber('obstacle_distance', Float32, self._on_distance, queue_size=5)
        # Wall-clock timer: markers are for a person watching, and must update even if /clock stalls.
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)
        self._thread.start()
        rospy.on_shutdown(self._stop.set)

    def _on_cmd(self, msg):
        with self._lock:
            self._cmd = (msg.linear.x, msg.angular.z)
            self._cmd_wall = time.monotonic()

    def _on_mode(self, msg):
        with self._lock:
            self._mode = msg.data
            self._zone = markers.normalise_zone(msg.data)

    def _on_distance(self, msg):
        with self._lock:
            self._distance = msg.data

    def _loop(self):
        period = 1.0 / self.settings.rate_hz
        while not self._stop.wait(period) and not rospy.is_shutdown():
            self.publish()

    def _marker(self, marker_id, kind):
        m = Marker()
        m.header.frame_id = self._frame_id
        m.header.stamp = rospy.Time(0)  # draw at the latest transform
        m.ns = 'closed_loop'
        m.id = marker_id
        m.type = kind
        m.pose.orientation.w = 1.0
        return m

    def publish(self):
        s = self.settings
        with self._lock:
            cmd, cmd_wall, zone, mode, distance = self._cmd, self._cmd_wall, self._zone, self._mode, self._distance
        arrow = self._marker(0, Marker.ARROW)
        fresh = cmd is not None and time.monotonic() - cmd_wall <= s.command_timeout
        if not fresh:
            arrow.action = Marker.DELETE
            self._arrow_pub.publish(arrow)
        else:
            v, w = cmd
            zone = zone or markers.zone_from_command(v, s.slow_speed)
            arrow.color = ColorRGBA(*markers.ZONE_COLOURS[zone])
            x, y = markers.arrow_end(v, w, s.horizon)
            if abs(x) + abs(y) < 1e-3 and abs(w) > 1e-9:
                # Turning in place: a ring of points around the robot instead of an arrow.
                arrow.type = Marker.LINE_STRIP
                arrow.scale.x = ARROW_SHAFT_M / 2
                arrow.points = [Point(TURN_RING_RADIUS_M * math.cos(a / 10.0),
                                      TURN_RING_RADIUS_M * math.sin(a / 10.0), 0.05)
                                for a in range(0, 63)]
            else:
                arrow.scale.x, arrow.scale.y, arrow.scale.z = ARROW_SHAFT_M, ARROW_HEAD_M, ARROW_HEAD_M
                arrow.points = [Point(0.0, 0.0, 0.05), Point(x, y, 0.05)]
            self._arrow_pub.publish(arrow)
        text = self._marker(1, Marker.TEXT_VIEW_FACING)
        text.pose.position.z = TEXT_ABOVE_ROBOT_M
        text.scale.z = s.text_height
        text.color = ColorRGBA(1.0, 1.0, 1.0, 1.0)
        line = markers.distance_text(distance)
        if fresh:
            line += '\ncmd %.2f m/s, %.2f rad/s%s' % (cmd[0], cmd[1], (' (%s)' % mode) if mode else '')
        text.text = line
        self._text_pub.publish(text)


def main():
    init_node('cmd_vel_marker')
    CmdVelMarker()
    rospy.spin()
