"""Graph episodes: an episode whose controller is a ROS graph, for a controller that is not one of this
package's cores (a node of yours, in Python or C++), or one of ours run as its node. Free of rospy: the graph
is other processes.

Each graph episode is a real graph of its own: a master on a free loopback port (``graph_keeper``), its
own ``ROS_HOME`` and log folder, the simulator (``sim.launch``, in lockstep with the graph: simulated time goes on
only once every node has answered, ``closed_loop.nodes.sim_lockstep``; or, where the spec gives a
``real_time_factor``, in real time at that factor),
``robot_state_publisher``, the controller (a launch file of yours with its args, or a node of this package
with its settings), and the scenario judge, whose verdict (``closed_loop.batch.judge``, the rules of every
episode) is the result. Its row has the columns of an in-process episode, and ``logs``, the episode's folder
(the generated launch file, the graph's output, each node's log). What goes wrong is an ``error`` result that
says what: a launch that does not start, a node that dies, no verdict in time. When it is over, the graph is
shut down and everything left of it killed, whatever happened.
"""
import atexit
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from xml.sax.saxutils import quoteattr

import yaml

from closed_loop import launcher
from closed_loop.batch import graph_keeper, kept_graph, workspace
from closed_loop.batch.spec import EpisodeError, generated_world, judge_settings, result_from_verdict
from closed_loop.batch.judge import Verdict, track_from_dict
from closed_loop.sim.profiles import PACKAGE_ROOT

#: Wall time (s) a graph gets to start, and its slack beyond the scenario's simulated time (in lockstep, the
#: scenario's simulated time counts as wall time: a lockstepped graph slower than real time is waited for).
STARTUP_S, SLACK_S = 40.0, 20.0
#: After the verdict or an error, how long the keeper gets to shut the graph down (s).
SHUTDOWN_S = graph_keeper.GRACE_S + 10.0
#: Where the keeper finds this package, as this process did.
KEEPER_PATH = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(graph_keeper.__file__))))
#: How often (wall s) the runner looks for the verdict, and for what went wrong.
POLL_S = 0.05
#: How many lines of a log an error quotes.
TAIL_LINES = 8
DIED = re.compile(r'\[([^\]\s]+?)-\d+\] process has died \[pid \d+, exit code (-?\d+)')
#: roslaunch's colours and terminal titles, which a quoted log line leaves out.
ESCAPES = re.compile(r'\x1b\[[0-9;]*[A-Za-z]|\x1b\][^\x07]*\x07')
CANNOT_LAUNCH = re.compile(r'ERROR: cannot launch node of type \[([^\]]+)\]: ([^\n]*)')
#: One graph at a time in a process (a Dask worker runs one episode at a time; this holds it to that).
_ONE_GRAPH = threading.Lock()


def _launch_path(launch):
    if os.path.isabs(launch):
        return launch
    package, _, rest = launch.partition('/')
    return '$(find %s)/%s' % (package, rest)


def _value(value):
    return str(value).lower() if isinstance(value, bool) else str(value)


def _world(spec, prepared, folder):
    """The episode's world as the simulator's ``~world`` takes it (a generated one written to a file of its own)."""
    world = spec.world
    if isinstance(world, dict):
        world = os.path.join(folder, 'world.yaml')
        with open(world, 'w') as f:
            yaml.safe_dump(generated_world(spec.world, prepared.profile), f, sort_keys=False)
    elif os.path.isfile(world):
        world = os.path.abspath(world)
    return world


def sim_parameters(spec, prepared, world):
    """The simulator's parameters (under ``/sim``) of the episode: its world, the command's latency and the
    settings the spec gives it."""
    sim = dict(prepared.sim_params, world=world)
    sim.pop('camera')
    if spec.command_delay_s is not None:
        sim['command_delay'] = spec.command_delay_s
    if spec.real_time_factor is not None:    # in real time, every step's clock goes out, faster than real time too
        sim['max_clock_rate_hz'] = prepared.sim_params.get('physics_rate_hz', 100.0) * max(spec.real_time_factor, 1.0)
    return sim


def launch_text(spec, prepared, folder, bag=None, kept=False):
    """The launch file of the episode's graph: scenario.launch with the episode's world, robot, goal and judge
    (and its recorder, writing ``bag``, if given), the simulator's parameters, and the controller; ``kept``:
    the graph but the simulator (scenario_nodes.launch), for a kept graph, which sets the simulator's parameters
    itself (:func:`sim_parameters`)."""
    p, c = prepared, prepared.graph
    world = _world(spec, prepared, folder)
    judge = judge_settings(spec, p.controller_class)
    rtf = spec.real_time_factor
    args = {'world': world, 'robot': p.profile.name, 'camera': p.sim_params['camera'], 'lockstep': rtf is None,
            'command_delay': spec.command_delay_s,
            'time_limit': judge.time_limit, 'end_on_contact': judge.end_on_contact,
            'end_at_rest': c.get('end_at_rest', judge.end_at_rest), 'success_radius': judge.success_radius,
            'verdict_file': os.path.join(folder, 'verdict.json'), 'keep_track': spec.keep_trajectory}
    if rtf is not None:
        args['real_time_factor'] = rtf
    if p.goal_world is not None:
        args['goal_x'], args['goal_y'] = p.goal_world
    if bag is not None:
        args['bag'] = os.path.abspath(bag)
    node = c.get('node')
    if c.get('mode_topic') or node:
        args['mode_topic'] = c.get('mode_topic') or '/%s/mode' % node
    for name, value in args.items():
        if '$(' in str(value):          # roslaunch would substitute (or eval) it
            raise EpisodeError('%s: %r has "$(" in it, which roslaunch would take for a substitution' % (name, value))
    # The args at the top, as scenario.launch's own: it and a controller's launch file both get them all
    # (a launch file of yours may declare goal_x, goal_y, robot, world; it gets those it declares).
    lines = ['<launch>'] + ['  <arg name=%s value=%s/>' % (quoteattr(k), quoteattr(_value(v)))
                            for k, v in sorted(args.items())]
    lines.append('  <include file="$(find closed_loop)/launch/%s.launch" pass_all_args="true"/>'
                 % ('scenario_nodes' if kept else 'scenario'))
    if not kept:
        sim = sim_parameters(spec, p, world)
        sim.pop('world'), sim.pop('command_delay', None)           # (scenario.launch's args)
        lines += ['  <param name=%s value=%s/>' % (quoteattr('/sim/' + k), quoteattr(_value(v)))
                  for k, v in sorted(sim.items())]
    if node:
        lines.append('  <node pkg="closed_loop" type=%s name=%s output="screen">' % (quoteattr(node), quoteattr(node)))
        lines += ['    <param name=%s value=%s/>' % (quoteattr(k), quoteattr(_value(v)))
                  for s in [p.settings] + list(p.extra_settings) for k, v in sorted(vars(s).items())]
        if p.goal_odom is not None and p.controller_class.uses_goal:
            lines += ['    <param name="goal_x" value="%r"/>' % p.goal_odom[0], '    <param name="goal_y" value="%r"/>' % p.goal_odom[1]]
        lines.append('  </node>')
        if p.controller_class.uses_camera:
            lines.append('  <node pkg="closed_loop" type="vision_node" name="vision_node"/>')
    else:
        lines.append('  <include file=%s pass_all_args="true">' % quoteattr(_launch_path(c['launch'])))
        lines += ['    <arg name=%s value=%s/>' % (quoteattr(k), quoteattr(_value(v)))
                  for k, v in sorted((c.get('args') or {}).items())]
        lines.append('  </include>')
    return '\n'.join(lines + ['</launch>', ''])


def _tail(path, lines=TAIL_LINES):
    try:
        with open(path, errors='replace') as f:
            text = ESCAPES.sub('', f.read())
        kept = [line.rstrip()[:200] for line in text.splitlines() if line.strip()]
        return ' | '.join(kept[-lines:])
    except OSError:
        return '(no log)'


def _failed(folder):
    """What the graph's output says went wrong with a node: (node name, exit code) of the first that died,
    or (node type, why) of one roslaunch could not start; None when neither."""
    try:
        with open(os.path.join(folder, 'graph.log'), errors='replace') as f:
            text = ESCAPES.sub('', f.read())
    except OSError:
        return None
    died, cannot = DIED.search(text), CANNOT_LAUNCH.search(text)
    if cannot:
        return cannot.group(1), cannot.group(2).strip()
    return (died.group(1), int(died.group(2))) if died else None


def _node_log(folder, name):
    """The node's own log files' tail (roslaunch keeps them under the episode's ROS_LOG_DIR)."""
    logs = sorted(os.path.join(d, f) for d, _, files in os.walk(os.path.join(folder, 'log'))
                  for f in files if f.startswith(name + '-') and f.endswith('.log'))
    return ' || '.join('%s: %s' % (os.path.basename(path), _tail(path)) for path in logs) or _tail(
        os.path.join(folder, 'graph.log'))


def run_graph(spec, prepared, folder=None, bag=None):
    """Run the graph episode ``spec`` (resolved as ``prepared``) with its files in a new ``folder`` (None: a
    temporary one), recorded into ``bag`` if given (scenario.launch's recorder: every topic from t = 0). An
    earlier attempt's folder of that name (a worker that died, a resumed sweep) is kept beside it as
    ``FOLDER.attempt-K``. In lockstep (and unless the controller asks for ``fresh_graph``), the master and the
    simulator are this process's kept graph's (:mod:`closed_loop.batch.kept_graph`); else a graph of its own."""
    started = time.monotonic()
    with _ONE_GRAPH:
        if folder is None:
            folder = tempfile.mkdtemp(prefix='episode-')
        else:
            set_aside(folder)
            os.makedirs(folder)
        kept = spec.real_time_factor is None and bag is None and not prepared.graph.get('fresh_graph')
        launch_file = os.path.join(folder, 'episode.launch')
        with open(launch_file, 'w') as f:
            f.write(launch_text(spec, prepared, folder, bag, kept=kept))
        mark = graph_mark(folder)
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, (KEEPER_PATH, os.environ.get('PYTHONPATH')))))
        if prepared.graph.get('workspace'):
            env = workspace.environment(prepared.graph['workspace'], env, PACKAGE_ROOT, KEEPER_PATH)
        own = {'ROS_HOME': os.path.join(folder, 'ros_home'), 'ROS_LOG_DIR': os.path.join(folder, 'log'),
               launcher.MARK: mark}
        if kept:
            verdict, track, error = _run_kept(spec, prepared, folder, launch_file, env, own)
        else:
            try:
                verdict, track, error = _run_own(spec, folder, launch_file, dict(env, **own))
            finally:
                launcher.kill_marked(mark)          # whatever the keeper could not
    wall_s = time.monotonic() - started
    if verdict is None:
        c = prepared.graph
        error = '%s: %s' % (c['launch'] if 'launch' in c else 'node ' + c['node'], error)
        return result_from_verdict(Verdict('error', why=error), error=error, logs=folder, wall_s=wall_s)
    return result_from_verdict(verdict, logs=folder, wall_s=wall_s, trajectory=track[0], contact_log=track[1])


def _run_own(spec, folder, launch_file, env):
    """The episode in a graph of its own (``closed_loop.batch.graph_keeper``)."""
    with open(os.path.join(folder, 'keeper.log'), 'wb') as out:
        keeper = subprocess.Popen([sys.executable, '-m', graph_keeper.__name__, folder, launch_file],
                                  stdin=subprocess.PIPE,
                                  stdout=out, stderr=subprocess.STDOUT, env=env, start_new_session=True)
    try:
        return _wait(spec, folder, keeper)
    finally:
        keeper.stdin.close()                 # the keeper shuts the graph down
        try:
            keeper.wait(SHUTDOWN_S)
        except subprocess.TimeoutExpired:
            os.killpg(keeper.pid, 9)
            keeper.wait()


#: This process's kept graph (one at a time: a Dask worker runs one episode at a time).
_KEPT = []


def _kept_graph(spec, prepared, env, sim_params, mark_under):
    """This process's kept graph for ``prepared``'s robot and camera and ``env`` (a new one where they differ, or
    where the last episode did not leave it clean)."""
    key = (prepared.profile.name, prepared.sim_params['camera'], sorted(env.items()))
    if _KEPT and (_KEPT[0].key != key or not _KEPT[0].settle()):
        _KEPT.pop().close()
    if not _KEPT:
        lines = ['<launch>', '  <include file="$(find closed_loop)/launch/sim.launch">']
        lines += ['    <arg name=%s value=%s/>' % (quoteattr(k), quoteattr(_value(v))) for k, v in (
            ('world', sim_params['world']), ('robot', prepared.profile.name),
            ('camera', prepared.sim_params['camera']), ('paused', True), ('lockstep', True))]
        lines.append('  </include>')
        lines += ['  <param name=%s value=%s/>' % (quoteattr('/sim/' + k), quoteattr(_value(v)))
                  for k, v in sorted(sim_params.items()) if k != 'world']
        _KEPT.append(kept_graph.KeptGraph(key, '\n'.join(lines + ['</launch>', '']), env, mark_under))
    return _KEPT[0]


def settle_kept_graph():
    """Wait until this process's kept graph (if it has one) has brought its last episode down; True if it is ready
    for the next (a bench times an episode's start-up apart from the last one's teardown)."""
    return bool(_KEPT) and _KEPT[0].settle()


def close_kept_graph():
    """End this process's kept graph, if it has one (after the episode it runs, if one does): at the end of a
    sweep, on each of its workers, and when the process exits."""
    with _ONE_GRAPH:
        while _KEPT:
            _KEPT.pop().close()


atexit.register(close_kept_graph)


def _run_kept(spec, prepared, folder, launch_file, env, own):
    """The episode in this process's kept graph."""
    sim_params = sim_parameters(spec, prepared, _world(spec, prepared, folder))
    try:
        kept = _kept_graph(spec, prepared, env, sim_params, os.path.dirname(os.path.abspath(folder)))
    except kept_graph.KeptGraphError as error:
        return None, None, str(error)
    if not kept.start(folder, launch_file, sim_params, own):
        if kept.poll() is not None:
            _KEPT.clear()
            launcher.kill_marked(own[launcher.MARK])
        return None, None, 'the graph did not start: %s' % _tail(os.path.join(folder, 'keeper_error'))
    try:
        return _wait(spec, folder, kept)
    finally:
        kept.end()
        kept.settle()           # (the episode's folder whole before its row: its nodes write to it as they go)
        if kept.poll() is not None:
            _KEPT.clear()
            launcher.kill_marked(own[launcher.MARK])


def graph_mark(folder):
    """The mark (``launcher.MARK``) of one run of a graph in ``folder``: under the folder's path, and the run's own.
    A worker that dies leaves its keeper to end its graph, and that keeper kills what carries its mark after a
    grace of seconds; the episode, run again meanwhile in the same folder by another worker, carries another."""
    return os.path.join(os.path.abspath(folder), 'run-%d-%s' % (os.getpid(), uuid.uuid4().hex))


def set_aside(folder):
    if os.path.lexists(folder):
        attempt = 1
        while os.path.lexists('%s.attempt-%d' % (folder, attempt)):
            attempt += 1
        os.rename(folder, '%s.attempt-%d' % (folder, attempt))


def _wait(spec, folder, keeper):
    """(the verdict, (its trajectory, contact log) or Nones, None) or (None, None, why there is none)."""
    budget_s = STARTUP_S + spec.time_limit_s / (spec.real_time_factor or 1.0) + SLACK_S
    deadline = time.monotonic() + budget_s
    verdict_file = os.path.join(folder, 'verdict.json')
    while time.monotonic() < deadline:
        if os.path.exists(verdict_file):
            with open(verdict_file) as f:
                data = json.load(f)
            track = track_from_dict(data)
            data.pop('trajectory', None), data.pop('contact_log', None)
            return Verdict.from_dict(data), track, None
        failed = _failed(folder)
        if failed is not None and isinstance(failed[1], int):
            return None, None, 'node %s died (exit code %d): %s' % (failed[0], failed[1], _node_log(folder, failed[0]))
        if failed is not None:
            return None, None, 'roslaunch could not start node %s: %s' % failed
        if keeper.poll() is not None or os.path.exists(os.path.join(folder, 'keeper_error')):
            if os.path.exists(os.path.join(folder, 'keeper_error')):
                return None, None, 'the graph did not start: %s' % _tail(os.path.join(folder, 'keeper_error'))
            return None, None, 'the launch ended before a verdict: %s' % _tail(os.path.join(folder, 'graph.log'))
        time.sleep(POLL_S)
    return None, None, 'no verdict within %.0f s of wall time: %s' % (budget_s, _tail(os.path.join(folder, 'graph.log')))


def close_kept_graphs(client, interrupted=False):
    """At the end of a sweep, each worker's kept graph ends (``closed_loop.batch.graph_episode``): a cluster of
    yours keeps nothing of the sweep up. Interrupted, a local cluster's workers go with their graphs; another's
    graphs end by themselves once idle (``closed_loop.batch.kept_graph.IDLE_S``)."""
    if not interrupted:
        try:
            client.run(close_kept_graph)
        except Exception as error:      # a worker gone meanwhile: its graph went with it
            print('a worker\'s kept graph could not be closed: %s' % error, file=sys.stderr)


def wait_graphs_down(logs_root, timeout_s=graph_keeper.GRACE_S + 5.0):
    """After a local cluster has closed (done, or Ctrl-C): the keepers of graph episodes it was running shut
    their graphs down once their workers are gone; wait for that, then kill whatever is left of them."""
    prefix = logs_root + os.sep
    deadline = time.monotonic() + timeout_s
    while launcher.marked_processes(prefix) and time.monotonic() < deadline:
        time.sleep(0.2)
    launcher.kill_marked(prefix)
