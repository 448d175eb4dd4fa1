"""What stop_on_obstacle and state_machine_controller share (``closed_loop.nodes.front_controller``): the
front sector's reading of each scan, its age, and the decision path from the scan and from the timer."""
from closed_loop.controllers import Controller
from closed_loop.control.scan import ScanError, sector_min


class FrontController(Controller):
    """Keeps the newest scan's front reading; subclasses give :meth:`react_now` and :meth:`decide`."""

    def __init__(self, settings, context):
        Controller.__init__(self, settings, context)
        self.reading = None
        self.stamp_s = None
        # "Ahead" is the robot's forward direction in the laser's frame.
        self.forward_rad = -context.laser_pose.yaw

    def age_s(self, now_s):
        return None if self.stamp_s is None else now_s - self.stamp_s

    def on_scan(self, now_s, scan, odom):
        try:
            self.reading = sector_min(scan, self.forward_rad, self.settings.front_half_angle)
            self.stamp_s = scan.stamp_s
        except ScanError:
            self.reading, self.stamp_s = None, None
        if self.reading is None or self.react_now(self.reading, self.age_s(now_s)):
            return self.decide(now_s)
        return None

    def on_tick(self, now_s, odom):
        return self.decide(now_s)

    def react_now(self, reading, age_s):
        raise NotImplementedError

    def decide(self, now_s):
        raise NotImplementedError
