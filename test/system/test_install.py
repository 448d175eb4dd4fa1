"""The package as a user installs it into a workspace of their own (docs/development.md, "Using the package from your
own catkin workspace"): catkin_lint -W2 finds nothing; `catkin_make install` with the venv's interpreter
puts that interpreter into the installed scripts, so the demo runs from the install space with a PATH that
has no venv on it."""
import os
import shutil
import subprocess
import sys
import time

from conftest import ROOT, free_port, ros_env, stop, wait_master

BUILD_TIMEOUT_S = 600
LAUNCH_WAIT_S = 90
# What a user's shell has before they source anything: no venv, no workspace.
PLAIN_PATH = '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'
ROS_WORKSPACE_VARIABLES = ('ROS_PACKAGE_PATH', 'CMAKE_PREFIX_PATH', 'PYTHONPATH', 'LD_LIBRARY_PATH', 'PKG_CONFIG_PATH',
                           'ROS_ROOT', 'ROS_ETC_DIR', 'ROS_DISTRO', 'ROSLISP_PACKAGE_DIRECTORIES', 'VIRTUAL_ENV')


def package_files():
    """The package's files as a clone has them: those git tracks or would track (not ignored), or without
    git the tree minus build products."""
    if os.path.isdir(os.path.join(ROOT, '.git')):
        out = subprocess.run(['git', 'ls-files', '-z', '--cached', '--others', '--exclude-standard'], cwd=ROOT, stdout=subprocess.PIPE, check=True).stdout
        return [name for name in out.decode().split('\0') if name and os.path.exists(os.path.join(ROOT, name))]
    skip = {'.git', '.ws', '.venv', '.venv38', 'test_output'}
    names = []
    for folder, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in skip]
        names += [os.path.relpath(os.path.join(folder, f), ROOT) for f in files]
    return names


def plain(env):
    """``env`` as a user's shell has it before they source anything: no ROS workspace, no venv, and none of
    Python's own variables (``PYTHONUNBUFFERED``, ``PYTHONDONTWRITEBYTECODE``, ...), which a user's machine lacks."""
    return {k: v for k, v in env.items() if k not in ROS_WORKSPACE_VARIABLES and not k.startswith('PYTHON')}


def clean_env(tmp_path):
    env = plain(os.environ)
    env['PATH'] = PLAIN_PATH
    env['HOME'] = str(tmp_path)
    env.pop('PWD', None)
    return env


def test_lint_clean_and_the_install_space_runs_the_demo_without_the_venv_on_path(tmp_path):
    workspace = tmp_path / 'catkin_ws'
    package = workspace / 'src' / 'closed_loop'
    for name in package_files():
        os.makedirs(os.path.dirname(str(package / name)), exist_ok=True)
        shutil.copy2(os.path.join(ROOT, name), str(package / name))
    env = clean_env(tmp_path)

    lint = subprocess.run([os.path.join(os.path.dirname(sys.executable), 'catkin_lint'), '-W2', str(package)],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, env=env,
                          cwd=str(tmp_path), timeout=BUILD_TIMEOUT_S)
    problems = [line for line in lint.stdout.splitlines()
                if line.startswith('closed_loop:')]
    assert lint.returncode == 0 and not problems, lint.stdout
    assert 'found 0 problems' in lint.stdout or 'checked 1 packages and found 0' in lint.stdout, lint.stdout

    # The documented step: catkin_make install with the venv's interpreter (sys.executable is that venv's).
    python = sys.executable
    build = subprocess.run(['catkin_make', '-C', str(workspace), 'install', '-DPYTHON_EXECUTABLE=' + python],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True, env=env,
                           cwd=str(workspace), timeout=BUILD_TIMEOUT_S)
    assert build.returncode == 0, build.stdout[-4000:]
    install = workspace / 'install'
    scripts = sorted(os.listdir(str(package / 'scripts')))
    for name in scripts:
        with open(str(install / 'lib' / 'closed_loop' / name)) as f:
            assert f.readline().strip() == '#!' + python, 'lib/closed_loop/%s does not name the venv' % name
    assert (install / 'share' / 'closed_loop' / 'config' / 'robots' / 'burger.yaml').is_file()
    site = [p for p in (install / 'lib').glob('python3*/*-packages/closed_loop/sim/sensors/lidar.py')]
    assert site, 'closed_loop.sim.sensors is not installed'

    port = free_port()
    launch_env = plain(ros_env(tmp_path, port))
    launch_env.update(PATH=PLAIN_PATH, HOME=str(tmp_path))
    launch_env.pop('PWD', None)
    log_path = tmp_path / 'demo.log'
    with open(str(log_path), 'w') as log:
        # The paths go in as arguments, never into the command text.
        demo = subprocess.Popen(['bash', '-c', 'source "$1" && exec roslaunch -p "$2" closed_loop demo.launch '
                                 'camera:=false', 'bash', str(install / 'setup.bash'), str(port)],
                                stdout=log, stderr=subprocess.STDOUT, env=launch_env, start_new_session=True)
    try:
        wait_master(port, demo, timeout_s=LAUNCH_WAIT_S)
        echo_env = dict(launch_env)
        deadline = time.monotonic() + LAUNCH_WAIT_S
        seen = ''
        while time.monotonic() < deadline and demo.poll() is None:
            try:
                echo = subprocess.run(['bash', '-c', 'source "$1" && exec rostopic echo -n 1 /stop_on_obstacle/mode',
                                       'bash', str(install / 'setup.bash')], stdout=subprocess.PIPE,
                                      stderr=subprocess.STDOUT, universal_newlines=True, env=echo_env, timeout=30)
            except subprocess.TimeoutExpired:
                continue
            seen = echo.stdout
            if 'data: "' in seen:
                break
            time.sleep(1.0)
    finally:
        stop(demo)
    # Read once the launch has ended: roslaunch's output to a file is block-buffered (no PYTHONUNBUFFERED here).
    with open(str(log_path)) as f:
        text = f.read()
    assert 'data: "CLEAR"' in seen or 'data: "SLOW"' in seen or 'data: "STOP"' in seen, \
        'no mode from the installed controller:\n%s\n--- demo log ---\n%s' % (seen, text[-4000:])
    assert str(install) in text or 'process[sim-' in text, text[-4000:]
    assert 'process has died' not in text, text[-4000:]
