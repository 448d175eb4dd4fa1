"""velocity_publisher: publish one constant velocity command, the lesson's open-loop starting point."""
import threading

import rospy
from geometry_msgs.msg import Twist
from std_srvs.srv import Trigger, TriggerResponse

from closed_loop.commands import STOP, PublisherSettings, command_for
from closed_loop.nodes.common import Publisher, init_node, load_settings
from closed_loop.nodes.conversions import twist_from_command

# How often the steady "Publishing: ..." line may repeat in the log (s).
LOG_PERIOD_S = 5.0


class VelocityPublisher:
    """Publishes a fixed ``cmd_vel`` at a steady rate until told to stop.

    Publications:
        ``cmd_vel`` (geometry_msgs/Twist): the command, every ``1 / ~rate_hz`` s of ROS time;
        zero while stopped and once more on shutdown.
    Services:
        ``~stop`` (std_srvs/Trigger): publish zero velocity from now on (still publishing).
        ``~resume`` (std_srvs/Trigger): publish the configured command again.
    Parameters:
        ``~rate_hz`` (Hz, default 10): publishing rate.
        ``~linear_x`` (m/s, default 0.5): forward speed, used when ``~pattern`` is empty.
        ``~angular_z`` (rad/s, default 0.0): yaw rate, positive left, used when ``~pattern`` is empty.
        ``~pattern`` (default ''): one of forward, turn_left, curve, stop; overrides the two above.
    """

    def __init__(self):
        self._settings = load_settings(PublisherSettings)
        self._command = command_for(self._settings)
        self._lock = threading.Lock()
        self._stopped = False
        self._closing = False
        self._cmd_pub = Publisher('cmd_vel', Twist, queue_size=1)
        self._stop_srv = rospy.Service('~stop', Trigger, self._on_stop)
        self._resume_srv = rospy.Service('~resume', Trigger, self._on_resume)
        # reset=True: a ROS clock that jumps back (sim restart) restarts the timer instead of
        # killing its thread.
        self._timer = rospy.Timer(rospy.Duration(1.0 / self._settings.rate_hz), self._on_timer,
                                  reset=True)
        rospy.on_shutdown(self._on_shutdown)
        rospy.loginfo('%s: publishing v=%.2f m/s, w=%.2f rad/s on %s at %.1f Hz',
                      rospy.get_name(), self._command.linear_x, self._command.angular_z,
                      self._cmd_pub.resolved_name, self._settings.rate_hz)

    def _on_timer(self, _event):
        with self._lock:
            if self._closing:
                return
            command = STOP if self._stopped else self._command
            self._cmd_pub.publish(twist_from_command(command))
        rospy.loginfo_throttle(LOG_PERIOD_S, 'Publishing: v=%.2f m/s, w=%.2f rad/s',
                               command.linear_x, command.angular_z)

    def _on_stop(self, _request):
        with self._lock:
            was_stopped, self._stopped = self._stopped, True
            if not self._closing:
                self._cmd_pub.publish(twist_from_command(STOP))
        rospy.loginfo('%s: stop requested', rospy.get_name())
        return TriggerResponse(success=True, message='already stopped' if was_stopped
                               else 'stopped: publishing zero velocity')

    def _on_resume(self, _request):
        with self._lock:
            was_stopped, self._stopped = self._stopped, False
        rospy.loginfo('%s: resume requested', rospy.get_name())
        return TriggerResponse(success=True, message='resumed' if was_stopped
                               else 'was not stopped')

    def _on_shutdown(self):
        self._timer.shutdown()
        with self._lock:
            self._closing = True
            self._cmd_pub.publish(twist_from_command(STOP))


def main():
    init_node('velocity_publisher')
    VelocityPublisher()
    rospy.spin()
