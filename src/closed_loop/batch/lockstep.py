"""An episode in one process: the simulation and a controller's core (``closed_loop.controllers``) stepped in
lockstep, deterministic, free of ROS, and judged by the judge (``closed_loop.batch.judge``).

Timing, as the graph has it, on simulated time: physics at ``physics_rate_hz``; a LIDAR scan every period,
handed to the controller at its stamp (in the graph it arrives a few milliseconds of wall time later,
within the physics step); the controller's timer at its ``rate_hz``, first at ``timer_phase_s`` (default 0.05 s,
half a LIDAR period: the mean of a phase a real-time node's start-up puts anywhere; a lockstepped graph's node,
started with the scenario, ticks first one period in) and every period after; a command,
from the timer or at once from a scan (new danger), reaches the wheels ``command_delay_s`` later. That
delay is one physics step: the reaction benchmark (``bench_loop``) measures scan-to-zero-command delivery
of a few milliseconds at real time, and the simulator applies a command at its next physics step. The
camera is on only for a controller that looks at it; its frames come half a period after the scans, as the
simulator node has them, and each frame with red in it gives the controller a detection, as vision_node
does. The LIDAR is cast with the planar caster (``closed_loop.sim.planar_rays``): exact, and many times
cheaper in clutter.

What is judged comes from ground truth, as the simulator node publishes it to the scenario judge: contacts
every physics step (the simulator's own contact sensor), and the pose, the speeds and the least clearance
at the judge's period.
"""
import math
import time

import cv2
import numpy

from closed_loop.batch.spec import judge_settings, result_from_verdict
from closed_loop.batch.judge import Judge
from closed_loop.commands import validate_command
from closed_loop.control.scan import Scan
from closed_loop.control.vision import VisionSettings, detect_red
from closed_loop.controllers import Context, Odom
from closed_loop.geometry import quaternion_yaw
from closed_loop.sim.rig import Rig
from closed_loop.sim.scheduler import command_delay_steps
from closed_loop.sim.sensors.camera import Camera
from closed_loop.sim.sensors.clearance import Clearance
from closed_loop.sim.sensors.contacts import Contacts
from closed_loop.sim.sensors.lidar import Lidar


class Tap:
    """What an episode's loop shows to an onlooker (``closed_loop.nodes.episode_bag`` writes it to a bag): the
    readings the controller gets and the commands it sends, as they happen, on simulated time. An onlooker
    must not sample a sensor that keeps state (the LIDAR's noise, the contacts): the loop hands it those."""

    def begin(self, rig, controller, judge):
        """Before the first step: the simulation, its sensors, the controller and the judge."""

    def scan(self, t_s, ranges):
        """The LIDAR's reading at ``t_s``, as the controller got it."""

    def frame(self, t_s, rgb):
        """A camera frame at ``t_s`` (for a controller that looks at it)."""

    def decided(self, t_s):
        """The controller was called at ``t_s`` (its mode changes and drawings are there to take)."""

    def command(self, t_s, command):
        """The controller sent ``command`` (a VelocityCommand) at ``t_s``."""

    def stepped(self, t_s, began):
        """Physics stepped to ``t_s``; contacts with the obstacles ``began`` started."""


def run_in_process(spec, prepared, tap=None):
    """Run the episode ``spec``, resolved as ``prepared`` (``closed_loop.batch.episode.prepare``); ``tap``: a
    :class:`Tap` that sees it run."""
    started = time.monotonic()
    p = prepared
    laser_pose = p.profile.laser_pose(p.settings.scan_frame)
    rig = Rig(p.world, p.sim_params, p.profile.urdf)
    try:
        try:
            camera_pose = p.profile.laser_pose(rig.sim.model.names.camera_frame)
        except ValueError:
            camera_pose = None
        controller = p.controller_class(p.settings, Context(laser_pose, p.profile.footprint, p.goal_odom,
                                                            camera_pose), *p.extra_settings)
        controller.record_timings = True
        judge = Judge(judge_settings(spec, p.controller_class), p.goal_world, keep_track=spec.keep_trajectory)
        tap = tap or Tap()
        tap.begin(rig, controller, judge)
        _loop(spec, rig, controller, judge, tap)
        verdict = judge.verdict(rig.sim.time_s, _pose(rig.sim))
        simulated_s = rig.sim.time_s
    finally:
        rig.close()
    return result_from_verdict(verdict, decision_ms=getattr(controller, 'decision_ms', []),
                               timings=dict(getattr(controller, 'timings', {})), trajectory=judge.track,
                               contact_log=judge.contact_log, wall_s=time.monotonic() - started,
                               simulated_s=simulated_s)


def _pose(sim):
    pose, _ = sim.ground_truth()
    return pose.position[0], pose.position[1], quaternion_yaw(pose.orientation)


def _loop(spec, rig, controller, judge, tap):
    sim = rig.sim
    lidar = rig.sensors[Lidar]
    contacts = rig.sensors[Contacts]
    lookout = rig.sensors[Clearance].settings.clearance_lookout
    layout, ls = lidar.layout, lidar.settings
    dt = sim.dt_s
    steps_per_scan = max(1, int(round(lidar.period_s / dt)))
    steps_per_tick = max(1, int(round(1.0 / controller.settings.rate_hz / dt)))
    # The first tick at timer_phase_s, then every period: a phase of one period is a timer that starts with the
    # scenario, as a lockstepped graph's nodes' do (a ROS timer fires first a period after it is made).
    phase = int(round(spec.timer_phase_s / dt))
    delay = command_delay_steps(spec.command_delay_s, dt)
    camera = rig.sensors.get(Camera) if controller.uses_camera else None
    if camera is not None:
        steps_per_frame = max(1, int(round(camera.period_s / dt)))
        frame_phase = int(round(camera.offset_s / dt)) % steps_per_frame
        vision = VisionSettings()
        controller.on_camera_info(camera.intrinsics.fx, camera.intrinsics.cx, camera.intrinsics.width)
    # The scan's geometry as a sensor_msgs/LaserScan carries it (float32 fields): the core decides on the numbers
    # a node gets in the graph (a navigator's choice between two arcs can turn on the last bit of an angle).
    geometry = tuple(float(numpy.float32(v)) for v in (layout.angle_min, layout.angle_max, layout.angle_increment, 0.0,
                                                         lidar.period_s, ls.range_min, ls.range_max))
    pending = []                      # (step, command), in order
    command = (0.0, 0.0)
    last = int(round(spec.time_limit_s / dt))
    # The steps at which the LIDAR, the controller's timer and the camera are next due; between them, and the
    # judge's instants and the commands' arrivals, a step is the physics and the contact check alone.
    never = last + 1
    next_scan, next_tick = 0, phase
    next_frame = frame_phase if camera is not None else never
    next_event = min(next_scan, next_tick, next_frame)
    judge_from = judge.due_from()
    apply_at = never
    stepped = tap.stepped if type(tap).stepped is not Tap.stepped else None
    for k in range(last + 1):
        now = sim.time_s
        sent = []                     # what the controller sends at this instant, in order (a scan's, a tick's)
        if k == next_event:
            scan_due, frame_due, tick_due = k == next_scan, k == next_frame, k == next_tick
            odo = sim.odometry
            odom = Odom(odo.x, odo.y, odo.yaw, odo.twist.linear_x, odo.twist.angular_z, now)
            if scan_due:
                next_scan += steps_per_scan
                scan = Scan(now, lidar.frame, *geometry, lidar.sample(sim))
                tap.scan(now, scan.ranges)
                sent.append(controller.on_scan(now, scan, odom))
            if frame_due:
                next_frame += steps_per_frame
                # What vision_node does in the graph: a red_centroid only for a frame with red in it.
                rgb = camera.sample(sim)
                tap.frame(now, rgb)
                found = detect_red(cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), vision)
                if found.detected:
                    controller.on_detection(found.centroid_px[0], now, odom)
            if tick_due:
                next_tick += steps_per_tick
                sent.append(controller.on_tick(now, odom))
            next_event = min(next_scan, next_tick, next_frame)
            tap.decided(now)
            controller.take_transitions()       # what the node logs; an episode keeps only the mode
        if now >= judge_from or k == last:
            if _judge(sim, judge, now, command, controller.mode, lookout):
                return
            judge_from = judge.due_from()
        for command_sent in sent:
            if command_sent is not None:
                pending.append((k + delay, validate_command(*command_sent)))
                tap.command(now, pending[-1][1])
                apply_at = pending[0][0]
        if k >= apply_at:
            while pending and pending[0][0] <= k:
                _, cmd = pending.pop(0)
                command = (cmd.linear_x, cmd.angular_z)
                sim.command(cmd)
                judge.on_command(command)
            apply_at = pending[0][0] if pending else never
        sim.step()
        began = contacts.sample(sim)
        if stepped is not None:
            stepped(sim.time_s, began)
        if began:
            judge.on_contact(sim.time_s, len(began), began, _pose(sim) if judge.contact_log is not None else None)
            if judge.ended:
                return


def _judge(sim, judge, now, command, mode, lookout):
    """Show the judge the robot's ground truth now; True once the episode is over."""
    pose, (linear, angular) = sim.ground_truth()
    x, y = pose.position[:2]
    yaw = quaternion_yaw(pose.orientation)
    speed = linear[0] * math.cos(yaw) + linear[1] * math.sin(yaw)       # forward, signed
    # Without a track to fill, only a clearance below the least so far matters: nothing farther is looked for
    # (the least comes out the same, at a fraction of the cost among many obstacles).
    judge.on_clearance(sim.clearance(lookout if judge.track is not None else min(lookout, judge.clearance)))
    return judge.observe(now, x, y, yaw, speed, angular[2], command, mode)
