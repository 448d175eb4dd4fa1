#!/usr/bin/env python3
"""Black-box: malformed scans and images fed to stop_on_obstacle, obstacle_detector and vision_node.

This node is the sensor (no simulator, wall-clock ROS time). Each bad input must get a log line on
/rosout naming the problem, leave the node running, and give the safe output: cmd_vel 0 and
obstacle_distance NaN where the scan cannot be trusted, nothing on red_detected for an unusable image.
Every stop case starts from cruising, so a zero command is the node's reaction and not a leftover.
"""
import math
import os
import sys
import threading
import time
import unittest

import numpy
import rosnode
import rospy
import rostest
from geometry_msgs.msg import Twist
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import Image, LaserScan
from std_msgs.msg import Bool, Float32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402
from closed_loop.control.decisions import StopSettings  # noqa: E402
from closed_loop.nodes.common import LOG_PERIOD_S  # noqa: E402
from closed_loop.sim.sensors.lidar import LidarSettings  # noqa: E402
from closed_loop.control.vision import VisionSettings  # noqa: E402

NODES = ('/stop_on_obstacle', '/obstacle_detector', '/vision_node')

# Defaults of the nodes under test (StopSettings, the scan nodes' LOG_PERIOD_S, VisionSettings).
CRUISE_SPEED_MPS = StopSettings().cruise_speed
SCAN_TIMEOUT_S = StopSettings().scan_timeout
CONTROL_PERIOD_S = 1.0 / StopSettings().rate_hz
SCAN_NODES_LOG_PERIOD_S = LOG_PERIOD_S   # a repeated scan error is logged at most this often
VISION_LOG_PERIOD_S = VisionSettings().log_period_s

# A scan laid out like the simulator's: 360 rays from -pi, ray 180 straight ahead.
SCAN_RAYS = 360
SCAN_ANGLE_MIN_RAD = -math.pi
SCAN_INCREMENT_RAD = 2.0 * math.pi / SCAN_RAYS
FRONT_RAY = 180
RANGE_MIN_M = LidarSettings().range_min
RANGE_MAX_M = LidarSettings().range_max
CLEAR_RANGE_M = 2.0             # beyond ~slow_distance (1 m): cruise
SHORT_RAY_COUNT = 300           # a ranges length the angle fields do not describe
SCAN_PERIOD_S = 0.1             # 10 Hz, like the simulated LIDAR

IMAGE_WIDTH_PX = 16             # 192 px: above ~min_area_px (100), so a mis-decoded red image would show
IMAGE_HEIGHT_PX = 12
RED_RGB = (255, 0, 0)
GREY_RGB = (128, 128, 128)
IMAGE_PERIOD_S = 0.1

# Bounds that only catch hangs: a throttled log may be held back one full period after an earlier one.
CASE_WAIT_S = 5.0
LOG_WAIT_S = 2.0 * max(SCAN_NODES_LOG_PERIOD_S, VISION_LOG_PERIOD_S) + 2.0
CONNECT_WAIT_S = harness.WAIT_FOR_TOPIC_S
POLL_S = 0.01
# After a node reacts, its output must hold for this long while the input continues (10 commands).
HOLD_S = 1.0
MIN_HELD_MESSAGES = 5
# Scheduling and delivery on a loaded two-core machine, on top of scan_timeout + one control period.
STALE_SLACK_S = 0.4


class Recorder:
    """Every message of a topic with its arrival time (time.monotonic(), s)."""

    def __init__(self, topic, msg_type):
        self._lock = threading.Lock()
        self._log = []
        self.sub = rospy.Subscriber(topic, msg_type, self._on, queue_size=100)

    def _on(self, msg):
        with self._lock:
            self._log.append((time.monotonic(), msg))

    def since(self, t):
        with self._lock:
            return [(arrived, msg) for arrived, msg in self._log if arrived >= t]

    def find(self, predicate, since):
        """(arrival, message) of the first message at or after ``since`` that matches, or None."""
        for arrived, msg in self.since(since):
            if predicate(msg):
                return arrived, msg
        return None

    def wait_for(self, predicate, since, timeout_s, what):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline and not rospy.is_shutdown():
            found = self.find(predicate, since)
            if found is not None:
                return found
            time.sleep(POLL_S)
        raise AssertionError('no %s on %s within %g s' % (what, self.sub.name, timeout_s))


class ScanSource:
    """Publishes a LaserScan template on ``scan`` every SCAN_PERIOD_S, freshly stamped, like a driver."""

    def __init__(self):
        self.pub = rospy.Publisher('scan', LaserScan, queue_size=1)
        self._lock = threading.Lock()
        self._template = None
        self.last_publish = None
        thread = threading.Thread(target=self._run, name='scan_source', daemon=True)
        thread.start()

    def set(self, template):
        """Publish ``template`` from now on (None: go silent); return the switch time (monotonic s).

        Taking the lock waits out a publish in progress, so nothing of the old template follows.
        """
        with self._lock:
            self._template = template
            return time.monotonic()

    def _run(self):
        while not rospy.is_shutdown():
            with self._lock:
                if self._template is not None:
                    self._template.header.stamp = rospy.Time.now()
                    self.pub.publish(self._template)
                    self.last_publish = time.monotonic()
            time.sleep(SCAN_PERIOD_S)


def make_scan(ranges, angle_increment=SCAN_INCREMENT_RAD):
    msg = LaserScan()
    msg.header.frame_id = 'base_scan'
    msg.angle_min = SCAN_ANGLE_MIN_RAD
    msg.angle_increment = angle_increment
    msg.angle_max = SCAN_ANGLE_MIN_RAD + (SCAN_RAYS - 1) * SCAN_INCREMENT_RAD
    msg.scan_time = SCAN_PERIOD_S
    msg.time_increment = SCAN_PERIOD_S / SCAN_RAYS
    msg.range_min = RANGE_MIN_M
    msg.range_max = RANGE_MAX_M
    msg.ranges = list(ranges)
    return msg


def uniform_scan(range_m):
    return make_scan([range_m] * SCAN_RAYS)


def make_image(encoding, width, height, step, data):
    msg = Image()
    msg.header.stamp = rospy.Time.now()
    msg.header.frame_id = 'camera_optical_frame'
    msg.encoding = encoding
    msg.width, msg.height, msg.step = width, height, step
    msg.is_bigendian = 0
    msg.data = bytes(data)
    return msg


def red_bytes(size):
    """``size`` bytes of red rgb8 pixels (the last one cut short if need be)."""
    return (bytes(RED_RGB) * (size // 3 + 1))[:size]


def solid_rgb8(rgb, width=IMAGE_WIDTH_PX, height=IMAGE_HEIGHT_PX):
    return make_image('rgb8', width, height, 3 * width, bytes(rgb) * (width * height))


def as_float32(value):
    """``value`` as the Float32 message carries it."""
    return float(numpy.float32(value))


def is_stop(cmd):
    return cmd.linear.x == 0.0


def is_cruise(cmd):
    return cmd.linear.x == CRUISE_SPEED_MPS


class BadInput(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('bad_input_test')
        cls.cmd = Recorder('cmd_vel', Twist)
        cls.distance = Recorder('obstacle_distance', Float32)
        cls.red = Recorder('red_detected', Bool)
        cls.rosout = Recorder('/rosout', Log)
        cls.scans = ScanSource()
        cls.images = rospy.Publisher('camera/image_raw', Image, queue_size=1)
        # Messages sent before a subscriber connects are lost; wait for every link first.
        links = ((cls.scans.pub, 2), (cls.images, 1), (cls.cmd.sub, 1), (cls.distance.sub, 1),
                 (cls.red.sub, 1))
        deadline = time.monotonic() + CONNECT_WAIT_S
        while any(end.get_num_connections() < count for end, count in links):
            if time.monotonic() > deadline:
                raise AssertionError('nodes under test not connected within %g s: %s' % (
                    CONNECT_WAIT_S, [(end.name, end.get_num_connections()) for end, _ in links]))
            time.sleep(POLL_S)

    # -- helpers ---------------------------------------------------------------------------------

    def _cruise(self):
        since = self.scans.set(uniform_scan(CLEAR_RANGE_M))
        self.cmd.wait_for(is_cruise, since, CASE_WAIT_S, 'cruise command after a clear scan')
        return since

    def _assert_holds(self, recorder, start, predicate, what):
        """Every message from ``start`` on, for HOLD_S more, matches ``predicate``."""
        time.sleep(HOLD_S)
        held = recorder.since(start)
        self.assertGreaterEqual(len(held), MIN_HELD_MESSAGES,
                                'only %d messages on %s in %g s' % (len(held), recorder.sub.name, HOLD_S))
        for _, msg in held:
            self.assertTrue(predicate(msg), '%s did not hold: %s' % (what, msg))

    def _assert_stops_on(self, scan, what):
        """From cruising, ``scan`` brings cmd_vel to 0 and keeps it there; return the switch time."""
        self._cruise()
        since = self.scans.set(scan)
        t_stop, _ = self.cmd.wait_for(is_stop, since, CASE_WAIT_S, 'zero command after ' + what)
        self._assert_holds(self.cmd, t_stop, lambda m: is_stop(m) and m.angular.z == 0.0,
                           'stop after ' + what)
        return since

    def _assert_distance(self, since, predicate, what):
        """obstacle_distance turns to ``what`` after ``since`` and stays so (the scan keeps coming)."""
        t_first, _ = self.distance.wait_for(predicate, since, CASE_WAIT_S, 'obstacle_distance ' + what)
        for _, msg in self.distance.since(t_first):
            self.assertTrue(predicate(msg), 'obstacle_distance %r, expected %s' % (msg.data, what))

    def _log_matcher(self, node, fragments):
        return lambda log: log.name == node and all(f in log.msg for f in fragments)

    def _assert_logged(self, node, since, *fragments):
        self.rosout.wait_for(self._log_matcher(node, fragments), since, LOG_WAIT_S,
                             'log line from %s containing %s' % (node, fragments))

    def _send_image_until_logged(self, image, *fragments):
        """Publish ``image`` until vision_node logs a line with ``fragments`` (its log is throttled)."""
        since = time.monotonic()
        matches = self._log_matcher('/vision_node', fragments)
        deadline = since + LOG_WAIT_S
        while self.rosout.find(matches, since) is None:
            if time.monotonic() > deadline or rospy.is_shutdown():
                self.fail('vision_node logged nothing containing %s within %g s' % (fragments, LOG_WAIT_S))
            self.images.publish(image)
            time.sleep(IMAGE_PERIOD_S)

    # -- scans -----------------------------------------------------------------------------------

    def test_01_clear_scan_cruises(self):
        since = self._cruise()
        self._assert_distance(since, lambda m: m.data == CLEAR_RANGE_M, '%g m' % CLEAR_RANGE_M)

    def test_02_all_nan_stops(self):
        since = self._assert_stops_on(uniform_scan(math.nan), 'an all-NaN scan')
        self._assert_distance(since, lambda m: math.isnan(m.data), 'NaN')
        self._assert_logged('/obstacle_detector', since, 'no valid reading')
        self._assert_logged('/stop_on_obstacle', since, 'no valid reading')

    def test_03_minus_inf_ahead_is_an_obstacle_at_range_min(self):
        ranges = [CLEAR_RANGE_M] * SCAN_RAYS
        ranges[FRONT_RAY] = -math.inf
        since = self._assert_stops_on(make_scan(ranges), '-inf straight ahead')
        self._assert_distance(since, lambda m: m.data == as_float32(RANGE_MIN_M), 'range_min')

    def test_04_all_plus_inf_is_clear(self):
        # From a stop, so cruising is a decision taken on the +inf scan.
        since = self.scans.set(uniform_scan(math.nan))
        self.cmd.wait_for(is_stop, since, CASE_WAIT_S, 'zero command after an all-NaN scan')
        since = self.scans.set(uniform_scan(math.inf))
        t_cruise, _ = self.cmd.wait_for(is_cruise, since, CASE_WAIT_S, 'cruise command after an all +inf scan')
        self._assert_holds(self.cmd, t_cruise, is_cruise, 'cruise on an all +inf scan')
        self._assert_distance(since, lambda m: m.data == math.inf, '+inf')

    def test_05_zero_angle_increment_stops(self):
        scan = make_scan([CLEAR_RANGE_M] * SCAN_RAYS, angle_increment=0.0)
        since = self._assert_stops_on(scan, 'angle_increment 0')
        self._assert_distance(since, lambda m: math.isnan(m.data), 'NaN')
        self._assert_logged('/stop_on_obstacle', since, 'angle_increment')
        self._assert_logged('/obstacle_detector', since, 'angle_increment')

    def test_06_ranges_length_disagreeing_with_angles_stops(self):
        scan = make_scan([CLEAR_RANGE_M] * SHORT_RAY_COUNT)
        since = self._assert_stops_on(scan, '%d ranges for %d angles' % (SHORT_RAY_COUNT, SCAN_RAYS))
        self._assert_distance(since, lambda m: math.isnan(m.data), 'NaN')
        self._assert_logged('/stop_on_obstacle', since, 'ranges', str(SHORT_RAY_COUNT))
        self._assert_logged('/obstacle_detector', since, 'ranges', str(SHORT_RAY_COUNT))

    def test_07_stale_scan_stops(self):
        self._cruise()
        self.scans.set(None)
        last_scan = self.scans.last_publish
        t_stop, _ = self.cmd.wait_for(is_stop, last_scan, CASE_WAIT_S, 'zero command after the scans stopped')
        limit_s = SCAN_TIMEOUT_S + CONTROL_PERIOD_S + STALE_SLACK_S
        self.assertLessEqual(t_stop - last_scan, limit_s,
                             'stopped %.2f s after the last scan, expected within %.2f s'
                             % (t_stop - last_scan, limit_s))
        # With no scan at all, the node keeps commanding zero rather than falling silent.
        self._assert_holds(self.cmd, t_stop, is_stop, 'stop without scans')

    # -- images ----------------------------------------------------------------------------------

    def test_08_malformed_images_are_dropped_with_a_log(self):
        start = time.monotonic()
        row = 3 * IMAGE_WIDTH_PX
        step_too_small = row - 8
        self._send_image_until_logged(
            make_image('rgb8', IMAGE_WIDTH_PX, IMAGE_HEIGHT_PX, step_too_small,
                       red_bytes(step_too_small * IMAGE_HEIGHT_PX)),
            ': step:')
        self._send_image_until_logged(
            make_image('rgb8', IMAGE_WIDTH_PX, IMAGE_HEIGHT_PX, row, red_bytes(row * IMAGE_HEIGHT_PX - row // 2)),
            ': data:')
        wide = IMAGE_WIDTH_PX + 4
        self._send_image_until_logged(
            make_image('rgb8', wide, IMAGE_HEIGHT_PX, row, red_bytes(row * IMAGE_HEIGHT_PX)),
            '%dx%d' % (wide, IMAGE_HEIGHT_PX), ': step:', 'width')
        self.assertEqual(self.red.since(start), [], 'red_detected published for an unusable image')

    def test_09_unsupported_encoding_is_named(self):
        start = time.monotonic()
        bytes_per_pixel = 4
        step = bytes_per_pixel * IMAGE_WIDTH_PX
        image = make_image('32FC1', IMAGE_WIDTH_PX, IMAGE_HEIGHT_PX, step, bytes(step * IMAGE_HEIGHT_PX))
        self._send_image_until_logged(image, "'32FC1'", 'not supported')
        self.assertEqual(self.red.since(start), [], 'red_detected published for an unsupported encoding')

    def test_10_valid_images_still_detected(self):
        for rgb, expected in ((RED_RGB, True), (GREY_RGB, False)):
            since = time.monotonic()
            image = solid_rgb8(rgb)
            deadline = since + CASE_WAIT_S
            while self.red.find(lambda m: m.data == expected, since) is None:
                if time.monotonic() > deadline or rospy.is_shutdown():
                    self.fail('no red_detected %s for a %s image within %g s' % (expected, rgb, CASE_WAIT_S))
                self.images.publish(image)
                time.sleep(IMAGE_PERIOD_S)

    # -- afterwards ------------------------------------------------------------------------------

    def test_11_every_node_still_alive(self):
        # stop_on_obstacle still drives on a good scan after all of the above (and the silence).
        self._cruise()
        for node in NODES:
            self.assertTrue(rosnode.rosnode_ping(node, max_count=1), '%s does not answer' % node)


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'bad_input', BadInput)
