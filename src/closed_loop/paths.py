"""Where the package's data lives (``worlds/``, ``urdf/``, ``config/``): the repository in a source tree or a
devel space, ``share/closed_loop`` in an install space. Free of ROS messages; rospkg (a plain library) is
asked only when the source tree is not where this module stands."""
import functools
import os

PACKAGE = 'closed_loop'


@functools.lru_cache(maxsize=None)
def package_root():
    """The folder that holds ``package.xml``, ``worlds/``, ``urdf/`` and ``config/``."""
    here = os.path.dirname(os.path.abspath(__file__))
    source = os.path.normpath(os.path.join(here, '..', '..'))          # src/closed_loop/ -> the repository
    if os.path.isfile(os.path.join(source, 'package.xml')):
        return source
    try:
        import rospkg
    except ImportError:
        return source
    try:
        return rospkg.RosPack().get_path(PACKAGE)
    except rospkg.ResourceNotFound:     # not on ROS_PACKAGE_PATH: the source guess, whose errors name it
        return source


def data_path(*parts):
    """A path under :func:`package_root`, e.g. ``data_path('worlds')``."""
    return os.path.join(package_root(), *parts)
