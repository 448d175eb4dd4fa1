"""The simulator node's loop in lockstep (``~lockstep``): simulated time goes on only once the graph has done all
that the last instant asked of it (``closed_loop.quiescence``).

Each physics step's instant ``t`` goes out in this order, the graph quiet after each part:

1. ``/clock`` at 1 ns before ``t``, then the sensor messages stamped ``t``, one sensor at a time (odometry before
   the scan, as the node's table has them), the clock and each sensor read by every node before the next goes
   out: a callback sees the clock at its message's instant (to the nanosecond) and the odometry of that instant
   beside the scan;
2. ``/clock`` at 1 ns after ``t``: every timer due at ``t`` fires now, after the messages of ``t``, so it sees
   the newest scan every time, whatever its node's threads do. (Not at ``t`` itself: rospy takes a clock of 0 for
   one not yet started and starts its timers from the first that is not, so at 0 the timers' first tick would
   slip to a step after their first period; 1 ns after every instant, a timer made at 0 fires first at its
   period, in rospy and roscpp alike.)
3. the commands heard during 1 and 2 are queued to reach the wheels ``~command_delay`` later (whole physics
   steps, at least one: as an in-process episode's ``command_delay_s``), and physics steps on.

Where the timers are is learned, not declared: for the first :data:`LEARN_S` of simulated time part 2 comes at
every step, and the simulator notes at which steps of a simulated second a command followed ``/clock`` itself (a
timer's tick, directly or through other nodes). From then on part 2 comes only at those steps of each second
(part 1 moves the clock anyway, to 1 ns before each step with sensor messages), so a node's timer at 10 Hz costs
ten of them a second, not a hundred. A timer that commanded nothing in that time, or one that starts later off
those steps, fires at the next ``/clock`` instead, up to a sensor period late, the same way every time.
``~clock_every_step`` keeps part 2 at every step.
A node that computes past ``~lockstep_timeout`` of CPU time at one instant (``closed_loop.quiescence``) makes it
*missed*: the count goes out on
``~missed_ticks`` (std_msgs/UInt32, latched), and the base acts on the commands it has.

What a node of the launch is sent goes out in the simulator's own thread, before the wait that follows (rospy's
synchronous publishing); to any other subscriber (``rostopic echo``, rviz, ``rosbag record`` started apart) it
goes through rospy's queue, so a watcher that stops reading drops messages and holds nothing up.
"""
import collections
import os
import socket
import threading
import time
import xmlrpc.client

import rosgraph
import rospy
from std_msgs.msg import UInt32

from closed_loop import netenv
from closed_loop.batch.kept_graph import ROOT_VARIABLE
from closed_loop.nodes.common import Publisher
from closed_loop.participants import node_name
from closed_loop.quiescence import EVERY, Participants, Quiescence
from closed_loop.sim.scheduler import LEARN_S, command_delay_steps
from closed_loop.stall_watch import StallWatch

#: The clock of a step's sensor messages, and of its timers: this much before and after the step's instant.
BEFORE = AFTER = rospy.Duration(0, 1)
#: After a wave a controller answers (a sensor's messages, /clock at a timer's step), the simulator holds for its
#: command (wall s; it ends when the command comes): while learning, after every wave (so a wave nobody answers
#: costs LEARN_HOLD_S), after that after the learned ones (:class:`Answers`).
LEARN_HOLD_S, TICK_HOLD_S, SILENT_AFTER, HOLD_POLL_S = 0.002, 0.05, 3, 0.0002
#: Idle sleep while paused (s).
PAUSED_POLL_S = 0.01
#: Wall time (s) a look-up of a subscriber's process may take.
LOOKUP_S = 2.0
#: Wall time (s) without a physics step (unpaused) after which the loop's stack is logged: a wait ends within
#: BACKSTOP lockstep timeouts (20 s by default), so a stand this long is a hang to be shown where it is.
STALL_S = 60.0
#: Where simulated time goes on by less than this share of the wall time over STALL_S, a warning says so: a run
#: that crawls (each instant needs every node to run in turn, and a busy machine or a low CPU priority keeps
#: them from it) looks like a hang from outside (a CI's rostest at niceness 19: 1.2 s in 111 s of wall time).
SLOW_PACE = 0.05


def missed_publisher():
    """``~missed_ticks`` (std_msgs/UInt32, latched), at 0: made with the simulator's other topics, before it serves
    unpause, so that a scenario's judge is connected to it before the start."""
    publisher = Publisher('~missed_ticks', UInt32, queue_size=1, latch=True)
    publisher.publish(UInt32(0))
    return publisher


class LaunchNodes:
    """Which nodes take part in the lockstep: the processes of the launch that started the simulator (its parent
    roslaunch's descendants; in a kept graph, the keeper's, but the simulator's own roslaunch) and the master, but
    rosout and the ``watchers`` (node names: rviz), and the simulator's
    own threads but its loop's (those that accept a new subscriber, and read what the graph sends it: a node that
    subscribes anew for each scan, as ``rospy.wait_for_message`` does, is connected at the same instant every
    time)."""

    def __init__(self, watchers=''):
        master = netenv.master_pid(rosgraph.get_master_uri())
        self._watchers = ['/rosout'] + [rospy.resolve_name(name) for name in watchers.split()]
        root = launch_root()
        # In a kept graph, the simulator's own launch (its parent) only watches its nodes, as the root does.
        self._launchers = {os.getppid()} if root != os.getppid() else set()
        self.participants = Participants(root, extra=[master] if master else [], exclude=self.left_out)
        self.forget()

    def forget(self):
        """A new episode in a kept graph: nodes are looked up again (a node of the last one may have the name of
        one of this one)."""
        self._left_out = dict.fromkeys(self._watchers)
        self._known = {}

    def left_out(self, found=frozenset()):
        """The pids of rosout and the watchers, each looked up until it is found: among the processes ``found``
        by the node name they were started with (from their start, before they have told the master: a watcher
        that computes as it starts, rviz, is not waited for then either), else through the master."""
        for name, pid in self._left_out.items():
            if pid is None:
                self._left_out[name] = next((p for p in found if node_name(p) == name), None) or self._pid(name)
        return (set(self._left_out.values()) | self._launchers) - {None}

    def has(self, caller_id):
        """True if node ``caller_id`` runs in one of the launch's processes (asked of it and the master once)."""
        return self.pid(caller_id) is not None

    def pid(self, caller_id):
        """The pid of node ``caller_id`` if it runs in one of the launch's processes, else None."""
        if caller_id not in self._known:
            pid = self._pid(caller_id)
            self._known[caller_id] = pid if pid in self.participants.pids() else None     # (watchers are not)
        return self._known[caller_id]

    def receivers(self, publishers):
        """The pids of the launch's processes that ``publishers`` (rospy Publishers) send to now."""
        return {self.pid(c.endpoint_id) for p in publishers for c in list(p.impl.connections)} - {None}

    @staticmethod
    def _pid(caller_id):
        # (Both calls bounded: rosgraph.Master's own waits for the master for ever, in the simulator's loop.)
        try:
            code, _, uri = netenv.bounded_proxy(rosgraph.get_master_uri(), LOOKUP_S).lookupNode(rospy.get_name(),
                                                                                               caller_id)
            if code != 1:
                return None
            code, _, pid = netenv.bounded_proxy(uri, LOOKUP_S).getPid(rospy.get_name())
            return pid if code == 1 else None
        except (OSError, xmlrpc.client.Error, ValueError, TypeError):
            return None


def launch_root():
    """The process whose descendants take part: the launch that started the simulator, or the keeper of a kept
    graph (``closed_loop.batch.kept_graph.ROOT_VARIABLE``), which starts each episode's own launch beside it."""
    root = os.environ.get(ROOT_VARIABLE, '')
    return int(root) if root.isdigit() and os.path.exists('/proc/' + root) else os.getppid()


def write_through(publisher, launch_nodes):
    """``publisher`` writes each message to the launch's own nodes in the publishing thread, with TCP_NODELAY
    whatever the subscriber asked (with Nagle's algorithm a small message, a /clock, waits on the loopback for the
    acknowledgement of the one before, up to 40 ms, where the lockstep's wait cannot see it), and through rospy's
    queue to any other subscriber (see the module's doc). Call it as soon as the publisher is made."""
    impl = publisher.impl
    add = impl.add_connection
    lock = threading.Lock()

    def add_connection(connection):
        if not launch_nodes.has(connection.endpoint_id):
            return add(connection)
        sock = getattr(connection, 'socket', None)
        if sock is not None:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        with lock:
            queue_size, impl.queue_size = impl.queue_size, None     # rospy's synchronous publishing
            try:
                return add(connection)
            finally:
                impl.queue_size = queue_size
    impl.add_connection = add_connection
    return publisher


def keep_own_time():
    """Stop the simulator hearing its own ``/clock`` (rospy subscribes every node on simulated time to it): each
    message would wake a thread of ours that competes with the loop for Python's lock; the loop sets the
    simulator's ROS time itself as it publishes (:func:`set_own_time`). Where rospy keeps its subscription
    elsewhere, nothing changes."""
    from rospy.impl import simtime
    subscriber = getattr(simtime, '_clock_sub', None)
    if subscriber is not None:
        subscriber.unregister()


def set_own_time(stamp):
    rospy.rostime._set_rostime(stamp)


class Answers:
    """What the robots' controllers answer: the waves (a sensor line's messages of a robot, or /clock at a step of
    a second) after which a robot's command came while learning. After learning, the simulator holds after such a
    wave until that command has come (:func:`hold`), except for a robot whose command did not come there
    :data:`SILENT_AFTER` times in a row (it fell silent), until it comes there again."""

    def __init__(self, robots):
        self.robots = robots
        self.learned = {}                       # wave -> the robots (port indices) that answered it
        self.strikes = collections.Counter()    # (wave, robot): holds in a row that ended with no command

    def collect(self, node, gate, wave, learning):
        """The commands ``node``'s ports heard after ``wave`` ([(port, command or None)]), held for as above
        (while learning, for any robot, :data:`LEARN_HOLD_S`)."""
        got = [(port, port.heard()) for port in node.ports]
        wanted = (set(range(self.robots)) if learning else
                  {i for i in self.learned.get(wave, ()) if self.strikes[wave, i] < SILENT_AFTER})
        hold(node, gate, got, wanted, LEARN_HOLD_S if learning else TICK_HOLD_S)
        for i, (_, command) in enumerate(got):
            if command is not None:
                self.strikes[wave, i] = 0
                if learning:
                    self.learned.setdefault(wave, set()).add(i)
            elif i in wanted and not learning:
                self.strikes[wave, i] += 1
        return got


def hold(node, gate, got, wanted, hold_s):
    """Hold until each port of ``wanted`` (indices into ``node.ports``) has a command in ``got`` (what the ports
    heard after a wave), or for ``hold_s`` of wall time: a command can reach the simulator's socket a little after
    the graph was seen quiet (measured on a loaded machine: about a millisecond, from a roscpp timer and from a rospy
    node that answers each scan). What comes is put in ``got``, and the graph waited for once more."""
    missing = {i for i in wanted if got[i][1] is None}
    end = time.monotonic() + hold_s
    came = False
    while missing and time.monotonic() < end and not gate.stopping():
        time.sleep(HOLD_POLL_S)
        for i, port in enumerate(node.ports):
            command = port.heard()
            if command is not None:
                got[i], came = (port, command), True
                missing.discard(i)
    if came:
        gate.wait(poll=EVERY)
        for i, port in enumerate(node.ports):
            command = port.heard()
            if command is not None:
                got[i] = (port, command)


def _steps(n):
    return '%d physics step%s' % (n, '' if n == 1 else 's')


def _name(pid):
    try:
        with open('/proc/%d/comm' % pid) as f:
            return f.read().strip()
    except OSError:
        return str(pid)


def run(node):
    """The lockstep loop of :class:`closed_loop.nodes.sim_node.SimNode` ``node`` until shutdown."""
    s = node.scheduling
    keep_own_time()
    missed_pub = node.missed_pub
    gate = Quiescence(node.launch_nodes.participants, s.lockstep_timeout,
                      stopping=lambda: node._stopped.is_set() or rospy.is_shutdown())
    sim = None
    def slow(gone_on, wall_s):
        rospy.logwarn('sim_node: lockstep: %.2f s of simulated time in the last %.0f s of wall time (%.3fx real time): '
                      "the graph's nodes are slow to answer, or kept from the CPU (a busy machine, a niceness, a CPU "
                      'limit); %d instants missed so far', gone_on, wall_s, gone_on / wall_s, gate.missed)
    watch = StallWatch(lambda: (id(node.sim), node.sim.time_s), lambda: node._paused or node._stopped.is_set(),
                       lambda text: rospy.logwarn('sim_node: lockstep: %s', text), STALL_S,
                       pace=(lambda: node.sim.time_s, SLOW_PACE, slow)).start()
    rospy.loginfo('sim_node: lockstep: each instant waits for the graph (a node computing at most %g s), commands '
                  'reach the wheels %s later', s.lockstep_timeout, _steps(command_delay_steps(s.command_delay,
                                                                                              node.sim.dt_s)))
    try:
        while not node._stopped.is_set() and not rospy.is_shutdown():
            if node._take_requests() or sim is not node.sim:    # the start, a reset, or an episode loaded
                if sim is not None:
                    queued.clear()
                    ahead = False
                if sim is not node.sim:
                    sim, s = node.sim, node.scheduling
                    schedule, tasks = node._schedule()
                    delay = command_delay_steps(s.command_delay, sim.dt_s)
                    step_ns = int(round(sim.dt_s * 1e9))
                    learn_steps, second_steps = int(round(LEARN_S / sim.dt_s)), int(round(1.0 / sim.dt_s))
                    queued = collections.deque()          # (step, port, command), in the order heard
                    answers = Answers(len(node.ports))
                    pollers = None                        # found at the first instant, the graph idle since the start
                    ahead = False       # the clock of the coming step's sensor messages is out already
                    if gate.missed:
                        missed_pub.publish(UInt32(0))
                    gate.restart()
                    gate.timeout_s = s.lockstep_timeout
                    missed = 0
            if node._paused:
                time.sleep(PAUSED_POLL_S)
                continue
            if pollers is None:
                pollers = gate.find_pollers()
                if pollers:
                    rospy.loginfo('sim_node: lockstep: %d thread%s of %s look%s again on their own every few ms of '
                                  'wall time: %s waited for after what concerns %s' % (
                                      len(pollers), '' if len(pollers) == 1 else 's',
                                      ', '.join(sorted({_name(pid) for pid, _ in pollers})),
                                      's' if len(pollers) == 1 else '', 'it is' if len(pollers) == 1 else 'they are',
                                      'it' if len(pollers) == 1 else 'them'))
            k = int(round(sim.time_s / sim.dt_s))
            # The instant in whole nanoseconds from the step count (the float sum of steps drifts: 190 steps of
            # 0.01 s make 1.8999999999999997 s, and a timer due at 1.9 s would wait for the next step).
            stamp = rospy.Time(0, k * step_ns)
            # Every sensor's messages are made first (the world stands still within an instant), while the
            # nodes take in the clock that went out before physics stepped here.
            lines = [(port, messages) for port, messages in
                     ((tasks[name][0], tasks[name][0].messages(tasks[name][1], tasks[name][2], stamp))
                      for name in schedule.due(sim.time_s)) if messages]
            if lines and not ahead and k > 0:          # (at t = 0 the clock reads 0 already)
                node._publish_clock(stamp - BEFORE)
                ahead = True
            if ahead:
                gate.wait()                            # every node has the clock before the messages
            learning = k < learn_steps
            heard = [(port, port.heard()) for port in node.ports]
            for port, messages in lines:
                port.publish(messages)
                gate.wait(poll=node.launch_nodes.receivers(port.publishers[topic] for topic, _ in messages))
                heard += answers.collect(node, gate, (node.ports.index(port),) + tuple(t for t, _ in messages),
                                         learning)
            residue = ('clock', k % second_steps)
            if learning or s.clock_every_step or residue in answers.learned:
                node._publish_clock(stamp + AFTER)
                gate.wait(poll=EVERY)
                heard += answers.collect(node, gate, residue, learning)
            if k == learn_steps and not s.clock_every_step:
                rospy.loginfo('sim_node: lockstep: /clock goes out with every sensor message and at %d of the %d '
                              'steps of each second (where a timer commanded)',
                              sum(key[0] == 'clock' for key in answers.learned), second_steps)
            if gate.missed != missed:
                missed = gate.missed
                missed_pub.publish(UInt32(missed))
                rospy.logwarn_throttle(10.0, 'sim_node: lockstep: %d instant%s missed (the last: %s)' % (
                    missed, '' if missed == 1 else 's', gate.why_last_miss()))
            queued.extend((k + delay, port, command) for port, command in heard if command is not None)
            while queued and queued[0][0] <= k:
                _, port, command = queued.popleft()
                port.view.command(command)
            # The next step's clock for its sensor messages goes out now, and the nodes take it in while physics
            # steps (everything of this instant is done: nothing can see it early).
            ahead = schedule.periodic_due(sim.time_s + sim.dt_s)
            if ahead:
                node._publish_clock(rospy.Time(0, (k + 1) * step_ns) - BEFORE)
            sim.step()
    finally:
        watch.stop()
        gate.close()
