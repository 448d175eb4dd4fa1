"""Before a tool starts a launch: a master URI where something listens but no master answers is named."""
import os
import socket
import threading
from xmlrpc.server import SimpleXMLRPCServer

from closed_loop import launcher
from test_netenv import _MasterApi


def test_nothing_listening_is_no_problem():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))            # bound, not listening: refused, so roslaunch will start a master
        assert launcher.master_problem('http://127.0.0.1:%d' % s.getsockname()[1]) is None


def test_a_port_that_accepts_and_never_answers_is_named():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        s.listen(4)
        uri = 'http://127.0.0.1:%d' % s.getsockname()[1]
        problem = launcher.master_problem(uri)
    assert problem is not None and uri in problem and 'does not answer as a ROS master' in problem, problem


def test_an_answering_master_is_no_problem():
    server = SimpleXMLRPCServer(('127.0.0.1', 0), logRequests=False)
    server.register_instance(_MasterApi())
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        assert launcher.master_problem('http://127.0.0.1:%d' % server.server_address[1]) is None
    finally:
        server.shutdown()
        server.server_close()


def test_a_malformed_uri_is_named_and_cut():
    problem = launcher.master_problem('not a uri ' + 'x' * 1000)
    assert problem.startswith('ROS_MASTER_URI ') and len(problem) < 300, problem
    assert launcher.master_problem('http://127.0.0.1:notaport') is not None


def test_a_graph_run_again_in_its_folder_is_not_the_dead_runs_keepers_to_kill(tmp_path):
    # A worker dies; its keeper ends its graph and, after a grace, kills what carries its mark. The episode,
    # run again in the same folder by another worker meanwhile, must not be among them.
    import subprocess
    import sys
    from closed_loop import launcher
    from closed_loop.batch.graph_episode import graph_mark
    folder = str(tmp_path / 'graphs' / '1')
    dead, again = graph_mark(folder), graph_mark(folder)
    assert dead != again and not again.startswith(dead) and not dead.startswith(again)
    node = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(30)'],
                            env=dict(os.environ, **{launcher.MARK: again}))
    try:
        import time
        deadline = time.monotonic() + 10
        while node.pid not in launcher.marked_processes(str(tmp_path)) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert node.pid in launcher.marked_processes(folder + os.sep)       # the sweep's cleanup finds it
        launcher.kill_marked(dead)
        assert node.poll() is None and node.pid not in launcher.marked_processes(dead)
    finally:
        node.kill()
        node.wait()


def test_a_launch_log_s_failure_lines_are_quoted_without_roslaunch_s_colours(tmp_path):
    log = tmp_path / 'launch.log'
    log.write_text('[INFO] started\n[FATAL] [1.0, 0.0] [/sim]: cannot load the world\n'
                   '\x1b[31m=====REQUIRED process [sim-2] has died!\x1b[0m\n')
    assert launcher.failure_lines(str(log)) == ['[FATAL] [1.0, 0.0] [/sim]: cannot load the world',
                                                '=====REQUIRED process [sim-2] has died!']
    assert launcher.failure_lines(str(tmp_path / 'missing.log')) == []
