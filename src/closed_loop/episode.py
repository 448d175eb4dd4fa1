"""Navigation episodes in one process: the simulator core and the navigator's core stepped in lockstep, no
ROS, for benchmarks and batches of scenarios.

The loop does what the graph does, on simulated time: physics at ``physics_rate_hz``; a LIDAR scan every
``scan_rate_hz`` period; the navigator at its ``rate_hz`` on the newest scan and the odometry (pose and
twist in ``odom``, from the wheels), as ``avoid_obstacles`` does; its command reaches the wheels
``COMMAND_DELAY_S`` later (one physics step: the time a message takes on loopback is under a millisecond,
and the node's own timer phase is already in the loop, since it acts on the newest scan at its own rate).
Everything judged comes from ground truth: contacts every physics step, the least clearance between the
robot's collision shapes and any obstacle at the navigator's rate, the final distance to the goal.
Free of ROS.
"""
import dataclasses
import math
import time

from closed_loop.commands import validate_command
from closed_loop.geometry import quaternion_yaw
from closed_loop.navigator import NavigatorSettings, NavState, Navigator
from closed_loop.rig import Rig
from closed_loop.scan import Scan
from closed_loop.sensors.lidar import Lidar
from closed_loop.settings import check

#: The goal counts as reached when ground truth ends this close to it (m), with no contact.
SUCCESS_RADIUS_M = 0.4
COMMAND_DELAY_S = 0.01
#: Clearance to obstacles is looked for up to this far (m); beyond, it reads as this.
CLEARANCE_LOOKOUT_M = 2.0


@dataclasses.dataclass
class NavResult:
    """What one navigation episode did. ``outcome``: 'reached' (the navigator said REACHED and ground truth
    is within SUCCESS_RADIUS_M of the goal, with no contact), 'collided' (any contact), 'failed' (FAILED,
    or REACHED by odometry but not by ground truth), 'timed_out'."""
    outcome: str
    state: str
    time_s: float
    contacts: int
    min_clearance_m: float
    goal_error_m: float
    path_m: float
    final_pose: tuple
    decision_ms: list
    wall_s: float
    #: With ``keep_trajectory``: (t s, truth x, y, yaw, odom x, y, yaw, state, command v, w) per decision.
    trajectory: list = None


def _transform_into_odom(start, x, y):
    """A world point in the odom frame, which starts at the robot's start pose."""
    dx, dy = x - start.x, y - start.y
    c, s = math.cos(start.yaw), math.sin(start.yaw)
    return c * dx + s * dy, -s * dx + c * dy


def run_navigation(world, profile, goal_xy, time_limit_s=80.0, nav_overrides=None, sim_overrides=None,
                   keep_trajectory=False):
    """Run ``avoid_obstacles``' core in ``world`` (a :class:`closed_loop.world.World`) with robot
    ``profile`` (:class:`closed_loop.profiles.Profile`) toward ``goal_xy`` (world frame, m) for at most
    ``time_limit_s`` simulated seconds; the profile's parameters apply, then the overrides. The camera is
    off (the navigator does not use it). Returns a :class:`NavResult`."""
    sim_params = dict(profile.node_params('sim'), camera=False, **(sim_overrides or {}))
    nav_params = dict(profile.node_params('avoid_obstacles'), **(nav_overrides or {}))
    settings = check(NavigatorSettings(**nav_params))
    footprint = profile.footprint
    laser_pose = profile.laser_pose(settings.scan_frame)
    rig = Rig(world, sim_params, profile.urdf)
    started = time.monotonic()
    try:
        sim = rig.sim
        lidar = rig.sensors[Lidar]
        layout, ls = lidar.layout, lidar.settings
        start = world.robot_start
        goal_odom = _transform_into_odom(start, *goal_xy)
        navigator = Navigator(settings, (0.0, 0.0, 0.0), goal_odom)
        steps_per_scan = max(1, int(round(lidar.period_s / sim.dt_s)))
        steps_per_control = max(1, int(round(1.0 / settings.rate_hz / sim.dt_s)))
        delay_steps = max(1, int(round(COMMAND_DELAY_S / sim.dt_s)))
        total_steps = int(round(time_limit_s / sim.dt_s))
        scan, pending, contacts, clearance, path_m, decision_ms = None, [], 0, math.inf, 0.0, []
        touching = set()
        last_xy = (start.x, start.y)
        state = navigator.state
        trajectory = [] if keep_trajectory else None
        for k in range(total_steps):
            if k % steps_per_scan == 0:
                scan = Scan(sim.time_s, lidar.frame, layout.angle_min, layout.angle_max,
                            layout.angle_increment, 0.0, lidar.period_s, ls.range_min, ls.range_max,
                            lidar.sample(sim))
            if k % steps_per_control == 0:
                odo = sim.odometry
                t0 = time.perf_counter()
                step = navigator.update(sim.time_s, (odo.x, odo.y, odo.yaw), odo.twist.linear_x,
                                        odo.twist.angular_z, scan, laser_pose, footprint)
                if step.plan is not None:
                    decision_ms.append((time.perf_counter() - t0) * 1e3)
                pending.append((k + delay_steps, validate_command(step.linear_x, step.angular_z)))
                state = step.state
                pose, _ = sim.ground_truth()
                clearance = min(clearance, sim.clearance(CLEARANCE_LOOKOUT_M))
                path_m += math.hypot(pose.position[0] - last_xy[0], pose.position[1] - last_xy[1])
                last_xy = pose.position[:2]
                if trajectory is not None:
                    trajectory.append((sim.time_s, pose.position[0], pose.position[1],
                                       quaternion_yaw(pose.orientation), odo.x, odo.y, odo.yaw, state.name,
                                       step.linear_x, step.angular_z))
                if state in (NavState.REACHED, NavState.FAILED) and abs(odo.twist.linear_x) < 1e-3 \
                        and abs(odo.twist.angular_z) < 1e-3:
                    break
            while pending and pending[0][0] <= k:
                sim.command(pending.pop(0)[1])
            sim.step()
            now_touching = sim.contacts_with_obstacles()
            contacts += len(now_touching - touching)    # a contact counts once, when it begins
            touching = now_touching
        pose, _ = sim.ground_truth()
        x, y, yaw = pose.position[0], pose.position[1], quaternion_yaw(pose.orientation)
        error = math.hypot(goal_xy[0] - x, goal_xy[1] - y)
        if contacts:
            outcome = 'collided'
        elif state is NavState.REACHED:
            outcome = 'reached' if error <= SUCCESS_RADIUS_M else 'failed'
        elif state is NavState.FAILED:
            outcome = 'failed'
        else:
            outcome = 'timed_out'
        return NavResult(outcome, state.name, sim.time_s, contacts, clearance, error, path_m, (x, y, yaw),
                         decision_ms, time.monotonic() - started, trajectory)
    finally:
        rig.close()
