"""scenario_recorder: one bag of a whole scenario, every topic of the graph from simulated t = 0.

``rosbag record`` on simulated time waits for a non-zero ``/clock`` before it subscribes to anything, so a
scenario that starts paused at t = 0 (``scenario.launch``) loses its first seconds to it. This node subscribes
to every topic as it appears (``rospy.AnyMsg``: the bytes as published, the publisher's connection header,
whatever the type), from the start, and says when it is connected to all of them (``/clock`` among them: a
scenario runs on simulated time): it then advertises
``~recording`` (std_msgs/Bool, latched), which the scenario judge waits for (its ``~wait_for``) before it
starts the simulation. Each message is written at its receipt on simulated time, as rosbag record writes
it (``/clock`` at its own value; t = 0 is written 1 ns later, which rosbag play accepts). ``/rosout`` and
``/rosout_agg`` are left out (the nodes' logs are in their log files).

Parameters: :class:`closed_loop.recording.ScenarioRecordSettings` (``~bag``, ``~min_free_mb``). The bag is
written as ``BAG.part`` and renamed to ``BAG`` when the node stops; a folder that cannot be written or a disk
short of room ends the node with a FATAL line that names the folder, and status 1.
"""
import os
import sys
import threading
import time

import rosbag
import rosgraph
import rospy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Bool

from closed_loop import recording
from closed_loop.nodes.common import Publisher, init_node, load_settings

#: How often the graph is looked at for new topics (s, wall clock): until every topic is recorded, then once it is
#: (in lockstep a look, a request to the master, is work the simulator waits for, so looks stay rare once
#: there is nothing new to find); and how often the free space is checked.
POLL_S, RECORDING_POLL_S, ROOM_CHECK_PERIOD_S = 0.05, 1.0, 2.0
LEFT_OUT = ('/rosout', '/rosout_agg')
#: Time 0 is not a valid time to rosbag play; what is received then is written 1 ns later.
FIRST_TIME = rospy.Time(0, 1)


class _Raw:
    """What rosbag's raw write asks of a message class: its md5sum (from the publisher's header)."""

    def __init__(self, md5sum):
        self._md5sum = md5sum


def keep_every(subscriber):
    """Receive every message of ``subscriber``'s topic, not the last of each read.

    On simulated time rospy subscribes to ``/clock`` itself with ``queue_size=1``, in the same subscription
    as ours, and a connection keeps the queue size it was made with: a recorder slowed by a loaded machine
    read several clock messages at once and kept only the last (a bag began at 0.06 s, not 0). A connection
    that rospy was still making when this was first called was made with a queue of 1 and joins the
    subscription afterwards, so it is called again at every look at the graph (a bag held back 1.5 s at the
    start began at 1.68 s)."""
    subscriber.impl.set_queue_size(-1)
    for connection in list(subscriber.impl.connections):
        connection.protocol.queue_size = None


class ScenarioRecorder:
    """Records every topic of the graph into one bag; see the module."""

    def __init__(self):
        self.settings = s = load_settings(recording.ScenarioRecordSettings)
        self.path = os.path.abspath(os.path.expanduser(s.bag))
        self.folder = os.path.dirname(self.path)
        problem = recording.folder_problem(self.folder, s.min_free_mb)
        if problem is not None:
            self.fail(problem)
        try:
            self.bag = rosbag.Bag(self.path + '.part', 'w')
        except (OSError, rosbag.ROSBagException) as error:
            self.fail('cannot write %s: %s' % (self.path + '.part', error))
        self.lock = threading.Lock()
        self.counts, self.subscribers = {}, {}
        self.ready = None
        self.master = rosgraph.Master(rospy.get_name())
        rospy.on_shutdown(self.close)

    def fail(self, problem):
        rospy.logfatal('recording failed: %s', problem)
        sys.exit(1)

    def on_message(self, msg, topic):
        header = msg._connection_header
        kept = {k: header[k] for k in ('callerid', 'latching', 'md5sum', 'message_definition', 'type') if k in header}
        if isinstance(msg, rospy.AnyMsg):
            raw, message = True, (header['type'], msg._buff, header['md5sum'], None, _Raw(header['md5sum']))
        else:       # /clock: rospy's own subscription to it (simulated time) gives every subscriber a Clock
            raw, message = False, msg
        t = msg.clock if isinstance(msg, Clock) else rospy.Time.now()
        with self.lock:
            if self.bag is None:
                return
            self.bag.write(topic, message, t if t > FIRST_TIME else FIRST_TIME, raw=raw,
                           connection_header=dict(kept, topic=topic))
            self.counts[topic] = self.counts.get(topic, 0) + 1

    def look(self):
        """Subscribe to topics that appeared; advertise ``~recording`` once connected to every one."""
        me = rospy.get_name()
        try:
            published = self.master.getSystemState()[0]
        except (rosgraph.MasterException, OSError):
            return
        for topic, nodes in published:
            if topic not in self.subscribers and topic not in LEFT_OUT and set(nodes) - {me}:
                self.subscribers[topic] = rospy.Subscriber(topic, rospy.AnyMsg, self.on_message, topic)
        if '/clock' in self.subscribers:
            keep_every(self.subscribers['/clock'])
        if self.ready is None and '/clock' in self.subscribers and all(
                sub.get_num_connections() > 0 for sub in self.subscribers.values()):
            rospy.loginfo('recording %d topics into %s', len(self.subscribers), self.path)
            self.ready = Publisher('~recording', Bool, queue_size=1, latch=True)
            self.ready.publish(Bool(data=True))

    def run(self):
        checked = time.monotonic()
        stop = threading.Event()
        rospy.on_shutdown(stop.set)
        while not rospy.is_shutdown():
            self.look()
            if time.monotonic() - checked > ROOM_CHECK_PERIOD_S:
                checked = time.monotonic()
                problem = recording.room_problem(self.folder, self.settings.min_free_mb)
                if problem is not None:
                    self.close()
                    self.fail(problem)
            stop.wait(POLL_S if self.ready is None else RECORDING_POLL_S)

    def close(self):
        """Close the bag and give it its name (BAG.part -> BAG)."""
        with self.lock:
            bag, self.bag = self.bag, None
        if bag is None:
            return
        bag.close()
        os.replace(self.path + '.part', self.path)
        rospy.loginfo('wrote %s: %d messages on %d topics', self.path, sum(self.counts.values()), len(self.counts))


def main():
    init_node('scenario_recorder')
    ScenarioRecorder().run()
