"""Each controller's core as its node drives it, on plain values, for the episode runner
(``closed_loop.batch.episode``), which steps it in lockstep with the simulation.

A :class:`Controller` does what its node in ``closed_loop.nodes`` does: :meth:`Controller.on_scan` on each
scan (a command when the node would act at once, on new danger; None when it waits for its timer) and
:meth:`Controller.on_tick` on each timer tick (the command sent). Commands are (m/s, rad/s). A new
controller is a module in this package with a subclass that sets ``name`` (its node's name, also its
section in a robot profile) and ``settings_class`` (the settings class its node reads, so an episode's
settings are validated as the node's are). Free of ROS.
"""
import collections
import importlib
import pkgutil

#: The robot's odometry as a controller gets it: pose (m, rad) and speeds (m/s, rad/s) in odom, and its stamp (s).
Odom = collections.namedtuple('Odom', 'x y yaw v w stamp_s')

#: What a controller knows of the robot and the task: the laser's pose on the base
#: (``robot_model.Pose2DInBase``), the footprint rectangle, the start pose (x, y, yaw) in odom, the
#: goal (x, y) in odom or None, and the camera's pose on the base (None: no camera).
Context = collections.namedtuple('Context', 'laser_pose footprint start goal camera_pose', defaults=(None,))


class ControllerError(ValueError):
    """An unknown controller, or settings it does not have."""


class Controller:
    """Base of the episode controllers; see the module's docstring."""
    name = None
    settings_class = None
    #: Extra settings classes it also reads (for example avoid_obstacles' GoalSettings).
    extra_settings_classes = ()
    #: An episode of it ends once the robot has been at rest under a zero command for a while (a stop
    #: controller's end); False for one that rests and goes on (the navigator waits and recovers).
    ends_at_rest = True
    #: True for a controller that looks at the camera: the episode turns it on and calls :meth:`on_frame`.
    uses_camera = False

    def __init__(self, settings, context):
        self.settings = settings
        self.context = context
        #: The name of the mode last decided (what the node publishes on ``~mode``), or None.
        self.mode = None
        #: True once the controller has ended for good (the navigator's REACHED or FAILED).
        self.finished = False

    def on_scan(self, now_s, scan, odom):
        """A scan (``closed_loop.control.scan.Scan``) arrives at ``now_s``: the command to send at once, or None."""
        return None

    def on_tick(self, now_s, odom):
        """The timer fires at ``now_s``: the command to send."""
        raise NotImplementedError

    def on_frame(self, now_s, rgb, intrinsics, odom):
        """A camera frame (an RGB image, ``sensors.camera.CameraIntrinsics``) at ``now_s``."""


def controller_classes():
    """{name: class} of every controller in this package."""
    found = {}
    for module in pkgutil.iter_modules(__path__):
        importlib.import_module('%s.%s' % (__name__, module.name))
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
