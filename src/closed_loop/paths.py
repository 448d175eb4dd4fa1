"""Where the package's data lives (``worlds/``, ``urdf/``, ``config/``): the repository in a source tree or a
devel space, ``share/closed_loop`` in an install space. Free of ROS: an install space is found the way
catkin lays it out, through ``CMAKE_PREFIX_PATH`` (set by the workspace's ``setup.bash``) and
``ROS_PACKAGE_PATH``."""
import functools
import os

PACKAGE = 'closed_loop'


def _candidates(environ):
    here = os.path.dirname(os.path.abspath(__file__))
    yield os.path.normpath(os.path.join(here, '..', '..'))          # src/closed_loop/ -> the repository
    for prefix in filter(None, environ.get('CMAKE_PREFIX_PATH', '').split(os.pathsep)):
        yield os.path.join(prefix, 'share', PACKAGE)
    for folder in filter(None, environ.get('ROS_PACKAGE_PATH', '').split(os.pathsep)):
        yield os.path.join(folder, PACKAGE)
        yield folder


@functools.lru_cache(maxsize=None)
def package_root():
    """The folder that holds this package's ``package.xml``, ``worlds/``, ``urdf/`` and ``config/`` (the
    source tree's guess where none is found, so that errors name a real place)."""
    candidates = list(_candidates(os.environ))
    return next((folder for folder in candidates if _names_us(folder)), candidates[0])


def _names_us(folder):
    """True if ``folder/package.xml`` is this package's manifest."""
    try:
        with open(os.path.join(folder, 'package.xml')) as f:
            return '<name>%s</name>' % PACKAGE in f.read()
    except OSError:
        return False


def data_path(*parts):
    """A path under :func:`package_root`, e.g. ``data_path('worlds')``."""
    return os.path.join(package_root(), *parts)
