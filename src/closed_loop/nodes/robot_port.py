"""One robot's side of the simulator node: its sensors' publishers and its ``cmd_vel`` input."""
import threading
import time

import rospy
from geometry_msgs.msg import Twist
from std_msgs.msg import UInt32

from closed_loop.nodes.common import LOG_PERIOD_S, load_settings
from closed_loop.nodes.conversions import connected_publishers, message_callerid
from closed_loop.sim import drive
from closed_loop.sources import SourceCheck


class RobotPort:
    """One robot's side of the simulator node: its sensors and their publishers, its ``cmd_vel`` input and
    its frame names. The only robot of a one-robot world has no name: its topics are relative to the node's
    namespace (``scan``) and its frames are the URDF's (``base_scan``). Robot NAME of a multi-robot world
    has its topics under NAME (``NAME/scan``, ``NAME/cmd_vel``) and its frames prefixed (``NAME/base_scan``,
    ``NAME/odom``), as robot_state_publisher prefixes them with the robot's ``tf_prefix``. What is the
    world's rather than a robot's (``world_markers``) is served once, by the first robot's port."""

    def __init__(self, node, index, setup, sensors):
        self.name = setup.name
        self.settings = setup.settings
        self._topic_prefix = setup.name + '/' if setup.name else ''
        self._frame_prefix = setup.name + '/' if setup.name else ''
        self._index, self._line_table = index, sensors
        self.publishers = {}
        self.attach(node)
        self._lock = threading.Lock()
        self._pending_command = None
        self._cmd_source = SourceCheck(rospy.resolve_name(self.command_topic(self.name)))
        # (tcp_nodelay: a publisher sends each command at once; with Nagle's algorithm a small message waits on the
        # loopback for the acknowledgement of the one before, up to 40 ms, unseen by the lockstep's wait.)
        self.cmd_sub = rospy.Subscriber(self.command_topic(self.name), Twist, self._on_cmd_vel, queue_size=10,
                                        tcp_nodelay=True)
        self.publishers['contact_count'].publish(UInt32(0))

    def attach(self, node, settings=None):
        """Take the robot of ``node.sim`` (a new simulation, as an episode is loaded into a kept graph: its sensors
        made again, their settings read again; ``settings``: the robot's new SimSettings). A topic keeps its
        publisher."""
        index = self._index
        if settings is not None:
            self.settings = settings
        self.view = node.sim.view(index)
        namespaces = ('/%s/sim/' % self.name, '~') if self.name else ('~',)
        self.sensors = []
        for line in self._line_table:
            if line.shared and index > 0:
                continue
            settings = (load_settings(line.sensor.settings_class, namespaces)
                        if line.sensor.settings_class else None)
            sensor = line.sensor(settings, self.view)
            if not sensor.available:
                rospy.loginfo('sim_node: no %s on %s (or turned off)', line.sensor.__name__.lower(),
                              self.label)
                continue
            self.sensors.append((line, sensor))
            for topic, msg_type, queue, latched in line.publications:
                if topic not in self.publishers:
                    self.publishers[topic] = node.publisher(self.topic(topic, line.shared), msg_type, queue, latched)

    @staticmethod
    def command_topic(name):
        """The command topic of robot ``name`` ('' for the only robot of a one-robot world)."""
        return name + '/cmd_vel' if name else 'cmd_vel'

    @property
    def label(self):
        return 'robot %r' % self.name if self.name else 'the robot'

    def describe(self):
        return '%s (%s) with %s' % (self.label, self.view.model.source,
                                  ', '.join(type(sensor).__name__ for _, sensor in self.sensors))

    def topic(self, name, shared=False):
        """A topic of this robot: global ones (``/tf``) and the world's as they are, the others under the
        robot's name."""
        return name if shared or name.startswith('/') else self._topic_prefix + name

    def frame(self, name):
        """A URDF frame name as this robot's messages carry it."""
        return self._frame_prefix + name

    def wanted(self, topic):
        """True if ``topic`` has a subscriber (messages nobody listens to are not built)."""
        return self.publishers[topic].get_num_connections() > 0

    # -- input (a subscriber thread): store, and let the loop act ----------------------------------------------
    def _on_cmd_vel(self, msg):
        conflict = self._cmd_source.observe(message_callerid(msg), None, time.monotonic(),
                                            connected_publishers(self.cmd_sub))
        if conflict is not None:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'sim_node: %s' % conflict.replace(
                'stopping until only one remains', 'the base obeys each message as it comes'))
        try:
            twist = drive.validate_twist((msg.linear.x, msg.linear.y, msg.linear.z),
                                         (msg.angular.x, msg.angular.y, msg.angular.z))
        except drive.CommandError as error:
            rospy.logwarn_throttle(LOG_PERIOD_S, 'sim_node: rejected cmd_vel: %s; braking' % error)
            twist = drive.STOP
        for clipped in drive.clipped_fields(twist, self.settings.max_linear_speed,
                                            self.settings.max_angular_speed):
            rospy.logwarn_throttle(LOG_PERIOD_S, 'sim_node: cmd_vel from %s: %s'
                                   % (message_callerid(msg) or 'an unknown publisher', clipped))
        with self._lock:
            self._pending_command = twist

    # -- the loop's side -----------------------------------------------------------------------------------------
    def take_command(self):
        """Drive by the newest command heard (real time: at once)."""
        command = self.heard()
        if command is not None:
            self.view.command(command)

    def heard(self):
        """The newest command heard since the last call (validated), or None."""
        with self._lock:
            command, self._pending_command = self._pending_command, None
        return command

    def reset(self):
        for _line, sensor in self.sensors:
            sensor.reset()
        self.publishers['contact_count'].publish(UInt32(0))

    def forget_sources(self):
        """A new episode in a kept graph: the command's publishers so far are no one's now."""
        self._cmd_source = SourceCheck(rospy.resolve_name(self.command_topic(self.name)))
        self.heard()

    def messages(self, line, sensor, stamp):
        """Sample ``sensor``: its messages ``[(topic, message)]`` (none for a lazy sensor nobody listens to)."""
        if line.lazy and not any(self.wanted(topic) for topic, _, _, _ in line.publications):
            return []
        return list(line.convert(self, sensor, sensor.sample(self.view), stamp))

    def publish(self, messages):
        for topic, msg in messages:
            self.publishers[topic].publish(msg)

    def serve(self, line, sensor, stamp):
        """Sample ``sensor`` and publish its messages."""
        self.publish(self.messages(line, sensor, stamp))
