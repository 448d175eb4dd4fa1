"""state_machine_controller: the lesson's EXPLORING / BACKING_UP behaviour on ROS time."""
import threading

import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String

from closed_loop.commands import STOP
from closed_loop.decisions import SilenceWatchdog, input_problem
from closed_loop.nodes.common import load_settings
from closed_loop.nodes.conversions import scan_from_msg, twist, twist_from_command
from closed_loop.scan import ScanError, sector_min
from closed_loop.state_machine import BackUpSettings, BackUpStateMachine, State

# How often a repeated warning or error may reappear in the log (s).
LOG_PERIOD_S = 2.0


class StateMachineController:
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
        ``~state`` (std_msgs/String, latched): EXPLORING or BACKING_UP, at start and on every
        transition.
    Parameters:
        ``~trigger_distance`` (m, default 0.5): back up when the nearest obstacle ahead is closer.
        ``~explore_speed`` (m/s, default 0.5): forward speed while exploring.
        ``~backup_speed`` (m/s, default -0.3, must be negative): speed while backing up.
        ``~backup_duration`` (s, default 2.0): how long to back up (ROS time).
        ``~front_half_angle`` (rad, default pi/2): half-width of the front sector around 0.
        ``~rate_hz`` (Hz, default 10): control timer rate; also the watchdog's rate.
        ``~scan_timeout`` (s, default 0.5): a scan older than this (ROS clock), or no scan received
        for this long (wall clock), means stop.
    """

    def __init__(self):
        self._settings = load_settings(BackUpSettings)
        period_s = 1.0 / self._settings.rate_hz
        self._lock = threading.Lock()
        self._reading = None
        self._stamp_s = None
        self._closing = False
        self._machine = BackUpStateMachine(self._settings, on_transition=self._on_transition)
        self._cmd_pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        self._state_pub = rospy.Publisher('~state', String, queue_size=1, latch=True)
        self._state_pub.publish(String(data=self._machine.state.name))
        self._watchdog = SilenceWatchdog(self._settings.scan_timeout, period_s, self._on_silence)
        self._scan_sub = rospy.Subscriber('scan', LaserScan, self._on_scan, queue_size=1)
        # reset=True: a ROS clock that jumps back (sim restart) restarts the timer instead of
        # killing its thread; the machine restarts its own state timer for the same reason.
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
            exploring = self._machine.state is State.EXPLORING
        # React at once to a new obstacle (a stale or bad scan is caught again inside _step).
        if (exploring and reading is not None and reading.trusted
                and reading.distance_m < self._settings.trigger_distance):
            self._step()

    def _on_timer(self, _event):
        self._step()

    def _step(self):
        with self._lock:
            if self._closing:
                return
            now_s = rospy.Time.now().to_sec()
            age_s = None if self._stamp_s is None else now_s - self._stamp_s
            problem = input_problem(self._reading, age_s, self._settings.scan_timeout)
            if problem is not None:
                self._cmd_pub.publish(twist_from_command(STOP))
                rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped, %s on hold: %s',
                                       self._machine.state.name, problem)
                return
            _state, linear_x = self._machine.update(self._reading.distance_m, now_s)
            self._cmd_pub.publish(twist(linear_x, 0.0))

    def _on_transition(self, old, new, now_s):
        # Called by the machine inside _step, with the lock held.
        rospy.loginfo('state %s -> %s at %.2f s (front obstacle %.2f m)', old.name, new.name,
                      now_s, self._reading.distance_m)
        self._state_pub.publish(String(data=new.name))

    def _on_silence(self, silent_s):
        with self._lock:
            if self._closing:
                return
            self._cmd_pub.publish(twist_from_command(STOP))
        rospy.logwarn_throttle(LOG_PERIOD_S, 'stopped: no scan received for %.2f s of wall time '
                               '(scan_timeout %.2f s)', silent_s, self._settings.scan_timeout)

    def _on_shutdown(self):
        self._watchdog.stop()
        self._timer.shutdown()
        with self._lock:
            self._closing = True
            self._cmd_pub.publish(twist_from_command(STOP))


def main():
    rospy.init_node('state_machine_controller')
    StateMachineController()
    rospy.spin()
