# Installed by catkin (catkin_python_setup in CMakeLists.txt); do not run directly.
from catkin_pkg.python_setup import generate_distutils_setup
from setuptools import setup

setup(**generate_distutils_setup(
    packages=['closed_loop', 'closed_loop.batch', 'closed_loop.control', 'closed_loop.control.navigation',
              'closed_loop.controllers', 'closed_loop.nodes', 'closed_loop.sim', 'closed_loop.sim.sensors'],
    package_dir={'': 'src'},
))
