"""stop_on_obstacle: the lesson's stop / slow / cruise controller, failing safe."""
import rospy

from closed_loop.control.decisions import StopSettings, Zone, decide, react_now, stop
from closed_loop.nodes.common import init_node, load_settings
from closed_loop.nodes.conversions import twist
from closed_loop.nodes.front_controller import LOG_PERIOD_S, FrontController


class StopOnObstacle(FrontController):
    """Drives forward at a speed set by the nearest obstacle ahead; stops on any doubt.

    The scan callback stores the front reading with its header stamp; a timer on the ROS clock
    decides and publishes. A reading that would make things more dangerous is acted on at once from
    the callback, through the same decide-and-publish path, unless ``~react_immediately`` is false:
    then only the timer acts on new danger (the lesson's design), which adds a wait of up to one
    timer period to the reaction. A missing, stale (older than ``~scan_timeout`` by the ROS clock),
    malformed or all-invalid scan means stop. A wall-clock watchdog also publishes zero while no
    scan has been received for ``~scan_timeout`` s of wall time, since a dead simulator stops
    ``/clock`` and with it the ROS-clock timer.

    Subscriptions:
        ``scan`` (sensor_msgs/LaserScan).
    Publications:
        ``cmd_vel`` (geometry_msgs/Twist): forward speed only, every ``1 / ~rate_hz`` s of ROS
        time, at once on new danger (with ``~react_immediately``), zero from the watchdog and on
        shutdown.
        ``~mode`` (std_msgs/String, latched): the zone, CLEAR, SLOW or STOP
        (``closed_loop.control.decisions.Zone``), on every change (the controllers' shared contract).
    Parameters:
        ``~stop_distance`` (m, default 0.5): stop when the nearest obstacle ahead is closer.
        ``~slow_distance`` (m, default 1.0): slow down when it is closer.
        ``~slow_speed`` (m/s, default 0.2): speed in the slow zone.
        ``~cruise_speed`` (m/s, default 0.5): speed when clear.
        ``~hysteresis`` (m, default 0.05): margin past a limit needed to leave its zone.
        ``~react_immediately`` (bool, default true): act on a more dangerous scan at once from the
        scan callback; false decides only in the timer, as the lesson does (the very first
        decision after start-up still happens at once, see :meth:`react_now`).
        ``~front_half_angle``, ``~rate_hz``, ``~scan_timeout``: shared by the front controllers, see
        :class:`closed_loop.nodes.front_controller.FrontController`.
    """

    def __init__(self):
        FrontController.__init__(self, load_settings(StopSettings))

    def react_now(self, reading, age_s):
        """:func:`closed_loop.control.decisions.react_now`: the first decision, and new danger unless
        ``~react_immediately`` is false.

        The first decision (no mode published yet) is made at once whatever ``~react_immediately``
        says: it is not a reaction to a change but the end of start-up, before which this node has
        sent no command at all; deciding at once only makes the first command (a stop, if the scan
        says so) come up to one timer period sooner, from a fresh scan. It happens once per node
        start (the watchdog's stop also counts as a decision), so reaction latencies measured
        after the node's first command are those of the timer-only design.
        """
        return react_now(reading, age_s, self.mode, self.settings)

    def decide(self, reading, age_s):
        self._publish(decide(reading, age_s, self.mode, self.settings))

    def on_silence(self, silent_s):
        self._publish(stop('no scan received for %.2f s of wall time (scan_timeout %.2f s)'
                           % (silent_s, self.settings.scan_timeout)))

    def _publish(self, decision):
        """Publish ``decision`` (call with the lock held)."""
        self.cmd_pub.publish(twist(decision.linear_x, 0.0))
        if decision.fault and self.awaiting_first_scan():
            return   # a timer tick before the first scan: stopped, and nothing to report yet
        # Stopping is a warning, logged once on entry: standing at the wall is the normal end state. A stop
        # for want of input (no, stale or invalid scans) is a fault and is repeated while it lasts.
        self.publish_mode(decision.zone, decision.reason,
                          rospy.logwarn if decision.zone == Zone.STOP else rospy.loginfo)
        if decision.fault:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped: %s', decision.reason)


def main():
    init_node('stop_on_obstacle')
    StopOnObstacle()
    rospy.spin()
