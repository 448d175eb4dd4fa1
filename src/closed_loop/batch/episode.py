"""Episodes in one process: the simulator's core and a controller's core (``closed_loop.controllers``)
stepped in lockstep, deterministic, free of ROS; for benchmarks and batches of scenarios
(``closed_loop.batch.sweep``).

An :class:`EpisodeSpec` names everything an episode depends on: the world (a shipped name, a file, or
``{'generator': {...}}``, ``closed_loop.sim.generators``), the robot profile, the controller and its settings (checked by
the settings class its node uses), the LIDAR's noise and seed, the goal, the time limit. :func:`run_episode`
gives an :class:`EpisodeResult`; the same spec gives the same result and trajectory, bit for bit, in any
process (nothing in it reads a clock, and the noise has its own seeded generator).

Timing, as the graph has it, on simulated time: physics at ``physics_rate_hz``; a LIDAR scan every period,
handed to the controller at its stamp (in the graph it arrives a few milliseconds of wall time later,
within the physics step); the controller's timer at its ``rate_hz``, ``timer_phase_s`` (default 0.05 s,
half a LIDAR period: the mean of a phase the node's start-up puts anywhere) after each scan; a command, from the timer or at once from
a scan (new danger), reaches the wheels ``command_delay_s`` later. That delay is one physics step: the
reaction benchmark (``bench_loop``) measures scan-to-zero-command delivery of a few milliseconds at real
time, and the simulator applies a command at its next physics step. The camera is on only for a controller
that looks at it (the fusion controller), its frames half a period after the scans, as the simulator node
has them. The LIDAR is cast with the planar caster (``closed_loop.sim.planar_rays``): exact, and many times
cheaper in clutter.

Everything judged comes from ground truth: contacts every physics step, the least clearance between the
robot's collision shapes and any obstacle at the controller's rate, the path, the deceleration.
"""
from closed_loop.batch.spec import (  # noqa: F401  (what an episode is, checked: here too for its callers)
    EpisodeError, EpisodeResult, EpisodeSpec, Prepared, SUCCESS_RADIUS_M, controller_settings, generated_world,
    judge_settings, load_episode_world, prepare, result_from_verdict)


def run_episode(spec, cache=None, logs=None, tap=None, bag=None):
    """Run ``spec`` (an :class:`EpisodeSpec`): its controller's core in lockstep with the simulation
    (``closed_loop.batch.lockstep``, shown to ``tap`` if given), or a graph (``closed_loop.batch.graph_episode``,
    its folder under ``logs``, a new folder if None; ``bag``: a .bag file the graph is recorded into). An
    unusable spec raises :class:`EpisodeError`."""
    prepared = prepare(spec, cache)
    if prepared.graph is not None:
        if tap is not None:
            raise EpisodeError('controller: a graph episode runs in its own processes; it has no loop to tap')
        from closed_loop.batch.graph_episode import run_graph
        return run_graph(spec, prepared, logs, bag)
    if bag is not None:
        raise EpisodeError('bag: an in-process episode is written as a bag through its loop (episode_bag)')
    from closed_loop.batch.lockstep import run_in_process
    return run_in_process(spec, prepared, tap)
