"""A catkin workspace of yours as the place a graph episode's controller comes from: ``controller: {launch:
my_pkg/my.launch, workspace: /home/me/ws_pr}`` runs the launch file of ``my_pkg`` as that workspace has it, so
that ``compare`` can hold the same launch file from two workspaces (before and after a change) side by side.

The graph's environment is the worker's, with the workspace put first, as sourcing its ``setup.bash`` would
(but without a shell: nothing a user types reaches one): its prefix (``devel/`` or ``install/``, whichever has
catkin's ``.catkin`` marker, ``devel/`` first) at the front of ``CMAKE_PREFIX_PATH`` and each of its folders
catkin's own ``_setup_util.py`` names (``ENV_VAR_SUBFOLDERS``: ``lib`` for ``LD_LIBRARY_PATH``, ``bin`` for
``PATH``, its Python folder for ``PYTHONPATH`` ...) at the front of its variable, and its source folders (what
``.catkin`` lists; ``share`` for an install space) at the front of ``ROS_PACKAGE_PATH``, as ros_environment's
hook does. Only this package itself stays ahead of the workspace (in ``ROS_PACKAGE_PATH`` and ``PYTHONPATH``),
so that both sides of a comparison are judged by the same simulator and judge, this worker's, even where the
workspace holds a copy of ``closed_loop`` of its own. Free of ROS.
"""
import importlib.util
import os

#: Where a workspace's prefix (the folder with ``.catkin``) is looked for, in this order.
PREFIXES = ('devel', 'install', '')
MARKER = '.catkin'


class WorkspaceError(ValueError):
    """A path that is not a built catkin workspace (the message names it and what is missing)."""


def prefix_of(path):
    """The prefix of the catkin workspace at ``path`` (the workspace, or its devel or install space itself)."""
    if not isinstance(path, str) or not path:
        raise WorkspaceError('expected the path of a catkin workspace, got %r' % (path,))
    path = os.path.abspath(os.path.expanduser(path))
    if not os.path.isdir(path):
        raise WorkspaceError('%s: no such folder' % path)
    for sub in PREFIXES:
        if os.path.isfile(os.path.join(path, sub, MARKER)):
            return os.path.normpath(os.path.join(path, sub))
    raise WorkspaceError('%s is not a built catkin workspace: no devel/.catkin or install/.catkin (run catkin_make '
                         'in it first)' % path)


def subfolders(prefix):
    """catkin's ``ENV_VAR_SUBFOLDERS`` of the workspace at ``prefix``, from its own ``_setup_util.py`` (imported as
    a module, which defines it and does nothing else; its setup.bash runs it as a program)."""
    source = os.path.join(prefix, '_setup_util.py')
    try:
        found = importlib.util.spec_from_file_location('_catkin_setup_util', source)
        module = importlib.util.module_from_spec(found)
        found.loader.exec_module(module)
        return dict(module.ENV_VAR_SUBFOLDERS)
    except (OSError, SyntaxError, ImportError, AttributeError) as error:
        raise WorkspaceError('%s: cannot read catkin\'s setup utility (%s)' % (source, error))


def package_paths(prefix):
    """The folders a workspace adds to ``ROS_PACKAGE_PATH``: the source folders its ``.catkin`` lists, or its
    ``share`` folder (an install space's ``.catkin`` is empty)."""
    with open(os.path.join(prefix, MARKER)) as f:
        listed = [p for p in f.read().strip().split(';') if p]
    return listed or [os.path.join(prefix, 'share')]


def _first(env, name, paths):
    """``env[name]`` with ``paths`` at its front, each once."""
    rest = [p for p in env.get(name, '').split(os.pathsep) if p and p not in paths]
    env[name] = os.pathsep.join(list(paths) + rest)


def environment(workspace, env, package_root, python_root):
    """``env`` (not changed) with the workspace at ``workspace`` first, as the module's docstring says, behind
    only this package (``package_root``, its folder with ``package.xml``; ``python_root``, where its Python
    package is imported from)."""
    prefix = prefix_of(workspace)
    env = dict(env)
    _first(env, 'CMAKE_PREFIX_PATH', [prefix])
    for name, subs in sorted(subfolders(prefix).items()):
        if name == 'CMAKE_PREFIX_PATH':
            continue
        subs = subs if isinstance(subs, list) else [subs]
        _first(env, name, [p for p in (os.path.join(prefix, s) for s in subs) if os.path.exists(p)])
    _first(env, 'ROS_PACKAGE_PATH', package_paths(prefix))
    _first(env, 'ROS_PACKAGE_PATH', [package_root])
    _first(env, 'PYTHONPATH', [python_root])
    return env
