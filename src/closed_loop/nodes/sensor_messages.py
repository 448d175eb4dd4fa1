"""Sensor readings as ROS messages: one conversion per sensor of closed_loop.sim.sensors, for sim_node's table.

A conversion is ``convert(port, sensor, reading, stamp)`` and returns ``[(topic, message), ...]``; ``port`` is
the robot's side of the simulator node (``closed_loop.nodes.robot_port.RobotPort``): it may ask
``port.wanted(topic)`` to skip building messages nobody subscribes to; ``port.settings`` is the robot's
SimSettings (URDF frame names), and ``port.frame(name)`` the frame id on the wire (with the robot's TF
prefix in a multi-robot world, ``r1/base_scan``). Topics are relative to the robot's namespace.
"""
import math

import rospy
from geometry_msgs.msg import Quaternion, TransformStamped
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, JointState, LaserScan
from std_msgs.msg import Float32, String, UInt32
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker, MarkerArray

from closed_loop import image_encoding
from closed_loop.geometry import yaw_quaternion

ODOM_FRAME = 'odom'
WORLD_FRAME = 'world'
#: world_markers: marker type per obstacle shape (closed_loop.sim.shapes.SHAPES), and the namespace.
MARKER_TYPES = {'box': Marker.CUBE, 'cylinder': Marker.CYLINDER}
WORLD_MARKER_NS = 'world'
# A small diagonal covariance for odometry (m^2, rad^2), so consumers that weigh it do not divide by 0.
ODOM_POSE_VARIANCE = 1e-3
ODOM_TWIST_VARIANCE = 1e-3


def scan_messages(node, lidar, ranges, stamp):
    """sensor_msgs/LaserScan in the LIDAR's frame; REP 117 ranges."""
    layout = lidar.layout
    msg = LaserScan()
    msg.header.stamp = stamp
    msg.header.frame_id = node.frame(node.settings.scan_frame)
    msg.angle_min = layout.angle_min
    msg.angle_max = layout.angle_max
    msg.angle_increment = layout.angle_increment
    msg.scan_time = lidar.period_s
    # A LIDAR spinning once per scan_time spends this long per ray.
    msg.time_increment = msg.scan_time * abs(layout.angle_increment) / (2.0 * math.pi)
    msg.range_min = lidar.settings.range_min
    msg.range_max = lidar.settings.range_max
    msg.ranges = ranges.tolist()
    return [('scan', msg)]


def camera_messages(node, camera, rgb, stamp):
    """sensor_msgs/Image (rgb8) and its CameraInfo, in the camera's optical frame."""
    height, width, step, data = image_encoding.array_to_image(rgb, 'rgb8')
    image = Image(height=height, width=width, encoding='rgb8', is_bigendian=0, step=step, data=data)
    image.header.stamp = stamp
    image.header.frame_id = node.frame(node.settings.camera_optical_frame)
    k = camera.intrinsics
    info = CameraInfo()
    info.header = image.header
    info.height, info.width = height, width
    info.distortion_model = 'plumb_bob'
    info.D = [0.0] * 5
    info.K = [k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0]
    info.R = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    info.P = [k.fx, 0.0, k.cx, 0.0, 0.0, k.fy, k.cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return [('camera/image_raw', image), ('camera/camera_info', info)]


def odometry_messages(node, _odometry, reading, stamp):
    """nav_msgs/Odometry odom -> base frame and its TF, with world -> odom; the ground truth in frame
    ``world``."""
    out = []
    base = node.frame(node.settings.base_frame)
    odom_frame = node.frame(ODOM_FRAME)
    if node.wanted('odom') or node.wanted('/tf'):
        odom = Odometry()
        odom.header.stamp = stamp
        odom.header.frame_id = odom_frame
        odom.child_frame_id = base
        odom.pose.pose.position.x, odom.pose.pose.position.y = reading.x, reading.y
        odom.pose.pose.orientation = Quaternion(*yaw_quaternion(reading.yaw))
        odom.twist.twist.linear.x = reading.twist.linear_x
        odom.twist.twist.angular.z = reading.twist.angular_z
        for i in range(6):
            odom.pose.covariance[7 * i] = ODOM_POSE_VARIANCE
            odom.twist.covariance[7 * i] = ODOM_TWIST_VARIANCE
        tf = TransformStamped()
        tf.header.stamp = stamp
        tf.header.frame_id = odom_frame
        tf.child_frame_id = base
        tf.transform.translation.x, tf.transform.translation.y = reading.x, reading.y
        tf.transform.rotation = odom.pose.pose.orientation
        out += [('odom', odom), ('/tf', TFMessage([world_to_odom(reading, stamp, odom_frame), tf]))]
    if node.wanted('base_pose_ground_truth'):
        pose, (linear, angular) = reading.truth_pose, reading.truth_velocity
        truth = Odometry()
        truth.header.stamp = stamp
        truth.header.frame_id = WORLD_FRAME
        truth.child_frame_id = base
        p = truth.pose.pose
        p.position.x, p.position.y, p.position.z = pose.position
        p.orientation = Quaternion(*pose.orientation)
        # nav_msgs/Odometry carries the twist in the child frame.
        yaw = pose.yaw
        truth.twist.twist.linear.x = math.cos(yaw) * linear[0] + math.sin(yaw) * linear[1]
        truth.twist.twist.linear.y = -math.sin(yaw) * linear[0] + math.cos(yaw) * linear[1]
        truth.twist.twist.linear.z = linear[2]
        truth.twist.twist.angular.z = angular[2]
        out.append(('base_pose_ground_truth', truth))
    return out


def world_to_odom(reading, stamp, odom_frame=ODOM_FRAME):
    """TF world -> odom from the ground truth and the odometry: where odometry's origin lies in the world
    (the start pose, moved by whatever odometry has drifted), so ground truth and odom share one tree."""
    truth_x, truth_y, _ = reading.truth_pose.position
    yaw = reading.truth_pose.yaw - reading.yaw
    c, s = math.cos(yaw), math.sin(yaw)
    tf = TransformStamped()
    tf.header.stamp = stamp
    tf.header.frame_id = WORLD_FRAME
    tf.child_frame_id = odom_frame
    tf.transform.translation.x = truth_x - (c * reading.x - s * reading.y)
    tf.transform.translation.y = truth_y - (s * reading.x + c * reading.y)
    tf.transform.rotation = Quaternion(*yaw_quaternion(yaw))
    return tf


def world_messages(_node, _world, reading, stamp):
    """visualization_msgs/MarkerArray of every obstacle in frame ``world``, in its colour, led by a
    DELETEALL (so markers of an earlier world do not linger); nothing when the reading is no news. Marker
    ``id`` i is the world file's obstacle i (rviz warns about a text on a shape, so the name is not sent)."""
    if not reading.news:
        return []
    clear = Marker(action=Marker.DELETEALL, ns=WORLD_MARKER_NS)
    clear.header.frame_id = WORLD_FRAME
    clear.header.stamp = stamp
    clear.pose.orientation.w = 1.0
    markers = [clear]
    for marker_id, (obstacle, position) in enumerate(reading.obstacles):
        m = Marker(ns=WORLD_MARKER_NS, id=marker_id, type=MARKER_TYPES[obstacle.shape], action=Marker.ADD)
        m.header.frame_id = WORLD_FRAME
        m.header.stamp = stamp
        m.pose.position.x, m.pose.position.y, m.pose.position.z = position
        m.pose.orientation = Quaternion(*yaw_quaternion(obstacle.yaw))
        m.scale.x, m.scale.y, m.scale.z = obstacle.size
        m.color.r, m.color.g, m.color.b, m.color.a = obstacle.color
        markers.append(m)
    return [('world_markers', MarkerArray(markers=markers))]


def joint_messages(_node, _wheels, reading, stamp):
    """sensor_msgs/JointState of every wheel joint (for robot_state_publisher)."""
    joints = JointState()
    joints.header.stamp = stamp
    joints.name, joints.position, joints.velocity = reading
    return [('joint_states', joints)]


def contact_messages(node, contacts, began, stamp):
    """std_msgs/String per contact begun, and the latched count; each contact is also a warning."""
    out = []
    for name in began:
        rospy.logwarn('sim_node: %scontact with %r at t = %.3f s', node.name + ': ' if node.name else '', name,
                      stamp.to_sec())
        out += [('contact', String(name)), ('contact_count', UInt32(contacts.count))]
    return out


def clearance_messages(_node, _clearance, reading, stamp):
    """std_msgs/Float32: the ground-truth clearance (m; +inf beyond the lookout)."""
    return [('clearance', Float32(reading))]
