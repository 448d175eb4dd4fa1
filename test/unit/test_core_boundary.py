"""The ROS-free core stays ROS-free: every module outside ``nodes/`` imports with ROS blocked.

The check runs in a fresh interpreter, so modules this test run already imported (or that
another test imported with ROS available) cannot hide a dependency.
"""
import json
import os
import subprocess
import sys
import textwrap

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
PACKAGE_DIR = os.path.join(SRC, 'closed_loop')
# The thin ROS layer: the only place allowed to import rospy and message packages.
ROS_LAYER = 'nodes'
BLOCKED_NAMES = ('rospy', 'roslib', 'rospkg', 'genpy', 'tf2_ros')
BLOCKED_SUFFIXES = ('_msgs', '_srvs')
IMPORT_TIMEOUT_S = 120

CHECKER = textwrap.dedent('''
    import importlib
    import json
    import sys
    import traceback

    BLOCKED_NAMES = set(%(names)r)
    BLOCKED_SUFFIXES = %(suffixes)r
    attempts = []


    class BlockRos(object):
        """Refuse ROS modules before any other finder can locate them."""

        def find_spec(self, fullname, path=None, target=None):
            top = fullname.split('.')[0]
            if top in BLOCKED_NAMES or top.endswith(BLOCKED_SUFFIXES):
                attempts.append(fullname)
                raise ImportError('%%s is blocked: the core must not import ROS' %% fullname)
            return None


    sys.path.insert(0, %(src)r)
    sys.meta_path.insert(0, BlockRos())
    result = {'blocked_probe': [], 'imported': [], 'failed': {}, 'attempts': {}}
    # Prove the block works: the ROS layer itself must now fail to import.
    for probe in ('rospy', 'std_msgs.msg', 'closed_loop.%(ros_layer)s.common'):
        try:
            importlib.import_module(probe)
        except ImportError:
            result['blocked_probe'].append(probe)
    for name in [m for m in list(sys.modules) if m.startswith('closed_loop')]:
        del sys.modules[name]
    del attempts[:]
    for module in %(modules)r:
        before = len(attempts)
        try:
            importlib.import_module(module)
            result['imported'].append(module)
        except Exception:
            result['failed'][module] = traceback.format_exc()
        if len(attempts) > before:
            # Even a guarded "try: import rospy" is a leak through the boundary.
            result['attempts'][module] = attempts[before:]
    result['loaded_ros'] = sorted(m for m in sys.modules
                                  if m.split('.')[0] in BLOCKED_NAMES
                                  or m.split('.')[0].endswith(BLOCKED_SUFFIXES))
    print(json.dumps(result))
''')


def core_modules():
    """Dotted names of every module under src/closed_loop/ except the ROS layer, found on disk."""
    modules = []
    for directory, subdirs, files in os.walk(PACKAGE_DIR):
        relative = os.path.relpath(directory, SRC)
        if relative.split(os.sep)[:2] == ['closed_loop', ROS_LAYER]:
            subdirs[:] = []
            continue
        subdirs[:] = sorted(d for d in subdirs if not d.startswith(('.', '__')))
        package = relative.replace(os.sep, '.')
        for name in sorted(files):
            if not name.endswith('.py'):
                continue
            stem = name[:-3]
            modules.append(package if stem == '__init__' else package + '.' + stem)
    return modules


def test_discovery_finds_the_core_and_skips_the_ros_layer():
    modules = core_modules()
    for expected in ('closed_loop', 'closed_loop.sim.drive', 'closed_loop.settings',
                     'closed_loop.sim.simulation', 'closed_loop.sim.world'):
        assert expected in modules
    assert not any(m.startswith('closed_loop.%s' % ROS_LAYER) for m in modules)


def test_every_core_module_imports_without_ros():
    modules = core_modules()
    script = CHECKER % {'names': BLOCKED_NAMES, 'suffixes': BLOCKED_SUFFIXES, 'src': SRC,
                        'ros_layer': ROS_LAYER, 'modules': modules}
    process = subprocess.run([sys.executable, '-c', script], stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, timeout=IMPORT_TIMEOUT_S,
                             universal_newlines=True, cwd=os.path.dirname(SRC))
    assert process.returncode == 0, process.stderr
    # The last line is ours; anything a C extension prints comes before it.
    result = json.loads(process.stdout.strip().splitlines()[-1])
    assert result['blocked_probe'] == ['rospy', 'std_msgs.msg', 'closed_loop.%s.common' % ROS_LAYER]
    assert result['failed'] == {}, '\n'.join(result['failed'].values())
    assert result['attempts'] == {}
    assert result['imported'] == modules
    assert result['loaded_ros'] == []
