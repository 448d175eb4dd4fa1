"""Packaging: what catkin installs is complete (every node script, every Python package)."""
import os
import re

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
