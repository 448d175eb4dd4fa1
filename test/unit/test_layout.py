"""The layout holds: imports run one way (nodes -> batch -> controllers -> control; sim beside control; all on
the shared helpers), only the nodes import rospy or message packages, the control cores never see pybullet,
and no module grows past 400 lines. Read from the source text (every import, at any depth), so an import
inside a function cannot hide."""
import ast
import os

import pytest

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
PACKAGE = 'closed_loop'
MAX_MODULE_LINES = 400
#: Each layer and the layers it may import (the shared helpers are the top-level modules of the package).
ALLOWED = {
    'helpers': {'helpers'},
    'sim': {'helpers', 'sim'},
    'control': {'helpers', 'control'},
    'controllers': {'helpers', 'control', 'controllers'},
    'batch': {'helpers', 'sim', 'control', 'controllers', 'batch'},
    'nodes': {'helpers', 'sim', 'control', 'controllers', 'batch', 'nodes'},
}
#: Top-level modules that are commands of a layer rather than helpers (``python3 -m closed_loop.sweep``).
ENTRY_POINTS = {'closed_loop.sweep': 'batch'}
ROS_NAMES = ('rospy', 'roslib', 'rospkg', 'rosgraph', 'rosbag', 'roslaunch', 'rosnode', 'rostopic', 'genpy',
             'tf2_ros', 'dynamic_reconfigure', 'actionlib', 'message_filters')
ROS_SUFFIXES = ('_msgs', '_srvs')
#: What a helper may import beside the rule, and why. closed_loop.description reads a robot description the way
#: ROS's tools and the simulator read it, in the functions that need it (a URDF of primitives loads none of
#: these): the ROS package path through rospkg ($(find PKG), package://; not rospy: no master, no node) and the
#: meshes' vertices through pybullet (the simulator's own reading of them, so the footprint is what collides).
EXCEPTIONS = {'closed_loop.description': {'rospkg', 'pybullet'}}


def modules():
    """{dotted name: path} of every module of the package."""
    found = {}
    for folder, dirs, files in os.walk(os.path.join(SRC, PACKAGE)):
        dirs[:] = [d for d in dirs if not d.startswith(('.', '__'))]
        package = os.path.relpath(folder, SRC).replace(os.sep, '.')
        for name in files:
            if name.endswith('.py'):
                found[package if name == '__init__.py' else package + '.' + name[:-3]] = os.path.join(folder, name)
    return found


def layer(module):
    if module in ENTRY_POINTS:
        return ENTRY_POINTS[module]
    parts = module.split('.')
    if len(parts) > 1 and os.path.isdir(os.path.join(SRC, PACKAGE, parts[1])):
        return parts[1]
    return 'helpers'


def imports(module, path):
    """Every module ``path`` imports, as absolute dotted names."""
    tree = ast.parse(open(path).read(), path)
    names = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names += [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            assert not node.level, '%s: a relative import; the package imports by absolute names' % path
            base = node.module
            names.append(base)
            names += ['%s.%s' % (base, a.name) for a in node.names]
    return names


def is_ros(name):
    top = name.split('.')[0]
    return top in ROS_NAMES or top.endswith(ROS_SUFFIXES)


def test_every_sub_package_says_what_it_holds_and_may_import():
    for sub in ('sim', 'control', 'controllers', 'batch', 'nodes'):
        with open(os.path.join(SRC, PACKAGE, sub, '__init__.py')) as f:
            doc = ast.get_docstring(ast.parse(f.read()))
        assert doc and ('May import' in doc or 'Free of ROS' in doc), '%s/__init__.py: say what it holds and ' \
                                                                     'what it may import' % sub


def test_imports_run_one_way():
    everything = modules()
    wrong = []
    for module, path in sorted(everything.items()):
        mine = layer(module)
        for name in imports(module, path):
            if name.split('.')[0] != PACKAGE or name not in everything:
                continue
            theirs = layer(name)
            if theirs not in ALLOWED[mine]:
                wrong.append('%s (%s) imports %s (%s)' % (module, mine, name, theirs))
    assert not wrong, '\n'.join(wrong)


def test_only_the_nodes_import_ros_and_the_control_cores_never_the_simulator():
    wrong = []
    for module, path in sorted(modules().items()):
        mine = layer(module)
        for name in imports(module, path):
            if name.split('.')[0] in EXCEPTIONS.get(module, ()):
                continue
            if is_ros(name) and mine != 'nodes':
                wrong.append('%s imports %s: only closed_loop.nodes may' % (module, name))
            if name.split('.')[0] == 'pybullet' and mine in ('control', 'controllers', 'helpers'):
                wrong.append('%s imports pybullet: only the simulator (and what drives it) may' % module)
    assert not wrong, '\n'.join(wrong)


def import_graph():
    """{module: the package's modules it imports, at any depth of its code (a function's imports too)}."""
    everything = modules()
    graph = {}
    for module, path in everything.items():
        found = set()
        for name in imports(module, path):
            while name and name not in everything:        # 'closed_loop.sim.world.load_world' -> its module
                name = name.rpartition('.')[0]
            if name and name != module:
                found.add(name)
        graph[module] = found
    return graph


def import_circles(graph):
    """The circles of ``graph`` ({node: its successors}): each strongly connected set of more than one module
    (Tarjan's), as sorted lists."""
    graph = {m: {n for n in found if n in graph} for m, found in graph.items()}
    index, low, stack, on, circles = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on.add(node)
        for successor in graph[node]:
            if successor not in index:
                visit(successor)
                low[node] = min(low[node], low[successor])
            elif successor in on:
                low[node] = min(low[node], index[successor])
        if low[node] == index[node]:
            part = []
            while True:
                member = stack.pop()
                on.discard(member)
                part.append(member)
                if member == node:
                    break
            if len(part) > 1:
                circles.append(sorted(part))
    for node in sorted(graph):
        if node not in index:
            visit(node)
    return circles


def test_no_modules_import_each_other_in_a_circle():
    """Not even through an import inside a function: a circle means two modules that are one thing, or a thing
    that belongs in a third."""
    assert import_circles(import_graph()) == [], import_circles(import_graph())


def test_a_circle_is_seen():
    assert import_circles({'a': {'b'}, 'b': {'c'}, 'c': {'a'}, 'd': {'a'}}) == [['a', 'b', 'c']]
    assert import_circles({'a': {'b'}, 'b': set()}) == []


def test_the_layering_is_seen_by_the_checks():
    """The checks above can fail: a control module importing the simulator, and a core importing rospy,
    are caught."""
    assert layer('closed_loop.control.navigation.navigator') == 'control'
    assert layer('closed_loop.sim.sensors.lidar') == 'sim'
    assert layer('closed_loop.settings') == 'helpers'
    assert layer('closed_loop.sweep') == 'batch'
    assert 'sim' not in ALLOWED['control'] and 'controllers' not in ALLOWED['sim']
    assert is_ros('rospy') and is_ros('sensor_msgs.msg') and not is_ros('numpy')


@pytest.mark.parametrize('module', sorted(modules()))
def test_no_module_is_over_400_lines(module):
    with open(modules()[module]) as f:
        lines = sum(1 for _ in f)
    assert lines <= MAX_MODULE_LINES, '%s: %d lines (at most %d): split it where it holds two things' % (
        module, lines, MAX_MODULE_LINES)


def test_every_module_imports():
    """Every module of the package imports (the nodes too, where rospy is installed): a stale import after a
    move fails here, not in a graph."""
    import importlib
    try:
        import rospy  # noqa: F401
        has_ros = True
    except ImportError:
        has_ros = False
    failed = {}
    for module in sorted(modules()):
        if layer(module) == 'nodes' and not has_ros:
            continue
        try:
            importlib.import_module(module)
        except Exception as error:      # any failure to import is the finding
            failed[module] = '%s: %s' % (type(error).__name__, error)
    assert not failed, failed


def test_the_benchmarks_and_tools_import_what_the_package_has():
    """Every ``from closed_loop... import name`` of the benchmarks and the tools names a module or an attribute
    the package has: a benchmark is run by hand (``make bench``), so a stale import after a move fails here."""
    import importlib.util
    root = os.path.dirname(SRC)
    missing = []
    for folder in ('test/bench', 'tools'):
        for name in sorted(os.listdir(os.path.join(root, folder))):
            if not name.endswith('.py'):
                continue
            with open(os.path.join(root, folder, name)) as f:
                tree = ast.parse(f.read())
            for node in ast.walk(tree):
                if isinstance(node, ast.ImportFrom) and (node.module or '').split('.')[0] == PACKAGE:
                    if layer(node.module) == 'nodes':
                        continue
                    module = importlib.import_module(node.module)
                    for alias in node.names:
                        if not hasattr(module, alias.name) and \
                                importlib.util.find_spec('%s.%s' % (node.module, alias.name)) is None:
                            missing.append('%s/%s: %s.%s' % (folder, name, node.module, alias.name))
    assert not missing, missing
