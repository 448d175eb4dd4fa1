"""Whether a node's connections are made: what a scenario waits for before its clock starts.

A node that has registered its publishers and subscribers with the master is not yet connected: each
subscription still asks every publisher for a connection (the master tells it whom; the publisher's TCPROS
server accepts), and until then what is published does not reach it. A controller that publishes zero
commands while it waits for its first scan, started before its connections were made, stood still for the
judge's ``rest_hold`` and was judged ``stopped`` at the start line on a loaded machine.

A connection counts as made when its publisher lists it: a node's ``getBusInfo`` (the slave API, as
``rosnode info`` reads it; rospy and roscpp alike) has a row ``(id, destination, 'o', transport, topic,
...)`` for each subscriber it sends to, once that subscriber's header has been accepted.

:func:`start_when_ready` starts a simulator that waits paused at t = 0 once the controller is up so: the
scenario judge runs it (``scenario.launch``), and the ``start_when_ready`` node does for any other launch
(``demo.launch paused:=true``), whose world's moving obstacles then meet the robot when the docs say.
"""
import time

import rosgraph
import rospy
from std_srvs.srv import Empty

from closed_loop import netenv

#: Wall time (s) a call to a node's API gets before it counts as not answering.
CALL_TIMEOUT_S = 2.0
#: How often the master is asked again while the graph comes up (wall s).
POLL_S = 0.02


#: Topics whose connections a scenario need not wait for: the nodes' log lines.
LOGGING = ('/rosout', '/rosout_agg')


def wanted(state, node, out_topics=None):
    """The connections ``(publisher, topic, subscriber)`` that ``node`` needs, from the master's
    ``getSystemState``: one from every publisher of each topic it subscribes to, and one to every subscriber
    of each topic it publishes (of ``out_topics`` only, if given); ``node`` None: every connection of the graph
    but its logging's."""
    publishers, subscribers = dict(state[0]), dict(state[1])
    if node is None:
        return sorted((p, topic, s) for topic, nodes in subscribers.items() if topic not in LOGGING
                      for s in nodes for p in publishers.get(topic, ()) if p != s)
    inbound = {(p, topic, node) for topic, nodes in subscribers.items() if node in nodes
               for p in publishers.get(topic, ()) if p != node}
    outbound = {(node, topic, s) for topic, nodes in publishers.items() if node in nodes
                and (out_topics is None or topic in out_topics) for s in subscribers.get(topic, ()) if s != node}
    return sorted(inbound | outbound)


def listed(bus_info, topic, subscriber):
    """True if a publisher's ``getBusInfo`` rows hold an outbound connection on ``topic`` to ``subscriber``."""
    return any(len(row) > 4 and row[2] == 'o' and row[4] == topic and row[1] == subscriber for row in bus_info)


def bus_info(master, node, caller_id):
    """``node``'s getBusInfo rows, or [] where it cannot be asked (gone, not answering, not a node)."""
    try:
        code, _, rows = netenv.bounded_proxy(master.lookupNode(node), CALL_TIMEOUT_S).getBusInfo(caller_id)
    except Exception:    # unknown to the master, refused, timed out, a fault: not connected, as far as we know
        return []
    return rows if code == 1 and isinstance(rows, list) else []


def missing(master, node, caller_id, out_topics=None):
    """The connections of :func:`wanted` that their publishers do not list yet, as ``'P -> TOPIC -> S'``
    lines; [] once all are made. ``master``: a ``rosgraph.Master``; ``node`` None: the whole graph."""
    try:
        pairs = wanted(master.getSystemState(), node, out_topics)
    except (rosgraph.MasterException, OSError) as error:
        return ['the master: %s' % error]
    rows = {p: bus_info(master, p, caller_id) for p in {pair[0] for pair in pairs}}
    return ['%s -> %s -> %s' % pair for pair in pairs if not listed(rows[pair[0]], pair[1], pair[2])]


def unrecorded(master, recorders):
    """``'RECORDER does not read TOPIC'`` for each topic published (but logging and the recorder's own) that one of
    ``recorders`` has not subscribed to yet."""
    if not recorders:
        return []
    try:
        state = master.getSystemState()
    except (rosgraph.MasterException, OSError) as error:
        return ['the master: %s' % error]
    subscribers = dict(state[1])
    return ['%s does not read %s' % (recorder, topic) for topic, nodes in state[0] if topic not in LOGGING
            for recorder in sorted(recorders) if set(nodes) - {recorder} and recorder not in subscribers.get(topic, ())]


def start_when_ready(start):
    """Call ``start.unpause`` (a std_srvs/Empty service: the simulator's) once some node publishes cmd_vel, each
    of the ``start.wait_for`` topics has a publisher, and every connection of the graph is made (each subscriber
    to each publisher of its topic: the controller's, and the judge's, the recorder's, any node's, so that nothing
    sent at the start is lost or late, then ``start.settle`` more), or after ``start.ready_timeout`` anyway, with
    a warning that says what was missing. ``start``: a :class:`closed_loop.batch.judge.StartSettings`."""
    topic, master = rospy.resolve_name('cmd_vel'), rosgraph.Master(rospy.get_name())
    deadline = time.monotonic() + start.ready_timeout
    try:
        # First the simulator itself: once it serves unpause, every topic of its is registered, and the connections
        # to them are among those waited for below (a check made before would not know them).
        _wait_for_service(master, rospy.resolve_name(start.unpause), deadline + 1.0)
    except rospy.ROSException as error:
        rospy.logerr('cannot start the simulation (%s): %s', start.unpause, error)
        return False
    publishers = _wait_for_publisher(master, topic, deadline)
    recorders = set()
    for other in start.wait_for.split():
        found = _wait_for_publisher(master, rospy.resolve_name(other), deadline) if publishers else []
        recorders.update(found)
        if publishers and not found:
            rospy.logwarn('no node publishes %s after %g s: starting the simulation anyway', other, start.ready_timeout)
    if not publishers:
        rospy.logwarn('no node publishes %s after %g s: starting the simulation anyway', topic, start.ready_timeout)
    else:
        lacking = _wait_for_connections(master, deadline, recorders)
        if lacking:
            rospy.logwarn('%d connection%s of the graph not made after %g s (%s): starting the simulation '
                          'anyway', len(lacking), '' if len(lacking) == 1 else 's', start.ready_timeout,
                          ', '.join(lacking[:3]) + (', ...' if len(lacking) > 3 else ''))
        else:
            time.sleep(start.settle)
            rospy.loginfo('the controller is up (%s publishes %s, connected): starting the simulation',
                          publishers[0], topic)
    try:
        rospy.ServiceProxy(start.unpause, Empty)()
    except (rospy.ROSException, rospy.ServiceException) as error:
        rospy.logerr('cannot start the simulation (%s): %s', start.unpause, error)
        return False
    return True


def _wait_for_service(master, service, deadline):
    """Once ``service`` is registered (rospy.wait_for_service looks every 0.3 s: this, every POLL_S); raises
    rospy.ROSException at ``deadline`` (wall clock)."""
    while not rospy.is_shutdown():
        try:
            master.lookupService(service)
            return
        except (rosgraph.MasterError, OSError):
            pass
        if time.monotonic() >= deadline:
            raise rospy.ROSException('%s is not served after %g s' % (service, deadline - time.monotonic()))
        time.sleep(POLL_S)


def _wait_for_publisher(master, topic, deadline):
    """The nodes that publish ``topic``, once there is one, or [] at ``deadline`` (wall clock)."""
    while not rospy.is_shutdown() and time.monotonic() < deadline:
        try:
            publishers = dict(master.getSystemState()[0]).get(topic, [])
        except (rosgraph.MasterException, OSError):
            publishers = []
        if publishers:
            return publishers
        time.sleep(POLL_S)
    return []


def _wait_for_connections(master, deadline, recorders=()):
    """Wait until every connection of the graph is made, and each of ``recorders`` (the nodes that publish a
    ``wait_for`` topic: a recorder) subscribes to every topic published. What is still missing at ``deadline``
    (wall clock), [] once all is there."""
    while True:
        lacking = unrecorded(master, recorders) + missing(master, None, rospy.get_name())
        if not lacking or rospy.is_shutdown() or time.monotonic() >= deadline:
            return lacking
        time.sleep(POLL_S)
