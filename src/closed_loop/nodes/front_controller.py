"""The part stop_on_obstacle and state_machine_controller share: taking in scans, staleness, timers."""
import threading
import time

import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import LaserScan
from std_msgs.msg import String

from closed_loop.control.decisions import SilenceWatchdog
from closed_loop.nodes.common import LOG_PERIOD_S, LaserMounting, LiveSettings, StopsOnShutdown, frame_id
from closed_loop.nodes.conversions import connected_publishers, message_callerid, scan_from_msg
from closed_loop.control.scan import ScanError, sector_min
from closed_loop.sources import SourceCheck



class FrontController(StopsOnShutdown):
    """Base of the controllers that drive on the nearest obstacle in the front sector.

    The ``scan`` callback stores the front reading (``closed_loop.control.scan.SectorReading``) with its header
    stamp, and calls :meth:`control` at once when :meth:`react_now` says the reading is news that cannot
    wait. A scan is only taken from one publisher in the expected frame (``~scan_frame``): while a
    second node publishes on ``scan``, or a scan comes in another frame, every scan is refused, an
    error names the publishers, and the controller stops (``closed_loop.sources.SourceCheck``); a timer on the ROS clock calls :meth:`control` every ``1 / ~rate_hz`` s. A wall-clock watchdog
    publishes zero while no scan has been received for ``~scan_timeout`` s of wall time, since a dead
    simulator stops ``/clock`` and with it the ROS-clock timer. Zero is also sent on shutdown.

    The settings' live fields (thresholds, speeds, the sector's width) are served by dynamic_reconfigure
    (:class:`closed_loop.nodes.common.LiveSettings`): ``dynparam set /NODE stop_distance 0.8`` takes effect
    on the next scan; a change the settings class refuses (stop above slow) is refused with the reason.

    Parameters every front controller has (``closed_loop.control.decisions.FrontControlSettings``):
        ``~front_half_angle`` (rad, default pi/2): half-width of the front sector around the robot's
        forward direction (angle 0 of the scan, unless the URDF mounts the laser turned).
        ``~rate_hz`` (Hz, default 10, at least 1): control timer rate; also the watchdog's rate
        (or twice per ``~scan_timeout``, if that is more often).
        ``~scan_timeout`` (s, default 0.5, at most 5): a scan older than this (ROS clock), or no scan
        received for this long (wall clock), means stop.
        ``~scan_frame`` (default base_scan): the laser's frame; scans in another frame mean stop. With a
        ``tf_prefix`` parameter in the robot's namespace (a multi-robot world), the expected frame id is
        prefixed (``r1/base_scan``), as robot_state_publisher and the simulator prefix theirs.

    The controller contract: every controller publishes ``cmd_vel`` and its mode on ``~mode``
    (std_msgs/String, latched; the name of a member of the controller's own mode enum), on every
    change, through :meth:`publish_mode`. Nothing outside a controller needs to know its mode names.

    Subclasses set ``self.settings`` (a ``FrontControlSettings``), create their own publishers in
    :meth:`setup`, and implement :meth:`react_now` (a call to their core's rule), :meth:`decide`
    (called with the lock held) and :meth:`on_silence`.
    """

    def __init__(self, settings):
        self.settings = settings
        period_s = 1.0 / settings.rate_hz
        self.lock = threading.Lock()
        self.reading = None
        self.stamp_s = None
        self._closing = False
        self.cmd_pub = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        self.mode = None  # the mode enum member last published; None before the first
        self._scan_seen = False
        self._started_wall = time.monotonic()
        self._mode_pub = rospy.Publisher('~mode', String, queue_size=1, latch=True)
        self.setup()
        self._source = SourceCheck(rospy.resolve_name('scan'), frame_id(settings.scan_frame))
        # "Ahead" is the robot's forward direction in the laser's frame, from how the URDF mounts it.
        self._forward_rad = LaserMounting().forward_rad(settings.scan_frame)
        self._watchdog = SilenceWatchdog(settings.scan_timeout, settings.watchdog_period_s, self._on_silence)
        self._scan_sub = rospy.Subscriber('scan', LaserScan, self._on_scan, queue_size=1)
        # reset=True: a ROS clock that jumps back (sim restart) restarts the timer instead of
        # killing its thread.
        self._timer = rospy.Timer(rospy.Duration(period_s), lambda _event: self.control(), reset=True)
        self._watchdog.start()
        self._live = LiveSettings(settings, self._apply_settings)
        rospy.on_shutdown(self._on_shutdown)

    # -- for subclasses ---------------------------------------------------------------------------------
    def setup(self):
        """Create the subclass's own publishers."""

    def react_now(self, reading, age_s):
        """True if this new reading must be acted on before the next timer tick."""
        raise NotImplementedError

    def decide(self, reading, age_s):
        """Decide and publish from the stored reading and its age (s, ROS clock); lock held."""
        raise NotImplementedError

    def on_silence(self, silent_s):
        """No scan for ``silent_s`` s of wall time: publish a stop (lock held)."""
        raise NotImplementedError

    def on_settings(self, settings):
        """New live settings were taken (lock held); ``self.settings`` is already the new one."""

    # -- shared ---------------------------------------------------------------------------------------------
    def _apply_settings(self, settings):
        # From dynamic_reconfigure: the next scan and the next tick decide with the new values.
        with self.lock:
            self.settings = settings
            self.on_settings(settings)

    def publish_mode(self, mode, why, log=rospy.loginfo):
        """Publish ``mode`` (an enum member) on ``~mode`` and log the change once with ``log``, if it is a
        change; a standing mode is not logged again."""
        if mode != self.mode:
            log('mode %s -> %s: %s', self.mode.name if self.mode is not None else '-', mode.name, why)
            self.mode = mode
            self._mode_pub.publish(String(data=mode.name))

    def age_s(self, stamp_s):
        """Age of a scan stamp on the ROS clock (s), or None for no scan."""
        if stamp_s is None:
            return None
        return rospy.Time.now().to_sec() - stamp_s

    def awaiting_first_scan(self):
        """True from start-up until the first scan arrives or ``~scan_timeout`` s of wall time have passed:
        meanwhile zero goes out, but "no scan yet" is start-up, not a fault to announce."""
        return not self._scan_seen and time.monotonic() - self._started_wall < self.settings.scan_timeout

    def _on_scan(self, msg):
        self._watchdog.kick()
        self._scan_seen = True
        refused = self._source.observe(message_callerid(msg), msg.header.frame_id, time.monotonic(),
                                       connected_publishers(self._scan_sub))
        if refused is not None:
            rospy.logerr_throttle(LOG_PERIOD_S, 'scan refused, stopping: %s', refused)
            reading, stamp_s = None, None
        else:
            try:
                scan = scan_from_msg(msg)
                reading = sector_min(scan, self._forward_rad, self.settings.front_half_angle)
                stamp_s = scan.stamp_s
            except ScanError as error:
                rospy.logerr_throttle(LOG_PERIOD_S, 'scan rejected: %s', error)
                reading, stamp_s = None, None
        with self.lock:
            self.reading, self.stamp_s = reading, stamp_s
            # A refused scan is news too: the stop must not wait for the timer.
            urgent = refused is not None or self.react_now(reading, self.age_s(stamp_s))
        if urgent:
            self.control()

    def control(self):
        """The one decision path, from the timer and from urgent scans."""
        with self.lock:
            if self._closing:
                return
            self.decide(self.reading, self.age_s(self.stamp_s))

    def _on_silence(self, silent_s):
        with self.lock:
            if self._closing:
                return
            self.on_silence(silent_s)
