"""state_machine_controller: the lesson's EXPLORING / BACKING_UP behaviour on ROS time."""
import rospy

from closed_loop.commands import STOP
from closed_loop.control.decisions import input_problem
from closed_loop.nodes.common import init_node, load_settings
from closed_loop.nodes.conversions import twist, twist_from_command
from closed_loop.nodes.front_controller import LOG_PERIOD_S, FrontController
from closed_loop.control.state_machine import BackUpSettings, BackUpStateMachine, react_now


class StateMachineController(FrontController):
    """Explores forward and backs up for a while whenever an obstacle ahead gets too close.

    Same structure and staleness rules as stop_on_obstacle: the scan callback stores the front
    reading with its header stamp; a timer on the ROS clock advances the machine with that distance
    and ``rospy.Time.now()`` (so it runs on simulated time) and publishes. A reading that triggers
    backing up is acted on at once from the callback, through the same path. While the reading is
    missing, stale, malformed or all-invalid the node publishes zero and does not advance the
    machine. A wall-clock watchdog publishes zero while no scan has been received for
    ``~scan_timeout`` s of wall time (a dead simulator stops ``/clock`` and the ROS-clock timer).

    Subscriptions:
        ``scan`` (sensor_msgs/LaserScan).
    Publications:
        ``cmd_vel`` (geometry_msgs/Twist): forward speed only, every ``1 / ~rate_hz`` s of ROS
        time, zero from the watchdog and on shutdown.
        ``~mode`` (std_msgs/String, latched): the state, EXPLORING or BACKING_UP
        (``closed_loop.control.state_machine.State``), at start and on every transition (the controllers'
        shared contract).
    Parameters:
        ``~trigger_distance`` (m, default 0.5): back up when the nearest obstacle ahead is closer.
        ``~explore_speed`` (m/s, default 0.5): forward speed while exploring.
        ``~backup_speed`` (m/s, default -0.3, must be negative): speed while backing up.
        ``~backup_duration`` (s, default 2.0): how long to back up (ROS time).
        ``~front_half_angle``, ``~rate_hz``, ``~scan_timeout``: shared by the front controllers, see
        :class:`closed_loop.nodes.front_controller.FrontController`.
    """

    def __init__(self):
        FrontController.__init__(self, load_settings(BackUpSettings))

    def setup(self):
        self._machine = BackUpStateMachine(self.settings, on_transition=self._on_transition)
        self.publish_mode(self._machine.state, 'start')

    def on_settings(self, settings):
        self._machine.reconfigure(settings)

    def react_now(self, reading, age_s):
        return react_now(self._machine.state, reading, self.settings)

    def decide(self, reading, age_s):
        problem = input_problem(reading, age_s, self.settings.scan_timeout)
        if problem is not None:
            self.cmd_pub.publish(twist_from_command(STOP))
            rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped, %s on hold: %s', self._machine.state.name,
                                   problem)
            return
        _state, linear_x = self._machine.update(reading.distance_m, rospy.Time.now().to_sec())
        self.cmd_pub.publish(twist(linear_x, 0.0))

    def _on_transition(self, old, new, now_s):
        # Called by the machine inside decide(), with the lock held.
        self.publish_mode(new, 'at %.2f s (front obstacle %.2f m)' % (now_s, self.reading.distance_m))

    def on_silence(self, silent_s):
        self.cmd_pub.publish(twist_from_command(STOP))
        rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped: no scan received for %.2f s of wall time '
                               '(scan_timeout %.2f s)', silent_s, self.settings.scan_timeout)


def main():
    init_node('state_machine_controller')
    StateMachineController()
    rospy.spin()
