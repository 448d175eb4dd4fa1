"""fusion_controller: the navigator that waits for people (logic in closed_loop.control.fusion_navigator), behind the
usual topics and avoid_obstacles' own."""
import json

import rospy
from geometry_msgs.msg import Point, PointStamped
from sensor_msgs.msg import CameraInfo
from std_msgs.msg import ColorRGBA, String
from visualization_msgs.msg import Marker, MarkerArray

from closed_loop import robot_model
from closed_loop.control.fusion import Belief, CameraModel, FusionSettings, WaitSettings
from closed_loop.control.fusion_navigator import FusionNavigator
from closed_loop.nodes.avoid_obstacles import AvoidObstacles
from closed_loop.nodes.common import init_node, load_settings, stamp_to_sec
from closed_loop.control.tracking import TrackerSettings

BELIEF_COLOURS = {Belief.PERSON: (0.95, 0.2, 0.1, 0.8), Belief.STATIC: (0.6, 0.6, 0.6, 0.8),
                  Belief.UNKNOWN: (1.0, 0.8, 0.0, 0.8)}
TRACK_HEIGHT_M = 0.5


class FusionController(AvoidObstacles):
    """avoid_obstacles, plus: the scan's clusters tracked in odom, the vision node's red detection matched
    to a track through ``camera/camera_info`` and the camera's pose in the URDF, and a wait (WAITING, at
    rest) while a PERSON, or a near UNKNOWN, is in the path (``closed_loop.control.fusion_navigator``).

    Subscriptions, besides avoid_obstacles': ``red_centroid`` (geometry_msgs/PointStamped from vision_node:
    the red pixels' centroid, x = column, stamped with its frame's time) and ``camera/camera_info``
    (sensor_msgs/CameraInfo: K gives fx and cx). With neither (no camera), the belief is the LIDAR's alone.
    Publications, besides avoid_obstacles' (``~mode`` adds WAITING): ``~belief`` (std_msgs/String, JSON: the
    decision, why, and every track's id, belief, why, position, speed and whether it is in the path) on
    every decision, and ``~tracks`` (visualization_msgs/MarkerArray in odom: a cylinder per track coloured by
    belief, red PERSON, grey STATIC, yellow UNKNOWN, and an arrow for its velocity).
    Parameters, besides avoid_obstacles': :class:`closed_loop.control.tracking.TrackerSettings`,
    :class:`closed_loop.control.fusion.FusionSettings`, :class:`closed_loop.control.fusion.WaitSettings` (read at start-up).
    """

    def __init__(self):
        self.tracker_settings = load_settings(TrackerSettings)
        self.fusion_settings = load_settings(FusionSettings)
        self.wait_settings = load_settings(WaitSettings)
        self.camera_pose = None
        urdf = rospy.get_param('robot_description', '')
        try:
            self.camera_pose = robot_model.frame_pose_2d(urdf, robot_model.CAMERA_FRAME)
        except robot_model.RobotModelError:
            rospy.loginfo('no %s in robot_description: the belief is the LIDAR\'s alone', robot_model.CAMERA_FRAME)
        self.camera = None
        self.belief_pub = rospy.Publisher('~belief', String, queue_size=1)
        self.tracks_pub = rospy.Publisher('~tracks', MarkerArray, queue_size=1)
        AvoidObstacles.__init__(self)
        rospy.Subscriber('camera/camera_info', CameraInfo, self._on_camera_info, queue_size=1)
        rospy.Subscriber('red_centroid', PointStamped, self._on_red, queue_size=1)

    def make_navigator(self, start, goal):
        return FusionNavigator(self.settings, self.tracker_settings, self.fusion_settings, self.wait_settings,
                               start, goal, self.camera, on_transition=self._on_transition)

    def _on_camera_info(self, msg):
        if self.camera_pose is None or len(msg.K) != 9 or not msg.K[0] > 0.0 or not msg.width:
            return
        camera = CameraModel(float(msg.K[0]), float(msg.K[2]), int(msg.width), self.camera_pose)
        with self.lock:
            self.camera = camera
            if self.navigator is not None:
                self.navigator.camera = camera

    def _on_red(self, msg):
        with self.lock:
            if self.navigator is None or self.odom is None:
                return
            x, y, yaw = self.odom[:3]
            self.navigator.on_detection(float(msg.point.x), stamp_to_sec(msg.header.stamp), (x, y, yaw))

    def after_step(self, step):
        tracks = [{'id': o.track.id, 'belief': o.belief.name, 'why': o.why, 'x': round(o.track.x, 3),
                   'y': round(o.track.y, 3), 'speed': round(o.track.speed, 3), 'in_path': o.in_path}
                  for o in step.opinions]
        self.belief_pub.publish(String(data=json.dumps({'mode': step.state.name, 'why': step.reason,
                                                        'tracks': tracks})))
        if self.tracks_pub.get_num_connections() > 0:
            self.tracks_pub.publish(self._track_markers(step.opinions))

    def _track_markers(self, opinions):
        stamp = rospy.Time.now()
        clear = Marker(action=Marker.DELETEALL)
        clear.header.frame_id, clear.header.stamp = self.odom_frame, stamp
        markers = [clear]
        for o in opinions:
            body = Marker(ns='tracks', id=2 * o.track.id, type=Marker.CYLINDER, action=Marker.ADD)
            body.header = clear.header
            body.pose.position = Point(o.track.x, o.track.y, 0.5 * TRACK_HEIGHT_M)
            body.pose.orientation.w = 1.0
            body.scale.x = body.scale.y = max(o.track.size, 0.1)
            body.scale.z = TRACK_HEIGHT_M
            body.color = ColorRGBA(*BELIEF_COLOURS[o.belief])
            markers.append(body)
            if o.track.speed > 0.05:
                arrow = Marker(ns='velocities', id=2 * o.track.id + 1, type=Marker.ARROW, action=Marker.ADD)
                arrow.header = clear.header
                arrow.pose.orientation.w = 1.0
                arrow.points = [Point(o.track.x, o.track.y, TRACK_HEIGHT_M),
                                Point(o.track.x + o.track.vx, o.track.y + o.track.vy, TRACK_HEIGHT_M)]
                arrow.scale.x, arrow.scale.y, arrow.scale.z = 0.04, 0.08, 0.1
                arrow.color = ColorRGBA(*BELIEF_COLOURS[o.belief])
                markers.append(arrow)
        return MarkerArray(markers=markers)


def main():
    init_node('fusion_controller')
    FusionController()
    rospy.spin()
