"""What stop_on_obstacle and state_machine_controller share: the newest scan's front reading (the nearest
obstacle in the sector ahead of the robot) with its stamp, and one decision path from the scan and the
timer."""
from closed_loop.control.scan import ScanError, sector_min
from closed_loop.controllers import Controller


class FrontController(Controller):
    """Keeps the newest scan's front reading; a subclass gives :meth:`react_now` (act on this reading before
    the next tick?) and :meth:`decide` (the command, from ``self.reading`` and its age)."""

    def __init__(self, settings, context, *extra_settings):
        Controller.__init__(self, settings, context)
        self.reading = None
        self.stamp_s = None
        #: True once a scan (usable or not) has arrived: before, a stop is start-up, not a fault to report.
        self.scans_seen = False
        # "Ahead" is the robot's forward direction in the laser's frame, from how the URDF mounts the laser.
        self.forward_rad = -context.laser_pose.yaw

    def age_s(self, now_s):
        """The front reading's age (s) at ``now_s``; None without one."""
        return None if self.stamp_s is None else now_s - self.stamp_s

    def on_scan(self, now_s, scan, odom):
        self.reading, self.stamp_s, self.scans_seen = None, None, True
        if scan is not None:
            try:
                self.reading = sector_min(scan, self.forward_rad, self.settings.front_half_angle)
                self.stamp_s = scan.stamp_s
            except ScanError as error:
                self.log.error('scan rejected: %s' % error)
        # A refused or rejected scan is news too: the stop must not wait for the timer.
        if self.reading is None or self.react_now(self.reading, self.age_s(now_s)):
            return self.decide(now_s)
        return None

    def on_tick(self, now_s, odom):
        return self.decide(now_s)

    def react_now(self, reading, age_s):
        raise NotImplementedError

    def decide(self, now_s):
        raise NotImplementedError
