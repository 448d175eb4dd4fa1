"""A tool that watches a launch (``make demo``, the screenshot) ends when the launch ends, even if the master
goes while it subscribes: rospy alone retries that registration forever."""
import os
import subprocess
import sys
import textwrap

from conftest import ROOT, free_port, ros_env

# A child that joins a real master's graph, sees the master end, then subscribes.
CHILD = textwrap.dedent('''
    import signal, subprocess, sys
    sys.path.insert(0, sys.argv[1] + '/src')
    import rospy
    from std_msgs.msg import String
    from closed_loop.nodes.common import join_launch
    launch = subprocess.Popen(['roscore', '-p', sys.argv[2]], stdout=subprocess.DEVNULL,
                              stderr=subprocess.STDOUT, start_new_session=True)
    joined = join_launch('joiner', launch, 30.0)
    launch.send_signal(signal.SIGINT)
    launch.wait(30)
    rospy.Subscriber('/anything', String, lambda m: None)
    # Shut-down asked for: rospy.is_shutdown() turns true only once its shut-down hooks have run, in the
    # watcher's thread, which may be a moment after the subscription returned.
    print('joined %s; subscribed after the launch ended; shut down: %s'
          % (joined, rospy.core.is_shutdown_requested()))
''')


def test_a_subscription_made_after_the_launch_ended_returns(tmp_path):
    port = free_port()
    done = subprocess.run([sys.executable, '-c', CHILD, ROOT, str(port)], env=ros_env(tmp_path, port),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=90)
    out = done.stdout.decode(errors='replace')
    assert 'joined True; subscribed after the launch ended; shut down: True' in out, out


def test_no_master_is_reported_not_waited_for_forever(tmp_path):
    port = free_port()
    code = textwrap.dedent('''
        import subprocess, sys
        sys.path.insert(0, sys.argv[1] + '/src')
        from closed_loop.nodes.common import join_launch
        launch = subprocess.Popen([sys.executable, '-c', 'pass'])
        print('joined', join_launch('joiner', launch, 30.0))
    ''')
    done = subprocess.run([sys.executable, '-c', code, ROOT], env=ros_env(tmp_path, port),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
    assert b'joined False' in done.stdout, done.stdout


def test_a_port_that_accepts_and_never_answers_is_no_master(tmp_path):
    """rosgraph's own check waits forever on such a port; the tools give up at their bound."""
    port = free_port()
    code = textwrap.dedent('''
        import socket, subprocess, sys, time
        sys.path.insert(0, sys.argv[1] + '/src')
        from closed_loop.nodes.common import join_launch
        silent = socket.socket()
        silent.bind(('127.0.0.1', int(sys.argv[2])))
        silent.listen(8)
        launch = subprocess.Popen(['sleep', '60'])
        started = time.monotonic()
        joined = join_launch('joiner', launch, 3.0)
        print('joined %s after %.0f s' % (joined, time.monotonic() - started))
        launch.kill()
    ''')
    done = subprocess.run([sys.executable, '-c', code, ROOT, str(port)], env=ros_env(tmp_path, port),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
    assert b'joined False' in done.stdout, done.stdout


# A master that answers the tools' check (getSystemState, then getPid) once, then closes its port and
# ends 2 s later: the tool's node retries its registration meanwhile.
FAKE_MASTER = textwrap.dedent('''
    import os, sys, time
    from xmlrpc.server import SimpleXMLRPCServer
    server = SimpleXMLRPCServer(('127.0.0.1', int(sys.argv[1])), logRequests=False)
    server.register_function(lambda caller: [1, '', []], 'getSystemState')
    server.register_function(lambda caller: [1, '', os.getpid()], 'getPid')
    server.handle_request()
    server.handle_request()
    server.server_close()
    time.sleep(2.0)
''')


def test_a_launch_that_ends_while_the_tool_joins_is_reported(tmp_path):
    """The master answers the check, then is gone before the tool's node registers (a required node that
    failed at once, under load): rospy's own start-up would retry its registration forever."""
    port = free_port()
    code = textwrap.dedent('''
        import subprocess, sys, time
        sys.path.insert(0, sys.argv[1] + '/src')
        from closed_loop.nodes.common import join_launch
        launch = subprocess.Popen([sys.executable, '-c', sys.argv[3], sys.argv[2]])
        started = time.monotonic()
        joined = join_launch('joiner', launch, 30.0)
        print('joined %s; launch ended: %s; after %.0f s'
              % (joined, launch.poll() is not None, time.monotonic() - started))
    ''')
    done = subprocess.run([sys.executable, '-c', code, ROOT, str(port), FAKE_MASTER], env=ros_env(tmp_path, port),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
    out = done.stdout.decode(errors='replace')
    assert 'joined False; launch ended: True' in out, out


def test_the_screenshot_says_why_when_the_launch_ends_early(tmp_path):
    # demo.launch with a world that does not exist: the simulator (required) exits, and roslaunch with it,
    # while the screenshot tool waits for the robot to drive. It says so in a sentence, not a traceback.
    port = free_port()
    out_png = tmp_path / 'shot.png'
    done = subprocess.run([sys.executable, os.path.join(ROOT, 'tools', 'screenshot.py'), '--world', 'no_such_world',
                           '--out', str(out_png), '--port', str(port)], env=ros_env(tmp_path, port),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=150)
    out = done.stdout.decode(errors='replace')
    assert done.returncode == 1, out
    assert 'screenshot: the launch ended early' in out and 'Traceback' not in out, out
    assert not out_png.exists()
