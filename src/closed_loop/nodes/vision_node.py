"""The vision node: camera images in, red-object detections out (logic in closed_loop.control.vision)."""
import rospy
from geometry_msgs.msg import PointStamped
from sensor_msgs.msg import Image
from std_msgs.msg import Bool, UInt32

from closed_loop.image_encoding import ImageEncodingError, array_to_image, image_to_array
from closed_loop.nodes.common import Publisher, init_node, load_settings
from closed_loop.control.vision import SUPPORTED_ENCODINGS, VisionError, VisionSettings, detect_red_encoded

#: Socket buffer of the image subscription. rospy's 64 KiB default holds less than one camera
#: frame, so frames would queue in the socket and ``queue_size=1`` would not drop stale ones;
#: 16 MiB holds more than one 1920x1080 rgb8 frame.
IMAGE_BUFFER_BYTES = 2 ** 24
#: Only the newest image is worth examining; older ones are dropped.
IMAGE_QUEUE_SIZE = 1
#: Consumers act on the latest detection; one waiting behind it in a queue is already stale.
RESULT_QUEUE_SIZE = 1


class VisionNode(object):
    """Detects red objects in camera images with HSV thresholds.

    Subscribes:
        ``camera/image_raw`` (sensor_msgs/Image): rgb8, bgr8 or mono8. Other encodings are refused
        with a throttled error naming the encoding, and an image whose size, step and data
        disagree is dropped with a throttled error naming the field; neither publishes anything.
        mono8 has no colour and always gives ``red_detected`` false (warned about once).

    Publishes:
        ``red_detected`` (std_msgs/Bool): for every usable image, whether more than
        ``~min_area_px`` pixels are red.
        ``red_centroid`` (geometry_msgs/PointStamped): only for images where red is detected;
        header copied from the image, x = u (column) and y = v (row) of the red pixels' mean in
        pixels (pixel centres at integer coordinates), z = 0.
        ``red_area`` (std_msgs/UInt32): only for images where red is detected; red pixels.
        ``~debug_mask`` (sensor_msgs/Image, mono8): 255 where a pixel is red, header copied from
        the image; built only while the topic has subscribers.

    Parameters:
        ``~hue_low_max`` (OpenCV hue 0-179, default 10): first red band, hue in [0, hue_low_max].
        ``~hue_high_min`` (OpenCV hue, default 170): second band, hue in [hue_high_min, 179];
        180 turns it off. Must be more than ``~hue_low_max``.
        ``~saturation_min`` (0-255, default 100): least saturation of a red pixel.
        ``~value_min`` (0-255, default 100): least value (brightness) of a red pixel.
        ``~min_area_px`` (px, default 100): red is detected above this many pixels.
        ``~log_period_s`` (s, default 1.0): least time between repeated log lines.
    """

    def __init__(self):
        self._settings = load_settings(VisionSettings)
        self._detected_pub = Publisher('red_detected', Bool, queue_size=RESULT_QUEUE_SIZE)
        self._centroid_pub = Publisher('red_centroid', PointStamped,
                                             queue_size=RESULT_QUEUE_SIZE)
        self._area_pub = Publisher('red_area', UInt32, queue_size=RESULT_QUEUE_SIZE)
        self._mask_pub = Publisher('~debug_mask', Image, queue_size=IMAGE_QUEUE_SIZE)
        self._image_sub = rospy.Subscriber('camera/image_raw', Image, self._on_image,
                                           queue_size=IMAGE_QUEUE_SIZE,
                                           buff_size=IMAGE_BUFFER_BYTES, tcp_nodelay=True)

    def _on_image(self, msg):
        """Decode ``msg``, detect red in it and publish the result; bad images publish nothing."""
        period = self._settings.log_period_s
        if msg.encoding not in SUPPORTED_ENCODINGS:
            rospy.logerr_throttle(period, 'Image encoding %r is not supported; expected one of %s',
                                  msg.encoding, ', '.join(SUPPORTED_ENCODINGS))
            return
        try:
            array = image_to_array(msg.encoding, msg.height, msg.width, msg.step, msg.data,
                                   msg.is_bigendian)
        except ImageEncodingError as error:
            rospy.logerr_throttle(period, 'Dropped a %dx%d %s image: %s',
                                  msg.width, msg.height, msg.encoding, error)
            return
        if msg.encoding == 'mono8':
            rospy.logwarn_once('mono8 images have no colour: red_detected stays false for them')
        try:
            detection = detect_red_encoded(array, msg.encoding, self._settings)
        except VisionError as error:
            rospy.logerr_throttle(period, 'Dropped a %dx%d %s image: %s',
                                  msg.width, msg.height, msg.encoding, error)
            return
        self._detected_pub.publish(Bool(data=detection.detected))
        if detection.detected:
            u, v = detection.centroid_px
            point = PointStamped(header=msg.header)
            point.point.x, point.point.y, point.point.z = u, v, 0.0
            self._centroid_pub.publish(point)
            self._area_pub.publish(UInt32(data=detection.area_px))
            rospy.loginfo_throttle(period, 'Red object detected: %d px around (u=%.1f, v=%.1f)',
                                   detection.area_px, u, v)
        if self._mask_pub.get_num_connections() > 0:
            height, width, step, data = array_to_image(detection.mask, 'mono8')
            self._mask_pub.publish(Image(header=msg.header, height=height, width=width,
                                         encoding='mono8', is_bigendian=0, step=step, data=data))


def main():
    """Start the vision node and serve until shutdown."""
    init_node('vision_node')
    VisionNode()
    rospy.spin()
