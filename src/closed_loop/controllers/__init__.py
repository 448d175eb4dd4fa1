"""The controllers: one core class per controller, the only place its behaviour lives. Free of ROS.

Two hosts drive any core, unchanged: the episode runner (``closed_loop.batch.episode``), in lockstep with
the simulation, and the controller node (``closed_loop.nodes.controller_node``), behind ROS topics. A host
hands the core its inputs, sends the command it returns, and shows what it reports; the core never knows
which host it has. The calls, all on the host's clock (``now_s``: the ROS clock, simulated time in
episodes), with commands as (m/s, rad/s):

- :meth:`Controller.on_scan` with each scan (``closed_loop.control.scan.Scan``; None for one the host
  refused: a second publisher, a wrong frame, malformed): a command to send at once (new danger), or None
  to wait for the timer;
- :meth:`Controller.on_tick` on each timer tick (every ``1 / rate_hz`` s): the command to send;
- :meth:`Controller.on_silence` when no scan has arrived for ``scan_timeout`` s of wall time (the graph
  only: a dead simulator stops its clock): the command (a stop);
- :meth:`Controller.set_goal`, :meth:`Controller.on_detection`, :meth:`Controller.on_camera_info` for a
  core that takes a goal or looks at the camera (``uses_goal``, ``uses_camera``);
- :meth:`Controller.reconfigure` with new live settings (dynamic_reconfigure in the graph).

What a core reports: ``mode`` (a name, published on ``~mode``), each change of it with why
(:meth:`Controller.take_transitions`), ``fault`` (why the last command is a stop for want of usable
input, or None), ``finished`` (ended for good), and its drawings (:meth:`Controller.drawings`,
``closed_loop.control.drawing``). It writes its log lines through ``context.log``.

Adding a controller is adding a module here with a :class:`Controller` subclass that sets ``name`` (its
node's name, and its section in a robot profile) and ``settings_class`` (a ``LoopSettings`` subclass), and
a script of a few lines that starts the controller node with that name (docs/development.md).
"""
import collections
import functools
import importlib
import pkgutil

#: The robot's odometry as a controller gets it: pose (m, rad) and speeds (m/s, rad/s) in odom, and its stamp (s).
Odom = collections.namedtuple('Odom', 'x y yaw v w stamp_s')

STOP = (0.0, 0.0)


class Log:
    """Where a core's log lines go: ``info``, ``warn`` and ``error``, each with one finished string. The
    controller node hands in rospy's; episodes use this one, which drops them."""

    def info(self, text):
        pass

    def warn(self, text):
        pass

    def error(self, text):
        pass


#: What a controller knows of the robot and the task: the laser's pose on the base
#: (``geometry.Pose2D``), the footprint rectangle (None where the host has no robot model), the
#: goal (x, y) in odom or None, the camera's pose on the base (None: no camera), and the :class:`Log`.
Context = collections.namedtuple('Context', 'laser_pose footprint goal camera_pose log')
Context.__new__.__defaults__ = (None, None, None, None)


class ControllerError(ValueError):
    """An unknown controller, settings it does not have, or an input it cannot take (a goal)."""


class Controller:
    """Base of every controller's core; see the module's docstring."""
    #: Its node's name (``rosrun closed_loop NAME``), and its section in a robot profile.
    name = None
    #: Its settings class (a ``closed_loop.control.loop.LoopSettings``): its ``~parameters``, the live ones
    #: served by dynamic_reconfigure.
    settings_class = None
    #: Other settings classes it reads at start-up (their fields are ``~parameters`` too).
    extra_settings_classes = ()
    #: An episode of it ends once the robot has been at rest under a zero command for a while (a stop
    #: controller's end); False for one that rests and goes on (the navigator waits and recovers).
    ends_at_rest = True
    #: Inputs the host gives it besides the scan: odometry (``odom``), a goal (``~goal_x``, ``~goal_y``,
    #: ``move_base_simple/goal``), the camera's red detections (``red_centroid``, ``camera/camera_info``).
    uses_odom = False
    uses_goal = False
    uses_camera = False
    #: True for one that cannot work without the robot's footprint (from ``robot_description``).
    needs_footprint = False
    #: Modes whose entry is logged as a warning rather than information.
    warn_modes = ()
    #: Its drawings: {name: kind} (``closed_loop.control.drawing``), each published on ``~name``.
    outputs = {}

    def __init__(self, settings, context, *extra_settings):
        self.settings = settings
        self.context = context
        self.log = context.log or Log()
        #: The mode last entered (a name), or None before the first.
        self.mode = None
        #: Why the last command is a stop for want of usable input, or None.
        self.fault = None
        #: True once the controller has ended for good (the navigator's REACHED or FAILED).
        self.finished = False
        self._transitions = []

    # -- what a host calls -------------------------------------------------------------------------------------
    def on_scan(self, now_s, scan, odom):
        """A scan (or None: refused) at ``now_s``: the command to send at once, or None to wait for the timer."""
        return None

    def on_tick(self, now_s, odom):
        """The timer fires at ``now_s``: the command to send."""
        raise NotImplementedError

    def on_silence(self, now_s, silent_s):
        """No scan for ``silent_s`` s of wall time: the command to send (a stop)."""
        self.fault = 'no scan received for %.2f s of wall time (scan_timeout %.2f s)' % (
            silent_s, self.settings.scan_timeout)
        return STOP

    def set_goal(self, goal_xy, now_s):
        """Head for ``goal_xy`` (odom, m); :class:`ControllerError` if it cannot."""
        raise ControllerError('%s takes no goal' % self.name)

    def on_detection(self, u_px, stamp_s, odom):
        """A camera frame stamped ``stamp_s`` saw red around pixel column ``u_px``; ``odom``: the robot then."""

    def on_camera_info(self, fx_px, cx_px, width_px):
        """The camera's intrinsics: focal length and principal point along x, and the image width (px)."""

    def reconfigure(self, settings):
        """New live settings (checked whole by the settings class); the next decision uses them."""
        self.settings = settings

    # -- what it reports ---------------------------------------------------------------------------------------
    def enter(self, mode, now_s, why):
        """Make ``mode`` (a name) the mode; a change is kept for :meth:`take_transitions`."""
        if mode != self.mode:
            self._transitions.append((self.mode, mode, now_s, why))
            self.mode = mode

    def take_transitions(self):
        """The mode changes since the last call: [(old or None, new, now_s, why), ...]."""
        taken, self._transitions = self._transitions, []
        return taken

    def drawings(self, wanted):
        """{name: drawing} of the outputs named in ``wanted`` that have news since the last call."""
        return {}


@functools.lru_cache(maxsize=None)
def _import_modules():
    """Import every module of this package, once (a class defined later, elsewhere, is still found)."""
    for module in pkgutil.iter_modules(__path__):
        importlib.import_module('%s.%s' % (__name__, module.name))


def controller_classes():
    """{name: class} of every controller in this package."""
    found = {}
    _import_modules()
    stack = list(Controller.__subclasses__())
    while stack:
        cls = stack.pop()
        stack.extend(cls.__subclasses__())
        if cls.name:
            found[cls.name] = cls
    return found


def controller_class(name):
    classes = controller_classes()
    if name not in classes:
        raise ControllerError('controller: expected one of %s, got %r' % (', '.join(sorted(classes)), name))
    return classes[name]
