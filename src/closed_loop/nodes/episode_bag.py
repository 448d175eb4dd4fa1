"""``rosrun closed_loop episode_bag OUTPUT INDEX [--out FILE.bag]``: a row of a finished sweep as a bag.

It re-runs the row's spec (``closed_loop.batch.rerun``) and writes, on simulated time, what the graph would
have carried: the simulator node's topics (``/clock``, ``/scan``, ``/odom``, ``/base_pose_ground_truth``,
``/tf`` with world -> odom -> base, ``/joint_states``, ``/clearance``, ``/contact``, ``/contact_count``,
``/world_markers``, and the camera where it was on), ``/tf_static`` (the URDF's fixed joints, as
robot_state_publisher sends them), and the controller's: ``/cmd_vel``, ``/NAME/mode`` and its drawings
(``/NAME/plan``, ``/NAME/map``, ...). The messages are the simulator node's and the controller node's own conversions
(``closed_loop.nodes.sensor_messages``, ``closed_loop.nodes.drawing_messages``), each sensor on its own
schedule (``closed_loop.sim.scheduler``), from the readings the controller got (the bag never samples the
LIDAR or the contacts a second time: their noise and state would change the run). It then checks that the
re-run reproduced the row (outcome, contacts, final pose to the bit) and says so.

A graph episode's row (a controller of yours, in its own processes) is re-run as a graph with
``scenario.launch``'s recorder (``closed_loop.nodes.scenario_recorder``): every topic of the graph, from
simulated t = 0, at receipt; its re-run is held to the outcome and a final position within 3 cm.

Replay it in rviz: ``roslaunch closed_loop display.launch sim_time:=true robot:=ROBOT
mode_topic:=/NAME/mode`` and ``rosbag play FILE.bag`` (the bag has its own /clock).
"""
import os
import sys

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String, UInt32
from tf2_msgs.msg import TFMessage

from closed_loop import robot_model
from closed_loop.batch import rerun
from closed_loop.batch.lockstep import Tap
from closed_loop.nodes import sensor_messages as to_msgs
from closed_loop.nodes.drawing_messages import to_message
from closed_loop.nodes.common import SIM_NODE
from closed_loop.nodes.conversions import twist
from closed_loop.sim.profiles import ProfileError, load_profile
from closed_loop.sim.scheduler import Schedule
from closed_loop.sim.sensors.camera import Camera
from closed_loop.sim.sensors.clearance import Clearance
from closed_loop.sim.sensors.contacts import Contacts
from closed_loop.sim.sensors.lidar import Lidar
from closed_loop.sim.sensors.odometry import Odometry as OdometrySensor
from closed_loop.sim.sensors.wheels import WheelEncoders
from closed_loop.sim.sensors.world_state import WorldState

#: The sensors the bag samples itself, on their schedules: each reads the simulation and changes nothing.
SAMPLED = ((OdometrySensor, to_msgs.odometry_messages), (WheelEncoders, to_msgs.joint_messages),
           (Clearance, to_msgs.clearance_messages), (WorldState, to_msgs.world_messages))
LATCHED = {'/world_markers', '/tf_static', '/contact_count'}
FIRST_TIME = rospy.Time(0, 1)


class _Port:
    """What the simulator node's conversions ask of its robot port: one unnamed robot, every topic wanted."""
    name = ''

    def __init__(self, settings):
        self.settings = settings

    def frame(self, name):
        return name

    def wanted(self, _topic):
        return True


class BagTap(Tap):
    """Writes what an episode's loop shows it into ``bag`` (a ``rosbag.Bag`` open for writing), the controller
    named ``controller`` (its node's name: its topics are ``/NAME/...``)."""

    def __init__(self, bag, controller, urdf):
        self.bag, self.node, self.urdf = bag, '/' + controller, urdf
        self.counts = {}

    def write(self, topic, msg, t_s, callerid=SIM_NODE):
        latched = topic in LATCHED or topic == self.node + '/mode'
        header = {'topic': topic, 'type': msg._type, 'md5sum': msg._md5sum, 'message_definition': msg._full_text,
                  'callerid': callerid, 'latching': '1' if latched else '0'}
        # rosbag play (C++) skips a message recorded at time 0 ("invalid time"): t = 0 is written 1 ns later.
        self.bag.write(topic, msg, rospy.Time.from_sec(t_s) if t_s > 0 else FIRST_TIME, connection_header=header)
        self.counts[topic] = self.counts.get(topic, 0) + 1

    def _topic(self, name):
        return name if name.startswith('/') else '/' + name

    def begin(self, rig, controller, judge):
        self.rig, self.controller = rig, controller
        self.port = _Port(rig.sim.settings)
        self.lidar, self.camera = rig.sensors[Lidar], rig.sensors.get(Camera)
        self.sampled = [(rig.sensors[cls], convert) for cls, convert in SAMPLED if cls in rig.sensors]
        self.schedule = Schedule(rig.sim.dt_s)
        for index, (sensor, _) in enumerate(self.sampled):
            self.schedule.add(index, sensor.period_s, sensor.offset_s)
        self.frames = {'base': rig.sim.settings.base_frame, 'odom': to_msgs.ODOM_FRAME}
        stamp = rospy.Time.from_sec(rig.sim.time_s)
        transforms = []
        for parent, child, xyz, quaternion in robot_model.fixed_joints(self.urdf):
            tf = TransformStamped()
            tf.header.stamp, tf.header.frame_id, tf.child_frame_id = stamp, parent, child
            tf.transform.translation.x, tf.transform.translation.y, tf.transform.translation.z = xyz
            (tf.transform.rotation.x, tf.transform.rotation.y, tf.transform.rotation.z,
             tf.transform.rotation.w) = quaternion
            transforms.append(tf)
        self.write('/tf_static', TFMessage(transforms), rig.sim.time_s, '/robot_state_publisher')
        self.write('/contact_count', UInt32(0), rig.sim.time_s)
        self._sample(rig.sim.time_s)

    def _sample(self, t_s):
        self.write('/clock', Clock(clock=rospy.Time.from_sec(t_s)), t_s)
        stamp = rospy.Time.from_sec(t_s)
        for index in self.schedule.due(t_s):
            sensor, convert = self.sampled[index]
            for topic, msg in convert(self.port, sensor, sensor.sample(self.rig.sim), stamp):
                self.write(self._topic(topic), msg, t_s)

    def scan(self, t_s, ranges):
        for topic, msg in to_msgs.scan_messages(self.port, self.lidar, ranges, rospy.Time.from_sec(t_s)):
            self.write(self._topic(topic), msg, t_s)

    def frame(self, t_s, rgb):
        for topic, msg in to_msgs.camera_messages(self.port, self.camera, rgb, rospy.Time.from_sec(t_s)):
            self.write(self._topic(topic), msg, t_s)

    def decided(self, t_s):
        c = self.controller
        for _old, new, _when, _why in c.take_transitions():
            self.write(self.node + '/mode', String(data=new), t_s, self.node)
        # take_transitions gave them to the bag; the loop's own call then finds none, as it keeps only the mode.
        for name, value in c.drawings(set(c.outputs)).items():
            self.write('%s/%s' % (self.node, name), to_message(value, self.frames, rospy.Time.from_sec(t_s)), t_s,
                       self.node)

    def command(self, t_s, command):
        self.write('/cmd_vel', twist(command.linear_x, command.angular_z), t_s, self.node)

    def stepped(self, t_s, began):
        for name in began:
            self.write('/contact', String(data=name), t_s)
        if began:
            self.write('/contact_count', UInt32(self.rig.sensors[Contacts].count), t_s)
        self._sample(t_s)


def main(argv=None):
    args = rerun.row_parser('episode_bag', 'A row of a finished sweep as a bag: its spec re-run, with what the '
                            'simulator and the controller would have published.',
                            'the bag to write (default: OUTPUT/bags/episode-INDEX.bag)').parse_args(argv)
    out = os.path.abspath(args.out or os.path.join(args.output, 'bags', 'episode-%05d.bag' % args.index))
    try:
        row, spec = rerun.find_row(args.output, args.index)
        os.makedirs(os.path.dirname(out), exist_ok=True)
        if isinstance(spec.controller, dict):
            counts, (row, spec, result, found) = _graph_bag(args, out)
        else:
            with rosbag.Bag(out + '.part', 'w') as bag:
                tap = BagTap(bag, spec.controller, load_profile(spec.robot).urdf)
                row, spec, result, found = rerun.rerun(args.output, args.index, tap)
            os.replace(out + '.part', out)
            counts = tap.counts
    except (rerun.RerunError, ProfileError, OSError, rosbag.ROSBagException) as error:
        print('episode_bag: %s' % error, file=sys.stderr)
        return 2
    finally:
        if os.path.exists(out + '.part'):
            os.remove(out + '.part')
    print('episode %d: %s\nbag: %s (%d messages on %d topics)' % (args.index, result.why, out,
                                                                sum(counts.values()), len(counts)))
    for topic, count in sorted(counts.items()):
        print('  %-34s %6d' % (topic, count))
    return 0 if rerun.report_differences(args.index, found) else 1


def _graph_bag(args, out):
    """A graph episode's row re-run with its graph recorded (scenario.launch's recorder, every topic from
    t = 0) into ``out``: ({topic: messages}, rerun's answer)."""
    if os.path.exists(out):
        os.remove(out)
    answer = rerun.rerun(args.output, args.index, bag=out)
    result = answer[2]
    if not os.path.isfile(out):
        raise rerun.RerunError('row %d: the re-run graph wrote no bag (%s); its logs: %s'
                               % (args.index, result.why, result.logs))
    with rosbag.Bag(out) as bag:
        topics = bag.get_type_and_topic_info().topics
    return {topic: info.message_count for topic, info in topics.items()}, answer
