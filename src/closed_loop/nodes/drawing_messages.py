"""A controller's drawings (``closed_loop.control.drawing``) as ROS messages: a Drawing is a
visualization_msgs/MarkerArray, a Note a std_msgs/String of JSON, a Goal a geometry_msgs/PoseStamped in odom and a
Route a nav_msgs/Path in odom."""
import json

from geometry_msgs.msg import Point, PoseStamped
from nav_msgs.msg import Path
from std_msgs.msg import ColorRGBA, String
from visualization_msgs.msg import Marker, MarkerArray

from closed_loop.control.drawing import Drawing, Goal, Note, Route

#: {drawing kind: (message type, latched)}: how each kind is published.
PUBLICATIONS = {Drawing: (MarkerArray, False), Note: (String, False), Goal: (PoseStamped, True),
                Route: (Path, False)}
MARKER_TYPES = {'line': Marker.LINE_STRIP, 'points': Marker.POINTS, 'sphere': Marker.SPHERE,
                'cylinder': Marker.CYLINDER, 'arrow': Marker.ARROW}


def _marker(shape, header):
    m = Marker(ns=shape.ns, id=shape.id, type=MARKER_TYPES[shape.kind], action=Marker.ADD)
    m.header = header
    m.pose.orientation.w = 1.0
    m.pose.position = Point(*shape.position)
    m.scale.x, m.scale.y, m.scale.z = shape.scale
    m.color = ColorRGBA(*shape.colour)
    m.points = [Point(float(x), float(y), float(z)) for x, y, z in shape.points]
    m.colors = [ColorRGBA(*c) for c in shape.colours]
    return m


def to_message(value, frames, stamp):
    """The message for ``value`` (a Drawing, Note, Goal or Route). ``frames``: {'base': frame id, 'odom': frame id},
    the robot's frames as its messages name them; ``stamp``: the header stamp (rospy.Time)."""
    if isinstance(value, Note):
        return String(data=json.dumps(value.data))
    if isinstance(value, Goal):
        msg = PoseStamped()
        msg.header.frame_id, msg.header.stamp = frames['odom'], stamp
        msg.pose.orientation.w = 1.0
        if value.xy is not None:
            msg.pose.position.x, msg.pose.position.y = value.xy
        return msg
    if isinstance(value, Route):
        msg = Path()
        msg.header.frame_id, msg.header.stamp = frames['odom'], stamp
        for x, y in value.points:
            pose = PoseStamped(header=msg.header)
            pose.pose.position.x, pose.pose.position.y = float(x), float(y)
            pose.pose.orientation.w = 1.0
            msg.poses.append(pose)
        return msg
    first = Marker(action=Marker.DELETEALL)
    first.header.frame_id, first.header.stamp = frames[value.frame], stamp
    markers = [first] if value.clear else []
    markers += [_marker(shape, first.header) for shape in value.shapes]
    return MarkerArray(markers=markers)
