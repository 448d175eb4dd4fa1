"""obstacle_detector: the nearest obstacle overall and per sector, from each laser scan."""
import math

import rospy
from sensor_msgs.msg import LaserScan
from std_msgs.msg import Float32

from closed_loop.nodes.common import LOG_PERIOD_S, LaserMounting, LiveSettings, Publisher, init_node, load_settings
from closed_loop.nodes.conversions import scan_from_msg
from closed_loop.control.scan import (SECTOR_CENTRES_RAD, DetectorSettings, ScanError, describe_reading,
                              nearest, sector_readings)


# One output per scan: a burst of scans (rosbag play, a busy machine) must not lose any, and each is
# cheap to process, so queue a few rather than keep only the newest.
SCAN_QUEUE_SIZE = 10
#: An obstacle within warn_distance is a standing state (a robot stopped at a wall stays so): warned once on
#: entry, and again only after the nearest obstacle has been this much beyond warn_distance.
WARN_RELEASE_M = 0.05


class ObstacleDetector:
    """Publishes obstacle distances for every scan it receives.

    Distances follow REP 117: +inf when every valid ray is clear, NaN when no ray is valid (or the
    scan is malformed); never a made-up number.

    Subscriptions:
        ``scan`` (sensor_msgs/LaserScan).
    Publications (std_msgs/Float32, m, one message each per scan):
        ``obstacle_distance``: nearest obstacle over the whole scan.
        ``obstacle_distance/front``: within ``~front_half_angle`` of 0 (forward).
        ``obstacle_distance/left``: within ``~side_half_angle`` of +pi/2.
        ``obstacle_distance/right``: within ``~side_half_angle`` of -pi/2.
    Parameters:
        ``~front_half_angle`` (rad, default pi/2): half-width of the front sector.
        ``~side_half_angle`` (rad, default pi/4): half-width of the left and right sectors.
        ``~warn_distance`` (m, default 0.5): log a warning when the nearest obstacle comes closer than
        this (once; again only after it has been ``WARN_RELEASE_M`` beyond it).
        All three are live (dynamic_reconfigure, :class:`closed_loop.nodes.common.LiveSettings`).
    """

    def __init__(self):
        self._settings = load_settings(DetectorSettings)
        self._nearest_pub = Publisher('obstacle_distance', Float32, queue_size=SCAN_QUEUE_SIZE)
        self._sector_pubs = {name: Publisher('obstacle_distance/' + name, Float32,
                                                   queue_size=SCAN_QUEUE_SIZE)
                             for name in SECTOR_CENTRES_RAD}
        # Sectors turn with the laser's mounting on the robot (robot_description), per scan frame.
        self._mounting = LaserMounting()
        self._scan_sub = rospy.Subscriber('scan', LaserScan, self._on_scan, queue_size=SCAN_QUEUE_SIZE,
                                          tcp_nodelay=True)
        self._close = False   # an obstacle within warn_distance was reported and has not left
        # Live settings: each scan reads self._settings once; swapping the reference is atomic.
        self._live = LiveSettings(self._settings, self._take_settings)

    def _take_settings(self, settings):
        self._settings = settings

    def _on_scan(self, msg):
        # The output is the per-scan conversion itself, so it is published from the callback.
        settings = self._settings
        try:
            scan = scan_from_msg(msg)
            overall = nearest(scan)
            sectors = sector_readings(scan, settings, self._mounting.forward_rad(msg.header.frame_id))
        except ScanError as error:
            rospy.logerr_throttle(LOG_PERIOD_S, 'scan rejected: %s', error)
            self._publish_all(math.nan, {name: math.nan for name in self._sector_pubs})
            return
        self._publish_all(overall.distance_m,
                          {name: reading.distance_m for name, reading in sectors.items()})
        if not overall.trusted:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'scan has %s', describe_reading(overall))
        elif overall.distance_m < settings.warn_distance:
            if not self._close:
                rospy.logwarn('Obstacle close: %.2f m (warn_distance %.2f m)', overall.distance_m,
                              settings.warn_distance)
                self._close = True
        else:
            if self._close and overall.distance_m >= settings.warn_distance + WARN_RELEASE_M:
                rospy.loginfo('Clear again: nearest obstacle %.2f m', overall.distance_m)
                self._close = False
            rospy.logdebug_throttle(LOG_PERIOD_S, 'Clear: nearest obstacle %.2f m',
                                    overall.distance_m)

    def _publish_all(self, nearest_m, sector_m):
        self._nearest_pub.publish(Float32(data=nearest_m))
        for name, publisher in self._sector_pubs.items():
            publisher.publish(Float32(data=sector_m[name]))


def main():
    init_node('obstacle_detector')
    ObstacleDetector()
    rospy.spin()
