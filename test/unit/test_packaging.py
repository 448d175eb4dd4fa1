"""Packaging: what catkin installs is complete (every node script, every Python package)."""
import os
import re
import shutil
import subprocess

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))


def read(name):
    with open(os.path.join(ROOT, name)) as f:
        return f.read()


def test_every_node_script_is_installed():
    listed = re.search(r'set\(CLOSED_LOOP_SCRIPTS(.*?)\)', read('CMakeLists.txt'), re.S)
    assert listed, 'CMakeLists.txt has no set(CLOSED_LOOP_SCRIPTS ...)'
    installed = set(listed.group(1).split())
    scripts = set(os.listdir(os.path.join(ROOT, 'scripts')))
    assert installed == scripts, ('add each script of scripts/ to CLOSED_LOOP_SCRIPTS in CMakeLists.txt '
                                  '(missing: %s; not in scripts/: %s)'
                                  % (sorted(scripts - installed), sorted(installed - scripts)))


def test_every_python_package_is_in_setup_py():
    packages = set()
    for folder, _dirs, files in os.walk(os.path.join(ROOT, 'src')):
        if '__init__.py' in files:
            packages.add(os.path.relpath(folder, os.path.join(ROOT, 'src')).replace(os.sep, '.'))
    listed = set(re.findall(r"'(closed_loop[\w.]*)'", re.search(r'packages=\[(.*?)\]', read('setup.py'), re.S).group(1)))
    assert listed == packages, 'setup.py packages= must list %s' % sorted(packages)


def test_developer_tools_are_not_executables_for_catkin():
    # catkin_lint reports an executable that is not installed; tools/ are run as `bash tools/x.sh`,
    # `python3 tools/x.py`.
    for name in os.listdir(os.path.join(ROOT, 'tools')):
        path = os.path.join(ROOT, 'tools', name)
        if os.path.isfile(path):       # (a directory, such as a __pycache__ of `make compat`, is not a program)
            assert not os.access(path, os.X_OK), 'tools/%s is executable' % name


#: Every program the package, its tools and its tests run: the Debian package that has it (tools/provision.sh
#: installs it) and its rosdep key in package.xml (None where rosdep has none; package.xml says why in a comment).
PROGRAMS = {
    'bash': ('bash', None), 'sleep': ('coreutils', 'coreutils'), 'timeout': ('coreutils', 'coreutils'),
    'seq': ('coreutils', 'coreutils'), 'hostname': ('hostname', None), 'mount': ('mount', None),
    'umount': ('mount', None), 'unshare': ('util-linux', 'util-linux'), 'nsenter': ('util-linux', 'util-linux'),
    'setpriv': ('util-linux', 'util-linux'), 'ip': ('iproute2', 'iproute2'), 'ss': ('iproute2', 'iproute2'),
    'pgrep': ('procps', 'procps'), 'git': ('git', 'git'), 'Xvfb': ('xvfb', 'xvfb'), 'xwd': ('x11-apps', None),
    'chromium': ('chromium', 'chromium-browser'), 'cmake': ('cmake', 'cmake'), 'g++': ('g++', None),
    'catkin_make': ('catkin', 'catkin'), 'roscore': ('python3-roslaunch', 'roslaunch'),
    'roslaunch': ('python3-roslaunch', 'roslaunch'), 'rosmaster': ('python3-rosmaster', 'rosmaster'),
    'rostest': ('python3-rostest', 'rostest'), 'rosbag': ('python3-rosbag', 'rosbag'),
    'rostopic': ('python3-rostopic', 'rostopic'), 'rosparam': ('python3-rosparam', 'rosparam'),
    'rosservice': ('python3-rosservice', 'rosservice'),
    'rosrun': ('rosbash', 'rosbash'), 'rospack': ('rospack-tools', 'rospack'), 'dpkg-query': ('dpkg', None), 'openssl': ('openssl', 'openssl'),
}
#: Debian's Essential packages, on every Debian system and never removed: provisioning need not name them.
ESSENTIAL = {'bash', 'dpkg'}
#: Programs run from shell text (test_network's graph script) or named apart from a call (machine.py's setpriv),
#: which the scan below cannot see.
RUN_FROM_TEXT = {'nsenter', 'ss', 'hostname', 'timeout', 'seq', 'setpriv', 'g++', 'cmake'}
#: A call's program: the first item of an argument list handed to subprocess (or a test's own ``sh``), and
#: ``shutil.which``'s argument.
#: tools/fresh.py runs on the developer's machine around the package (debootstrap, chroot), not in it; it installs
#: debootstrap itself.
AROUND = {os.path.join('tools', 'fresh.py')}
CALLED = re.compile(r"(?:Popen|run|call|check_output|check_call|\bsh)\(\s*\[\s*'([^']+)'|which\('([^']+)'\)")


def called_programs():
    found = set()
    for top in ('src', 'tools', 'test'):
        for folder, dirs, files in os.walk(os.path.join(ROOT, top)):
            dirs[:] = [d for d in dirs if d != '__pycache__']
            for name in files:
                if name.endswith('.py') and os.path.relpath(os.path.join(folder, name), ROOT) not in AROUND:
                    with open(os.path.join(folder, name)) as f:
                        found.update(a or b for a, b in CALLED.findall(f.read()))
    return {name for name in found if '/' not in name and name not in ('chromium-browser', 'sys.executable')}


def test_every_program_run_is_provisioned_and_declared():
    called = called_programs()
    assert called >= {'roslaunch', 'ip', 'unshare', 'Xvfb', 'xwd'}      # the scan sees the calls it is for
    unknown = called - set(PROGRAMS)
    assert not unknown, ('add %s to PROGRAMS here with its Debian package (in tools/provision.sh) and rosdep key '
                         '(in package.xml)' % sorted(unknown))
    assert not RUN_FROM_TEXT - set(PROGRAMS)
    provisioned = set(re.search(r'APT_PACKAGES=\((.*?)\)', read('tools/provision.sh'), re.S).group(1).split())
    declared = set(re.findall(r'<(?:\w+_)?depend>([^<]+)</', read('package.xml')))
    not_provisioned = {name: package for name, (package, _) in PROGRAMS.items()
                       if package not in provisioned | ESSENTIAL}
    assert not not_provisioned, 'tools/provision.sh does not install: %s' % not_provisioned
    undeclared = {name: key for name, (_, key) in PROGRAMS.items() if key is not None and key not in declared}
    assert not undeclared, 'package.xml does not declare: %s' % undeclared


def test_each_program_comes_from_the_debian_package_named_for_it():
    dpkg = shutil.which('dpkg-query')
    if dpkg is None:
        pytest.skip('not a Debian system: no dpkg-query to ask which package has a program')
    for name, (package, _) in sorted(PROGRAMS.items()):
        path = shutil.which(name)
        assert path is not None, '%s is not installed (make provision installs %s)' % (name, package)
        real = os.path.realpath(path)
        # Debian's merged /usr: a package may list /bin/ip for /usr/bin/ip.
        candidates = {path, real} | {p[len('/usr'):] for p in (path, real) if p.startswith('/usr/')}
        owners = subprocess.run(['dpkg-query', '-S'] + sorted(candidates), stdout=subprocess.PIPE,
                                stderr=subprocess.DEVNULL, universal_newlines=True).stdout
        found = {line.split(':')[0] for line in owners.splitlines() if ':' in line}
        assert any(owner == package or owner.startswith(package + '-') for owner in found), (name, package, found)


#: Every module outside the standard library that the package (src/) or its tests (test/) import: how it is
#: installed (``apt:`` a Debian package tools/provision.sh installs, ``pip:`` a pinned line of requirements.txt)
#: and its rosdep key in package.xml (None where rosdep has none: package.xml says so in a comment). What the
#: package imports is an exec_depend; what only the tests import, a test_depend (or an exec_depend).
MODULES = {
    'rospy': ('apt:python3-rospy', 'rospy'), 'rosgraph': ('apt:python3-rosgraph', 'rosgraph'),
    'rospkg': ('apt:python3-rospkg', 'python3-rospkg'), 'roslaunch': ('apt:python3-roslaunch', 'roslaunch'),
    'rosbag': ('apt:python3-rosbag', 'rosbag'), 'rosnode': ('apt:python3-rosnode', 'rosnode'),
    'rostest': ('apt:python3-rostest', 'rostest'), 'tf2_ros': ('apt:python3-tf2-ros', 'tf2_ros'),
    'dynamic_reconfigure': ('apt:python3-dynamic-reconfigure', 'dynamic_reconfigure'),
    'std_msgs': ('apt:python3-std-msgs', 'std_msgs'), 'std_srvs': ('apt:python3-std-srvs', 'std_srvs'),
    'geometry_msgs': ('apt:python3-geometry-msgs', 'geometry_msgs'),
    'sensor_msgs': ('apt:python3-sensor-msgs', 'sensor_msgs'), 'nav_msgs': ('apt:python3-nav-msgs', 'nav_msgs'),
    'visualization_msgs': ('apt:python3-visualization-msgs', 'visualization_msgs'),
    'tf2_msgs': ('apt:python3-tf2-msgs', 'tf2_msgs'), 'rosgraph_msgs': ('apt:python3-rosgraph-msgs', 'rosgraph_msgs'),
    'yaml': ('apt:python3-yaml', 'python3-yaml'), 'pytest': ('apt:python3-pytest', 'python3-pytest'),
    'numpy': ('pip:numpy', 'python3-numpy'), 'cv2': ('pip:opencv-python-headless', 'python3-opencv'),
    'pybullet': ('pip:pybullet', 'python3-pybullet-pip'), 'numba': ('pip:numba', 'python3-numba'),
    'matplotlib': ('pip:matplotlib', 'python3-matplotlib'), 'xacro': ('pip:xacro', 'xacro'),
    'dask': ('pip:dask', None), 'distributed': ('pip:distributed', None),
    'trimesh': ('pip:trimesh', 'python3-trimesh-pip'), 'collada': ('pip:pycollada', 'python3-collada'),
    'scipy': ('pip:scipy', 'python3-scipy'), 'optuna': ('pip:optuna', None),
    'cryptography': ('apt:python3-cryptography', 'python3-cryptography'),
}


def imported_modules(top):
    """{module: the files of ``top`` that import it} for every absolute import outside the standard library and
    the project's own files (the package, the tests' and tools' helper modules)."""
    import ast
    import sys
    # (creep: the throw-away core of docs/development.md, which test_own_core writes and imports.)
    own = {'closed_loop', 'creep'} | {name[:-3] for folder in ('test', 'test/system', 'test/unit', 'test/rostest',
                                                               'test/bench', 'tools')
                             if os.path.isdir(os.path.join(ROOT, folder))
                             for name in os.listdir(os.path.join(ROOT, folder)) if name.endswith('.py')}
    found = {}
    for folder, dirs, files in os.walk(os.path.join(ROOT, top)):
        dirs[:] = [d for d in dirs if d != '__pycache__']
        for name in files:
            path = os.path.join(folder, name)
            if not name.endswith('.py') and not folder.endswith('scripts'):
                continue
            try:
                tree = ast.parse(open(path).read(), path)
            except (SyntaxError, UnicodeDecodeError):
                continue                                          # (not Python: a C++ or shell file)
            for node in ast.walk(tree):
                names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                    [node.module] if isinstance(node, ast.ImportFrom) and not node.level and node.module else []
                for module in {n.split('.')[0] for n in names} - own - set(sys.stdlib_module_names):
                    found.setdefault(module, set()).add(os.path.relpath(path, ROOT))
    return found


def test_every_import_is_provisioned_and_declared_with_its_key():
    import sys
    if not hasattr(sys, 'stdlib_module_names'):
        pytest.skip('Python before 3.10 does not list its standard library')
    package, tests = imported_modules('src'), imported_modules('test')
    assert {'rospy', 'pybullet', 'xacro'} <= set(package) and 'pytest' in tests   # the scan sees the imports
    unknown = {m: sorted(files)[:3] for m, files in list(package.items()) + list(tests.items()) if m not in MODULES}
    assert not unknown, ('add each to MODULES here, with how provisioning installs it and its rosdep key: %s'
                         % unknown)
    provisioned = set(re.search(r'APT_PACKAGES=\((.*?)\)', read('tools/provision.sh'), re.S).group(1).split())
    pinned = {line.split('==')[0].strip() for line in read('requirements.txt').splitlines() if '==' in line}
    missing = {m: how for m, (how, _) in MODULES.items() if (m in package or m in tests)
               and how.partition(':')[2] not in (provisioned if how.startswith('apt:') else pinned)}
    assert not missing, 'provisioning does not install: %s' % missing
    xml = read('package.xml')
    run = set(re.findall(r'<(?:exec_)?depend>([^<]+)</', xml))
    test = run | set(re.findall(r'<test_depend>([^<]+)</', xml))
    undeclared = {m: key for m, (_, key) in MODULES.items() if key is not None and
                  (m in package and key not in run or m in tests and key not in test)}
    assert not undeclared, 'package.xml does not declare (exec_depend for src/, test_depend for test/): %s' % undeclared
