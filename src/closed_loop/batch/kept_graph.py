"""A kept graph: a master, the simulator and robot_state_publisher kept up across a worker's graph episodes,
every node of the episode's own (the judge, the controller, what its launch file starts) new each time. This is
the runner's side (free of ROS); the keeper, a process of its own, is ``closed_loop.nodes.kept_graph_keeper``.

The keeper starts the master and the simulator's launch (``sim.launch``, paused, in lockstep), notes the
parameters and the nodes the graph then has, and then, for each episode: sets the simulator's parameters, has it
load the episode (``/sim/load_episode``: the world and every setting read again, a new simulation paused at
t = 0), and starts the episode's launch (``scenario_nodes.launch``: the judge unpauses the simulator once the
controller is connected). After the verdict, the episode is brought down: the simulator paused, every node of
the episode given SIGINT, then SIGTERM, then SIGKILL, what they registered with the master and left behind
unregistered, every parameter set back to what the graph had before its first episode (the ones added
deleted). Where something of an episode could not be removed, the graph is ended and the next episode gets a
new one. A launch that sets a parameter the kept nodes read only at their start (``/robot_description``) is
refused: such a controller asks for ``fresh_graph: true``.
"""
import json
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import uuid

from closed_loop.batch import graph_keeper
from closed_loop.launcher import MARK

#: A keeper with no episode for this long (wall s) ends its graph (a worker of a cluster kept up between sweeps).
IDLE_S = 120.0
#: Wall time (s) the kept graph gets to be ready, a service call to be answered, an episode's launch to end.
READY_S, CALL_S, END_S = 40.0, 10.0, graph_keeper.GRACE_S
#: The services of the simulator the keeper calls.
LOAD, PAUSE = '/sim/load_episode', '/sim/pause_physics'
#: The environment variable that names the root of the processes that take part in the lockstep, where it is
#: not the simulator's parent: the keeper, which starts each episode's launch beside the simulator's.
ROOT_VARIABLE = 'CLOSED_LOOP_LOCKSTEP_ROOT'
#: The keeper's module.
KEEPER = 'closed_loop.nodes.kept_graph_keeper'
#: How often (wall s) the keeper looks at an episode's launch while it waits for the runner.
POLL_S = 0.2


class KeptGraphError(Exception):
    """A kept graph that could not be started, or has gone."""


class KeptGraph:
    """The runner's side: a keeper (:data:`KEEPER`, a process) and its graph, for the episodes of one worker whose
    graphs differ only in what the keeper sets for each (``key``: the rest, such as the robot)."""

    def __init__(self, key, base_text, env, mark_under):
        """The graph's files go in a temporary folder, removed when it is closed (each episode's folder gets the
        simulator's output of its episode: ``simulator.log``); its processes carry a mark under ``mark_under``
        (the first episode's folder's parent: a sweep waits for what carries a mark under its own at its end)."""
        self.key = key
        self.closed = False
        self.folder = tempfile.mkdtemp(prefix='closed_loop-kept-graph-')
        self.ending = False                 # an episode's end asked for, its answer not read yet
        base = os.path.join(self.folder, 'base.launch')
        with open(base, 'w') as f:
            f.write(base_text)
        env = dict(env, **{MARK: os.path.join(mark_under, 'kept-graph-%d-%s' % (os.getpid(), uuid.uuid4().hex))})
        with open(os.path.join(self.folder, 'keeper.log'), 'wb') as log:
            self.process = subprocess.Popen([sys.executable, '-m', KEEPER, self.folder, base], stdin=subprocess.PIPE,
                                            stdout=subprocess.PIPE, stderr=log, env=env, start_new_session=True)
        if self._answer(READY_S + CALL_S) != 'ready':
            why = self.why()
            self.close()
            raise KeptGraphError('the kept graph did not start: %s' % why)

    def why(self):
        """What the keeper said went wrong, or the tail of its graph's output."""
        for name in ('keeper_error', 'graph.log', 'keeper.log'):
            try:
                with open(os.path.join(self.folder, name), errors='replace') as f:
                    text = f.read().strip()
            except OSError:
                continue
            if text:
                return ' | '.join(text.splitlines()[-6:])[-1200:]
        return '(no output)'

    def _answer(self, timeout_s):
        """The keeper's next line, or None if none comes within ``timeout_s`` (wall s) or it has gone."""
        ready, _, _ = select.select([self.process.stdout], [], [], timeout_s)
        if not ready:
            return None
        return self.process.stdout.readline().decode(errors='replace').strip() or None

    def ask(self, line, timeout_s):
        try:
            self.process.stdin.write(line.encode() + b'\n')
            self.process.stdin.flush()
        except OSError:
            return None
        return self._answer(timeout_s)

    def start(self, folder, launch_file, sim_params, env):
        """Start an episode (its files in ``folder``): True, or False with why in ``folder``/keeper_error (if the
        graph cannot be used again, it is closed: :meth:`poll` says so)."""
        with open(os.path.join(folder, 'episode.json'), 'w') as f:
            json.dump({'launch': launch_file, 'sim_params': sim_params, 'env': env}, f)
        answer = self.ask('episode ' + os.path.abspath(folder), READY_S) if self.settle() else None
        if answer is None:
            with open(os.path.join(folder, 'keeper_error'), 'w') as f:
                f.write('the kept graph has gone: %s\n' % self.why())
        if answer != 'started' and answer != 'failed':       # gone, or left unclean: not used again
            self.close()
        return answer == 'started'

    def end(self):
        """Have the episode brought down, the graph back to what it was before it (:meth:`settle` waits for it)."""
        try:
            self.process.stdin.write(b'end\n')
            self.process.stdin.flush()
            self.ending = True
        except OSError:
            self.close()

    def settle(self):
        """True once the last episode's end is done and left the graph clean; else the graph is closed."""
        if self.ending:
            self.ending = False
            if self._answer(END_S + 2 * CALL_S) != 'clean':
                self.close()
        return self.process.returncode is None and self.process.poll() is None

    def poll(self):
        return self.process.poll()

    def close(self):
        """End the graph (the keeper shuts it down as its input closes), and remove its folder."""
        if self.closed:
            return
        self.closed = True
        try:
            self.process.stdin.close()
        except OSError:
            pass
        try:
            self.process.wait(graph_keeper.GRACE_S + 10.0)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()
        self.process.stdout.close()
        shutil.rmtree(self.folder, ignore_errors=True)
