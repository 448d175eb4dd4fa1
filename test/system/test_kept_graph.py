"""A worker's kept graph (closed_loop.batch.kept_graph): the master and the simulator kept up across graph
episodes, every node of each episode new. What an episode does to the graph does not outlive it: a parameter its
launch sets (global, private, or one of the simulator's), a node that stays up after SIGINT, a node that died;
and an episode gives the same result in a kept graph, after others, as in a graph of its own."""
import os
import xmlrpc.client

from closed_loop.batch import graph_episode
from closed_loop.batch.episode import EpisodeSpec, run_episode
from conftest import graph_leftovers

STOP = {'world': 'wall', 'controller': {'node': 'stop_on_obstacle'}, 'settings': {'cruise_speed': 1.0},
        'time_limit_s': 30}
#: A controller's launch that leaves what it can behind: parameters, global and private and the simulator's, and
#: a node that ignores SIGINT (``trap '' INT`` in a shell that stays up), beside the stop_on_obstacle node.
MESSY = '''<launch>
  <param name="/left_over" value="1"/>
  <param name="/sim/max_linear_speed" value="0.2"/>
  <rosparam param="/left_over_tree">{a: 1, b: [1, 2]}</rosparam>
  <node pkg="closed_loop" type="stop_on_obstacle" name="stop_on_obstacle" output="screen">
    <param name="cruise_speed" value="0.5"/>
    <param name="private_left_over" value="true"/>
  </node>
  <node pkg="closed_loop" type="start_when_ready" name="stubborn" args="--help" launch-prefix="bash -c 'trap &quot;&quot; INT TERM; sleep 600' --"/>
</launch>
'''


def master_state():
    """(every parameter, every node registered) of this process's kept graph, once its last episode's end is done."""
    kept = graph_episode._KEPT[0]
    assert kept.settle(), kept.why()
    with open(os.path.join(kept.folder, 'port')) as f:
        master = xmlrpc.client.ServerProxy('http://127.0.0.1:%d' % int(f.read()))
    params = master.getParam('/test', '/')[2]
    nodes = {n for kind in master.getSystemState('/test')[2] for _, ns in kind for n in ns}
    return params, nodes, kept


def test_an_episode_leaves_nothing_in_the_kept_graph_and_each_gives_what_its_own_graph_gives(tmp_path):
    launch = tmp_path / 'messy.launch'
    launch.write_text(MESSY)
    out = tmp_path / 'graphs'
    out.mkdir()
    try:
        first = run_episode(EpisodeSpec.from_dict(STOP), {}, str(out / 'first'))
        assert first.outcome == 'stopped', first.why
        params, nodes, kept = master_state()
        assert nodes == {'/sim', '/robot_state_publisher'}, nodes
        assert 'left_over' not in params and 'max_linear_speed' in params['sim']

        messy_spec = {k: v for k, v in STOP.items() if k != 'settings'}
        messy = run_episode(EpisodeSpec.from_dict(dict(messy_spec, controller={'launch': str(launch)})), {},
                            str(out / 'messy'))
        assert messy.outcome == 'stopped', messy.why
        after, nodes_after, kept_after = master_state()
        assert kept_after is kept, 'the kept graph was replaced'
        assert nodes_after == nodes and after == params, (nodes_after, sorted(after))

        again = run_episode(EpisodeSpec.from_dict(STOP), {}, str(out / 'again'))
        assert graph_episode._KEPT[0] is kept
        messy_own = run_episode(EpisodeSpec.from_dict(dict(messy_spec, controller={'launch': str(launch),
                                                                                   'fresh_graph': True})),
                                {}, str(out / 'messy_own'))
        # The same to the bit: after an episode that changed the simulator's parameters, and in a graph of its own
        # (the launch's own /sim/max_linear_speed of 0.2 m/s applies in both: it takes 10 s to stop).
        assert (again.outcome, again.time_s, again.final_pose) == (first.outcome, first.time_s, first.final_pose)
        assert (messy_own.outcome, messy_own.time_s, messy_own.final_pose) == (
            messy.outcome, messy.time_s, messy.final_pose) and messy.time_s > 10.0, (messy.why, messy_own.why)
    finally:
        graph_episode.close_kept_graph()
    assert graph_leftovers(out) == {'processes': [], 'listening': []}
