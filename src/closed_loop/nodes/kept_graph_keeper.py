"""The keeper of a kept graph (``closed_loop.batch.kept_graph``, which starts it): a master, the simulator and
robot_state_publisher kept up across a worker's graph episodes.

    python3 -m closed_loop.nodes.kept_graph_keeper FOLDER BASE_LAUNCH

It starts the master and ``BASE_LAUNCH`` (``sim.launch``, paused, in lockstep) as ``closed_loop.batch.graph_keeper``
does one episode's graph, notes the parameters and the nodes it then has, prints ``ready``, and then takes one
line at a time on its standard input:

- ``episode FOLDER``: FOLDER/episode.json names the episode's launch file, the simulator's parameters and the
  environment of its nodes. The keeper sets those parameters under ``/sim`` (and those the launch sets there),
  has the simulator load the episode (``/sim/load_episode``), starts the episode's launch (roslaunch, in this
  process: its nodes' output in FOLDER/graph.log) and answers ``started``, or ``failed`` with why in
  FOLDER/keeper_error.
- ``end``: the simulator paused, every process that carries the episode's mark given SIGINT, SIGTERM, SIGKILL;
  what the episode's nodes registered with the master and left behind unregistered; every parameter set back to
  what the graph had before its first episode (the ones added deleted); the simulator's output of the episode
  in FOLDER/simulator.log. Answers ``clean``, or ``dirty WHY`` when something of the episode could not be removed
  (the runner then ends this graph and starts another).

The lockstep's root (``CLOSED_LOOP_LOCKSTEP_ROOT``) is the keeper, so each episode's nodes, its children, take
part. The graph goes down, whatever is left of it killed, when the keeper's standard input closes (the worker is
done or died), on SIGTERM or SIGINT, after :data:`IDLE_S` without an episode, or when the simulator's launch
ends.
"""
import json
import os
import select
import signal
import subprocess
import sys
import threading
import time

from closed_loop import netenv
from closed_loop.batch import graph_keeper
from closed_loop.batch.kept_graph import CALL_S, END_S, IDLE_S, LOAD, PAUSE, POLL_S, READY_S, ROOT_VARIABLE
from closed_loop.launcher import MARK, kill_marked, marked_processes


class Keeper:
    """The keeper's side: the graph, and what an episode changes in it."""

    def __init__(self, folder, base_launch, env):
        self.folder, self.env = folder, env
        port, self.master = graph_keeper.start_master(folder, env)
        self.uri = env['ROS_MASTER_URI'] = 'http://127.0.0.1:%d' % port
        with open(os.path.join(folder, 'port'), 'w') as f:
            f.write('%d\n' % port)
        os.environ['ROS_MASTER_URI'] = self.uri             # (rospy's service proxies)
        with open(os.path.join(folder, 'graph.log'), 'ab') as log:
            self.base = subprocess.Popen(['roslaunch', '--skip-log-check', '-p', str(port), base_launch],
                                         stdout=log, stderr=subprocess.STDOUT, env=env)
        self.api = netenv.bounded_proxy(self.uri, CALL_S)
        self.episode = None             # [the episode's roslaunch, its mark, its end said, its folder]
        self.simulator_from = 0         # where the episode's part of the simulator's output begins
        self._wait_for_service(LOAD)
        self.params = self._call('getParam', '/')
        self.nodes = self._nodes()

    def _call(self, method, *args):
        code, message, value = getattr(self.api, method)('/kept_graph', *args)
        if code != 1:
            raise RuntimeError('master: %s: %s' % (method, message))
        return value

    def _wait_for_service(self, name):
        deadline = time.monotonic() + READY_S
        while time.monotonic() < deadline:
            if self.base.poll() is not None:
                raise RuntimeError('the simulator\'s launch ended (exit code %s): see %s'
                                   % (self.base.returncode, os.path.join(self.folder, 'graph.log')))
            code, _, _ = self.api.lookupService('/kept_graph', name)
            if code == 1:
                return
            time.sleep(0.05)
        raise RuntimeError('no %s within %g s' % (name, READY_S))

    def _nodes(self):
        """{node name: [(kind, name)]} of every node registered with the master."""
        found = {}
        for kind, entries in zip(('pub', 'sub', 'srv'), self._call('getSystemState')):
            for name, nodes in entries:
                for node in nodes:
                    found.setdefault(node, []).append((kind, name))
        return found

    @staticmethod
    def service(name, kind):
        """Call the simulator's service ``name`` (of type ``kind``, no arguments)."""
        import rospy                    # (only the keeper needs it, for a service call)
        rospy.wait_for_service(name, CALL_S)
        return rospy.ServiceProxy(name, kind)()

    def start(self, folder):
        with open(os.path.join(folder, 'episode.json')) as f:
            episode = json.load(f)
        import roslaunch.parent                 # (imported once, kept: the lever of a kept graph's start-up)
        import roslaunch.rlutil
        from std_srvs.srv import Trigger
        os.environ.update(episode['env'])      # (what the launch's nodes inherit: their logs' folder, the mark)
        launch = roslaunch.parent.ROSLaunchParent(roslaunch.rlutil.get_or_generate_uuid(None, False),
                                                  [episode['launch']], show_summary=False,
                                                  sigint_timeout=graph_keeper.NODE_SIGINT_S,
                                                  sigterm_timeout=graph_keeper.NODE_SIGTERM_S)
        launch.config = episode_config(episode['launch'])    # (start() reads it only where it has none)
        for name, value in sorted(episode['sim_params'].items()):
            self._call('setParam', '/sim/' + name, value)
        self._launch_settings(launch.config)
        answer = self.service(LOAD, Trigger)
        if not answer.success:
            raise EpisodeRefused('the simulator could not load the episode: %s' % answer.message)
        output_to(os.path.join(folder, 'graph.log'))
        self.episode = [launch, episode['env'][MARK], False, folder]
        self.simulator_from = self._simulator_size()
        launch.start(auto_terminate=False)

    def _launch_settings(self, config):
        """What the episode's launch sets for the simulator (``/sim/...``), set before it loads the episode, as in
        a graph of its own, where the launch's parameters are set before any node starts. A parameter the kept
        nodes read only at their start (``/robot_description``) the launch may not change."""
        for name, param in sorted(config.params.items()):
            if name.startswith('/sim/'):
                self._call('setParam', name, param.value)
                continue
            kept = _lookup(self.params, name)
            if kept is not _MISSING and kept != param.value and name not in ('/rosversion', '/rosdistro'):
                raise EpisodeRefused('the launch sets %s, which the kept graph\'s nodes took at their start: give the '
                                     'controller fresh_graph: true (a graph of its own)' % name)

    def check(self):
        """An episode's launch that ended before the episode did (a required node that died) is said in the
        episode's folder (``keeper_error``), once."""
        if self.episode is not None and not self.episode[2] and self.episode[0].pm.is_shutdown:
            self.episode[2] = True
            with open(os.path.join(self.episode[3], 'keeper_error'), 'w') as f:
                f.write('the episode\'s launch ended before a verdict\n')

    def end(self):
        """Bring the episode down and the graph back to what it was; None, or why it could not be. Every node
        of the episode gets SIGINT at once (roslaunch's shut-down gives it one node at a time), SIGTERM after
        :data:`graph_keeper.NODE_SIGINT_S` if still up, SIGKILL :data:`graph_keeper.NODE_SIGTERM_S` later."""
        from std_srvs.srv import Empty
        self.service(PAUSE, Empty)
        launch, mark, _, folder = self.episode
        self.episode = None
        names = {}
        for sig, grace_s in ((signal.SIGINT, graph_keeper.NODE_SIGINT_S), (signal.SIGTERM, graph_keeper.NODE_SIGTERM_S),
                             (signal.SIGKILL, 0.0)):
            nodes = [pid for pid in marked_processes(mark) if _alive(pid)]
            names.update((pid, _command(pid)) for pid in nodes if pid not in names)
            if nodes and sig != signal.SIGINT:     # (said as roslaunch says it, in the episode's graph.log)
                print('[kept graph] %s still up after %s: escalating to %s' % (
                    ', '.join('%s (pid %d)' % (names[pid], pid) for pid in nodes),
                    'SIGINT' if sig == signal.SIGTERM else 'SIGTERM', signal.Signals(sig).name), flush=True)
            if sig == signal.SIGKILL:
                break
            for pid in nodes:
                _signal(pid, sig)
            deadline = time.monotonic() + grace_s
            while time.monotonic() < deadline and any(_alive(pid) for pid in nodes):
                time.sleep(0.01)
        left = kill_marked(mark)
        launch.shutdown()
        output_to(os.path.join(self.folder, 'keeper.log'))
        self._simulator_output(os.path.join(folder, 'simulator.log'))
        if left:
            return 'processes %s of the episode could not be killed' % left
        for node, entries in self._nodes().items():
            if node not in self.nodes:
                self._unregister(node, entries)
        left = sorted(set(self._nodes()) - set(self.nodes))
        if left:
            return 'nodes %s are still registered with the master' % left
        self._restore_params()
        return None

    def _simulator_size(self):
        try:
            return os.path.getsize(os.path.join(self.folder, 'graph.log'))
        except OSError:
            return 0

    def _simulator_output(self, path):
        """What the simulator's launch printed during the episode, into ``path`` (the episode's folder)."""
        try:
            with open(os.path.join(self.folder, 'graph.log'), 'rb') as f, open(path, 'wb') as out:
                f.seek(self.simulator_from)
                out.write(f.read())
        except OSError:
            pass

    def _unregister(self, node, entries):
        """What ``node`` (gone) registered, as ``rosnode cleanup`` removes it."""
        code, _, node_api = self.api.lookupNode('/kept_graph', node)
        for kind, name in entries:
            if kind == 'srv':
                code, _, service_api = self.api.lookupService('/kept_graph', name)
                if code == 1:
                    self.api.unregisterService(node, name, service_api)
            elif code == 1:
                getattr(self.api, 'unregisterPublisher' if kind == 'pub' else 'unregisterSubscriber')(
                    node, name, node_api)

    def _restore_params(self):
        now = self._call('getParam', '/')
        for key in set(now) - set(self.params):
            self._call('deleteParam', '/' + key)
        for key, value in self.params.items():
            if now.get(key) != value:
                self._call('setParam', '/' + key, value)

    def close(self):
        if self.episode is not None:
            try:
                self.end()
            except Exception:           # going down anyway
                pass
        if self.base.poll() is None:
            self.base.send_signal(signal.SIGINT)
            try:
                self.base.wait(graph_keeper.GRACE_S)
            except subprocess.TimeoutExpired:
                pass


def episode_config(launch_file):
    """roslaunch's configuration of ``launch_file``, as ``roslaunch.config.load_config_default`` makes it, but for
    the parameters of roscore.xml (``/rosversion`` and ``/rosdistro``, which the graph has from its start): each
    is a command run (``rosversion``), 0.3 s of the episode's start-up."""
    import roslaunch.config
    import roslaunch.core
    import roslaunch.loader
    import roslaunch.xmlloader
    config = roslaunch.config.ROSLaunchConfig()
    try:
        roslaunch.xmlloader.XmlLoader().load(launch_file, config, verbose=False)
    except (roslaunch.xmlloader.XmlParseException, roslaunch.loader.LoadException) as error:
        raise roslaunch.core.RLException(error)
    config.assign_machines()
    return config


_MISSING = object()


def _lookup(tree, name):
    """The value at parameter ``name`` in ``tree`` (the master's parameters as one mapping), or :data:`_MISSING`."""
    for part in name.strip('/').split('/'):
        if not isinstance(tree, dict) or part not in tree:
            return _MISSING
        tree = tree[part]
    return tree


def output_to(path):
    """This process's standard output and error (and so a launch's nodes' ``output="screen"``) into ``path``."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    sys.stderr.flush()
    os.dup2(fd, 1)
    os.dup2(fd, 2)
    os.close(fd)


def _signal(pid, sig):
    try:
        os.kill(pid, sig)
    except OSError:
        pass


def _command(pid):
    """A process's program, as a log line names it."""
    try:
        with open('/proc/%d/cmdline' % pid, 'rb') as f:
            argv = [a for a in f.read().split(b'\0') if a]
        return ' '.join(os.path.basename(a.decode(errors='replace')) for a in argv[:2])[:80]
    except OSError:
        return '?'


def _alive(pid):
    """True while ``pid`` runs (not a zombie: a node roslaunch has not reaped yet counts as gone)."""
    try:
        with open('/proc/%d/stat' % pid, 'rb') as f:
            return f.read().rsplit(b')', 1)[1].split()[0] != b'Z'
    except (OSError, IndexError):
        return False


class EpisodeRefused(Exception):
    """An episode the kept graph could not start (its world, its parameters): the graph itself is fine."""


def serve(keeper, lines, out):
    """Answer the runner's lines (see the module's doc) until the input ends, the simulator's launch does, or
    :data:`IDLE_S` passes without one."""
    idle_end = time.monotonic() + IDLE_S
    while keeper.base.poll() is None:
        line = lines(POLL_S)
        if line is None and (lines.ended() or time.monotonic() > idle_end):
            return
        if line is None:
            keeper.check()
            continue
        idle_end = time.monotonic() + IDLE_S
        command, _, argument = line.strip().partition(' ')
        if not command:
            continue
        if command == 'episode':
            try:
                keeper.start(argument)
                answer = 'started'
            except Exception as error:       # (roslaunch's own for a launch file it cannot read, among others)
                with open(os.path.join(argument, 'keeper_error'), 'w') as f:
                    f.write('%s\n' % (error if isinstance(error, EpisodeRefused) else '%s: %s' % (
                        'roslaunch' if type(error).__name__ == 'RLException' else type(error).__name__, error)))
                why = keeper.end() if keeper.episode is not None else None
                answer = 'failed' if why is None else 'dirty ' + why
        elif command == 'end':
            folder = keeper.episode[3] if keeper.episode else None
            why = keeper.end() if keeper.episode else None
            answer = 'clean' if why is None else 'dirty ' + why
            if why is not None:
                with open(os.path.join(folder, 'graph.log'), 'a') as f:
                    f.write('[kept graph] ended after this episode: %s\n' % why)
        else:
            answer = 'failed unknown command %r' % command[:40]
        out.write(answer + '\n')
        out.flush()


def main(argv=None):
    folder, base_launch = (sys.argv[1:] if argv is None else argv)[:2]
    stop = threading.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: stop.set())
    env = dict(os.environ)
    env.setdefault(MARK, os.path.abspath(folder) + os.sep)
    env.pop('ROS_HOSTNAME', None)
    env['ROS_IP'] = '127.0.0.1'
    env[ROOT_VARIABLE] = str(os.getpid())
    out = os.fdopen(os.dup(1), 'w')    # the answers, the only lines on the runner's pipe
    output_to(os.path.join(folder, 'keeper.log'))
    stdin = sys.stdin.buffer

    ended = threading.Event()

    def lines(timeout_s):
        """The next line from the runner; None after ``timeout_s``, or once the input ends or a signal comes
        (then ``lines.ended()``)."""
        ready, _, _ = select.select([stdin], [], [], timeout_s)
        if stop.is_set():
            ended.set()
        elif ready:
            line = stdin.readline()
            if line:
                return line.decode(errors='replace')
            ended.set()
        return None
    lines.ended = ended.is_set
    keeper = None
    try:
        keeper = Keeper(folder, base_launch, env)
        out.write('ready\n')
        out.flush()
        serve(keeper, lines, out)
    except (OSError, RuntimeError) as error:
        with open(os.path.join(folder, 'keeper_error'), 'w') as f:
            f.write('%s\n' % error)
    finally:
        if keeper is not None:
            keeper.close()
        kill_marked(env[MARK])
        os.killpg(os.getpgid(0), signal.SIGKILL)


if __name__ == '__main__':
    main()

