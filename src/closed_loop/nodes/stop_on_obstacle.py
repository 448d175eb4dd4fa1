"""stop_on_obstacle: the lesson's stop / slow / cruise controller, failing safe."""
import threading

import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String

from closed_loop.commands import STOP
from closed_loop.decisions import SilenceWatchdog, StopSettings, Zone, decide, stop
from closed_loop.nodes.common import load_settings
from closed_loop.nodes.conversions import scan_from_msg, twist, twist_from_command
from closed_loop.scan import ScanError, sector_min

# How often a repeated warning or error may reappear in the log (s).
LOG_PERIOD_S = 2.0


class StopOnObstacle:
    """Drives forward at a speed set by the nearest obstacle ahead; stops on any doubt.

    The scan callback stores the front reading with its header stamp; a timer on the ROS clock
    decides and publishes. A reading that would make things more dangerous is acted on at once from
    the callback, through the same decide-and-publish path. A missing, stale (older than
    ``~scan_timeout`` by the ROS clock), malformed or all-invalid scan means stop. A wall-clock
    watchdog also publishes zero while no scan has been received for ``~scan_timeout`` s of wall
    time, since a dead simulator stops ``/clock`` and with it the ROS-clock timer.

    Subscriptions:
        ``scan`` (sensor_msgs/LaserScan).
    Publications:
        ``cmd_vel`` (geometry_msgs/Twist): forward speed only, every ``1 / ~rate_hz`` s of ROS
        time, at once on new danger, zero from the watchdog and on shutdown.
        ``~zone`` (std_msgs/String, latched): CLEAR, SLOW or STOP, on every change.
    Parameters:
        ``~stop_distance`` (m, default 0.5): stop when the nearest obstacle ahead is closer.
        ``~slow_distance`` (m, default 1.0): slow down when it is closer.
        ``~slow_speed`` (m/s, default 0.2): speed in the slow zone.
        ``~cruise_speed`` (m/s, default 0.5): speed when clear.
        ``~hysteresis`` (m, default 0.05): margin past a limit needed to leave its zone.
        ``~front_half_angle`` (rad, default pi/2): half-width of the front sector around 0.
        ``~rate_hz`` (Hz, default 10): control timer rate; also the watchdog's rate.
        ``~scan_timeout`` (s, default 0.5): a scan older than this (ROS clock), or no scan received
        for this long (wall clock), means stop.
    """

    def __init__(self):
        self._settings = load_settings(StopSettings)
        period_s = 1.0 / self._settings.rate_hz
        self._lock = threading.Lock()
        self._reading = None
        self._stamp_s = None
        self._zone = None  # the zone last published; None before the first decision
        self._closing = False
        self._cmd_pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        self._zone_pub = rospy.Publisher('~zone', String, queue_size=1, latch=True)
        self._watchdog = SilenceWatchdog(self._settings.scan_timeout, period_s, self._on_silence)
        self._scan_sub = rospy.Subscriber('scan', LaserScan, self._on_scan, queue_size=1)
        # reset=True: a ROS clock that jumps back (sim restart) restarts the timer instead of
        # killing its thread.
        self._timer = rospy.Timer(rospy.Duration(period_s), self._on_timer, reset=True)
        self._watchdog.start()
        rospy.on_shutdown(self._on_shutdown)

    def _on_scan(self, msg):
        self._watchdog.kick()
        try:
            scan = scan_from_msg(msg)
            reading = sector_min(scan, 0.0, self._settings.front_half_angle)
            stamp_s = scan.stamp_s
        except ScanError as error:
            rospy.logerr_throttle(LOG_PERIOD_S, 'scan rejected: %s', error)
            reading, stamp_s = None, None
        with self._lock:
            self._reading, self._stamp_s = reading, stamp_s
            previous = self._zone
        prospect = decide(reading, self._age_s(stamp_s), previous, self._settings)
        if previous is None or prospect.zone > previous:
            self._decide_and_publish()

    def _on_timer(self, _event):
        self._decide_and_publish()

    def _age_s(self, stamp_s):
        if stamp_s is None:
            return None
        return rospy.Time.now().to_sec() - stamp_s

    def _decide_and_publish(self):
        with self._lock:
            if self._closing:
                return
            decision = decide(self._reading, self._age_s(self._stamp_s), self._zone,
                              self._settings)
            self._publish(decision)

    def _on_silence(self, silent_s):
        with self._lock:
            if self._closing:
                return
            self._publish(stop('no scan received for %.2f s of wall time (scan_timeout %.2f s)'
                               % (silent_s, self._settings.scan_timeout)))

    def _publish(self, decision):
        """Publish ``decision`` (call with the lock held)."""
        self._cmd_pub.publish(twist(decision.linear_x, 0.0))
        if decision.zone != self._zone:
            rospy.loginfo('zone %s -> %s: %s', self._zone.name if self._zone is not None else '-',
                          decision.zone.name, decision.reason)
            self._zone = decision.zone
            self._zone_pub.publish(String(data=decision.zone.name))
        if decision.zone == Zone.STOP:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped: %s', decision.reason)

    def _on_shutdown(self):
        self._watchdog.stop()
        self._timer.shutdown()
        with self._lock:
            self._closing = True
            self._cmd_pub.publish(twist_from_command(STOP))


def main():
    rospy.init_node('stop_on_obstacle')
    StopOnObstacle()
    rospy.spin()
