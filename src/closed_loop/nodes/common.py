"""Helpers shared by the node classes: start-up, settings from ``~`` parameters, stamps."""
import dataclasses
import math
import os
import signal
import sys
import tempfile
import threading
import time

import rospkg
import rospy
from dynamic_reconfigure.server import Server as ReconfigureServer
from geometry_msgs.msg import Twist

from closed_loop import netenv, reconfigure, robot_model, robot_names
from closed_loop.settings import SettingsError, from_params

#: The signal by which :func:`join_launch`'s watcher asks the main thread to shut the node down.
LAUNCH_ENDED_SIGNAL = signal.SIGUSR1

#: How often a repeated warning or error of a node may reappear in the log (s).
LOG_PERIOD_S = 2.0

#: rospy's screen format with the node's name added, so every line says which node it is from. Used
#: unless the user has set ROSCONSOLE_FORMAT; roslaunch's log files and /rosout name the node anyway.
LOG_FORMAT = '[${severity}] [${time}] [${node}]: ${message}'


def log_dir_problem(log_dir):
    """Why a node cannot write its log file in ``log_dir``, or None when it can."""
    try:
        os.makedirs(log_dir, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=log_dir, prefix='.closed_loop-probe-'):
            pass
    except OSError as error:
        return error.strerror or str(error)
    return None


def init_node(name, **kwargs):
    """``rospy.init_node(name)``, after the two checks every closed_loop node makes first.

    The log format names the node (:data:`LOG_FORMAT`, unless ROSCONSOLE_FORMAT is set). A log folder
    that cannot be written (rospy would fail with a traceback) ends the process with one line that
    names the folder and the fix, and status 1.
    """
    os.environ.setdefault('ROSCONSOLE_FORMAT', LOG_FORMAT)
    log_dir = rospkg.get_log_dir()
    problem = log_dir_problem(log_dir)
    if problem is not None:
        sys.stderr.write('%s: cannot write its log in %s (%s); set ROS_LOG_DIR to a writable folder\n'
                         % (name, log_dir, problem))
        sys.exit(1)
    rospy.init_node(name, **kwargs)


class Publisher(rospy.Publisher):
    """``rospy.Publisher``, quiet once the node is shutting down. rospy closes a node's topics in a
    pre-shutdown hook, before ``rospy.is_shutdown()`` turns true, so a callback that publishes in that window
    (a scan arriving as roslaunch stops the graph) would end in "bad callback ... topic was closed during
    publish()" in the log. A publish that fails while shutdown has been asked for is dropped; any other
    failure is raised."""

    def publish(self, *args, **kwargs):
        try:
            super().publish(*args, **kwargs)
        except rospy.ROSException:
            if not (rospy.is_shutdown() or rospy.core.is_shutdown_requested()):
                raise


def join_launch(name, launch, wait_s):
    """Join, as an anonymous node without signal handlers, the graph that ``launch`` (the subprocess.Popen
    of a roslaunch) brings up. True once joined; False if no master came within ``wait_s`` s or the launch
    ended first. Call it from the main thread.

    rospy retries a registration with the master for as long as the node is up: its own start-up
    (``init_node`` registers ``/rosout``) and any subscription made as the launch ends would hang their
    caller forever. So a watcher thread shuts this node down when the launch ends. It hands the shut-down
    to the main thread (:data:`LAUNCH_ENDED_SIGNAL`), as rospy's own Ctrl-C handler does: rospy retries a
    registration holding its topics' lock, and a shut-down from another thread waits for that lock forever.
    """
    import rosgraph
    uri = rosgraph.get_master_uri()
    deadline = time.monotonic() + wait_s
    while netenv.master_pid(uri) is None:
        if launch.poll() is not None or time.monotonic() > deadline:
            return False
        time.sleep(0.2)
    main = threading.main_thread()
    signal.signal(LAUNCH_ENDED_SIGNAL, lambda signum, frame: rospy.signal_shutdown('the launch ended'))

    def watch():
        launch.wait()
        if not rospy.core.is_shutdown_requested():
            signal.pthread_kill(main.ident, LAUNCH_ENDED_SIGNAL)
    threading.Thread(target=watch, name='launch-watch', daemon=True).start()
    try:
        init_node(name, anonymous=True, disable_signals=True)
    except (rospy.ROSException, OSError):
        if launch.poll() is None:
            raise
    # A launch that ended while the node started (a required node that failed at once) is reported by the
    # caller, as one that ended before the master came.
    return launch.poll() is None


def load_settings(cls, namespaces=('~',), description=None):
    """Read ``cls`` from the node's private parameters; on a bad value log it and exit with status 2.

    ``namespaces``: where each parameter is looked for, in order (``'~'``, ``'/r1/sim/'``); the first
    that has it wins, the class default otherwise; the robot's parts (frames, wheel joints) no parameter sets,
    as the robot's description has them (``description``: its parameter; default ``robot_description`` for a
    node of one robot). The effective values (defaults included, converted) are written back to the first
    namespace, so ``rosparam get`` shows what the node runs with.
    """
    def get(name, default):
        for i, namespace in enumerate(namespaces):
            if i and name[1:] in found:         # (the robot's description before a shared fallback)
                return found[name[1:]]
            if rospy.has_param(namespace + name[1:]):
                return rospy.get_param(namespace + name[1:])
        return found.get(name[1:], default)
    found = {}
    if description or tuple(namespaces) == ('~',):
        # A part counts as named where the robot's own namespace names it (a shared fallback's value is the
        # simulator's default written back, not this robot's).
        own = (lambda name, default: rospy.get_param(namespaces[0] + name[1:], default))
        found = described_names(cls, own, description or 'robot_description')
    try:
        settings = from_params(cls, get)
    except SettingsError as error:
        where = '' if tuple(namespaces) == ('~',) else ' (in %s)' % ', '.join(namespaces)
        rospy.logfatal('%s: bad parameter %s%s', rospy.get_name(), error, where)
        sys.exit(2)
    for name, value in vars(settings).items():
        rospy.set_param(namespaces[0] + name, value)
    return settings


def described_names(cls, get, description='robot_description'):
    """{field: name} for the robot's parts (frames, wheel joints: ``closed_loop.robot_names``) among ``cls``'s
    fields that no parameter sets, as robot_description has them; {} without one, or where it cannot say."""
    fields = {f.name for f in dataclasses.fields(cls)} & set(robot_names.DEFAULTS)
    unset = {f for f in fields if get('~' + f, None) is None}
    urdf = rospy.get_param(description, None) if unset else None
    if not isinstance(urdf, str) or not urdf.strip():
        return {}
    try:
        parts = robot_names.parts(urdf, {f: get('~' + f, None) for f in fields - unset})
    except robot_model.RobotModelError:
        return {}                               # (the node's own reading of it says what is wrong)
    found = {f: parts[f] for f in unset if parts[f] != robot_names.DEFAULTS[f]}
    if found:
        rospy.loginfo('found in robot_description: %s', ', '.join('%s %r' % item for item in sorted(found.items())))
    return found


def tf_prefix():
    """The TF prefix of this node's robot ('r1/'), from the ``tf_prefix`` parameter found by searching up
    the namespace (as robot_state_publisher finds it); '' when there is none (a one-robot graph)."""
    key = rospy.search_param('tf_prefix')
    prefix = rospy.get_param(key, '') if key else ''
    prefix = prefix.strip('/') if isinstance(prefix, str) else ''
    return prefix + '/' if prefix else ''


def frame_id(name, prefix=None):
    """A URDF frame name as it is on the wire: with the robot's TF prefix (:func:`tf_prefix`)."""
    return (tf_prefix() if prefix is None else prefix) + name


class _Server(ReconfigureServer):
    """dynamic_reconfigure's server, without its silent clamping: a value out of range reaches the
    settings class's check and is refused with the reason, like any other bad value."""

    def _clamp(self, config):
        pass


class LiveSettings:
    """Serves the live fields of a node's settings (``closed_loop.reconfigure``) with dynamic_reconfigure,
    in the node's namespace (``~set_parameters``, ``~parameter_descriptions``, ``~parameter_updates``), so
    ``rosrun dynamic_reconfigure dynparam set /NODE NAME VALUE`` and rqt_reconfigure work.

    A change is checked whole by the settings class; if it passes, ``apply(new_settings)`` is called (the
    node swaps its settings under its own lock) and the new values go to the parameter server; if not, it is
    refused as dynamic_reconfigure servers conventionally refuse: the values in force are kept and returned
    (``dynparam set`` ends cleanly, ``dynparam get`` and rqt_reconfigure show what holds), and the reason is
    logged once, as a warning.
    """

    def __init__(self, settings, apply):
        self.settings = settings
        self._apply = apply
        self._started = False
        self._server = _Server(reconfigure.config_type(type(settings), settings), self._on_request)

    def _on_request(self, config, _level):
        if not self._started:  # the server's own first call, with the values the node started with
            self._started = True
            return config
        try:
            new = reconfigure.changed(self.settings, config)
        except SettingsError as error:
            rospy.logwarn('reconfigure refused, the values in force are kept: %s', error)
            config.update(reconfigure.live_values(self.settings))
            return config
        old, self.settings = self.settings, new
        self._apply(new)
        rospy.loginfo('reconfigured: %s', reconfigure.differences(old, new) or 'no change')
        config.update(reconfigure.live_values(new))
        return config


def robot_geometry(scan_frame, needs_it):
    """(footprint rectangle, the laser's pose in the base frame) from ``robot_description``; without a usable
    one, log why (``needs_it``: which node needs it, for the message) and exit with status 1."""
    urdf = rospy.get_param('robot_description', None)
    if not isinstance(urdf, str) or not urdf.strip():
        rospy.logfatal('no robot_description on the parameter server: %s needs the robot URDF', needs_it)
        raise SystemExit(1)
    try:
        return robot_model.footprint(urdf), robot_model.frame_pose_2d(urdf, scan_frame)
    except robot_model.RobotModelError as error:
        rospy.logfatal('%s', error)
        raise SystemExit(1)


def goal_param():
    """(x, y) from ``~goal_x`` and ``~goal_y`` (m, finite), or None when neither is set; a node given one without
    the other, or a value that is not a finite number, logs FATAL naming them and exits with status 2."""
    has_x, has_y = rospy.has_param('~goal_x'), rospy.has_param('~goal_y')
    if has_x != has_y:
        rospy.logfatal('%s: bad parameter: give both ~goal_x and ~goal_y, or neither', rospy.get_name())
        raise SystemExit(2)
    if not has_x:
        return None
    goal = rospy.get_param('~goal_x'), rospy.get_param('~goal_y')
    if not all(isinstance(g, (int, float)) and not isinstance(g, bool) and math.isfinite(g) for g in goal):
        rospy.logfatal('%s: bad parameter ~goal_x, ~goal_y: expected finite numbers (m), got %r'
                       % (rospy.get_name(), goal))
        raise SystemExit(2)
    return float(goal[0]), float(goal[1])


#: The simulator node's name, where its parameters are (sim.launch, scenario.launch, multi_robot.launch, kept graphs).
SIM_NODE = '/sim'


def clock_held():
    """True where a lockstepped simulator drives this graph's clock (``/use_sim_time`` and the simulator's
    ``~lockstep``): simulated time then stands still until every node has answered, however long that takes in
    wall time, and a dead simulator freezes the world with it. A wall-clock silence watchdog would stop the robot
    for the machine's load, not for stale input, and make the run depend on it: the nodes start theirs only where
    this is false (their ROS-time checks of stale input stay)."""
    return bool(rospy.get_param('/use_sim_time', False)) and bool(rospy.get_param(SIM_NODE + '/lockstep', False))


def stamp_to_sec(stamp):
    """A ``rospy.Time`` (or ``genpy.Time``) as float seconds."""
    return stamp.secs + stamp.nsecs * 1e-9


class LaserMounting:
    """Where the robot's forward direction lies in each laser frame, from ``robot_description``.

    :meth:`forward_rad` is minus the laser's yaw on the robot (its TF from the base frame, fixed by the
    URDF), so "ahead" follows the robot whatever way the laser is mounted. Without a robot description,
    or for a frame the URDF does not have, forward is 0 (the REP 103 convention), said once in the log.
    """

    def __init__(self, base_frame=robot_model.BASE_FRAME):
        self._base_frame = base_frame
        self._prefix = tf_prefix()
        self._urdf = rospy.get_param('robot_description', None)
        self._cache = {}

    def forward_rad(self, frame_id):
        if frame_id.startswith(self._prefix):
            frame_id = frame_id[len(self._prefix):]   # the URDF's name, without the robot's TF prefix
        if frame_id not in self._cache:
            forward = 0.0
            if isinstance(self._urdf, str) and self._urdf.strip():
                try:
                    forward = -robot_model.frame_pose_2d(self._urdf, frame_id, base_frame=self._base_frame).yaw
                except robot_model.RobotModelError as error:
                    rospy.logwarn('taking 0 rad as forward in frame %r: %s', frame_id, error)
            else:
                rospy.logwarn('no robot_description: taking 0 rad as forward in frame %r', frame_id)
            self._cache[frame_id] = forward
        return self._cache[frame_id]


class StopsOnShutdown:
    """For a node that drives ``cmd_vel``: on shutdown, stop its silence watchdog (``_watchdog``) and
    timer (``_timer``), refuse further commands (``_closing``, under ``lock``) and send zero on
    ``cmd_pub``. Register it with ``rospy.on_shutdown(self._on_shutdown)``."""

    def _on_shutdown(self):
        self._watchdog.stop()
        self._timer.shutdown()
        with self.lock:
            self._closing = True
            self.cmd_pub.publish(Twist())   # all zero
