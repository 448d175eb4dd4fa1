"""Robot profiles read without ROS: ``urdf/NAME.urdf`` and ``config/robots/NAME.yaml``, the same two files
``robot:=NAME`` loads in the launch files, for the in-process runs (episodes, benchmarks, the world
generator). The YAML maps each node's name (``sim``, ``avoid_obstacles``, ...) to its ``~parameters``.
"""
import os
from dataclasses import dataclass, field

from closed_loop import robot_model
from closed_loop.paths import package_root
from closed_loop.sim.world_robots import PROFILE_NAME
from closed_loop.yaml_check import FileError, load_yaml, read_text

MAX_PROFILE_BYTES = 64 * 1024

PACKAGE_ROOT = package_root()


class ProfileError(FileError):
    """A robot profile is unknown or unusable; the message names the file and what was wrong."""


@dataclass(frozen=True)
class Profile:
    """One robot profile: its name, its URDF text, and {node name: {parameter: value}}."""
    name: str
    urdf: str
    params: dict = field(default_factory=dict)

    def node_params(self, node):
        """The profile's ``~parameters`` for ``node`` (the simulator is ``sim``), a new dict."""
        return dict(self.params.get(node) or {})

    @property
    def footprint(self):
        return robot_model.footprint(self.urdf, source='urdf/%s.urdf' % self.name)

    def laser_pose(self, scan_frame):
        return robot_model.frame_pose_2d(self.urdf, scan_frame, source='urdf/%s.urdf' % self.name)


def available_profiles(root=PACKAGE_ROOT):
    """The profile names that have both files under ``root``."""
    config = os.path.join(root, 'config', 'robots')
    names = [f[:-5] for f in os.listdir(config) if f.endswith('.yaml')] if os.path.isdir(config) else []
    return sorted(n for n in names if os.path.isfile(os.path.join(root, 'urdf', n + '.urdf')))


def load_profile(name, root=PACKAGE_ROOT):
    """The :class:`Profile` called ``name`` (a name, never a path)."""
    known = ', '.join(available_profiles(root))
    if not isinstance(name, str) or not PROFILE_NAME.match(name):
        raise ProfileError('robot profile', 'name', 'a name of letters, digits and _ (one of %s)' % known, name)
    urdf_path = os.path.join(root, 'urdf', name + '.urdf')
    yaml_path = os.path.join(root, 'config', 'robots', name + '.yaml')
    if not os.path.isfile(urdf_path) or not os.path.isfile(yaml_path):
        raise ProfileError('robot profile', 'name', 'one of %s (urdf/NAME.urdf and config/robots/NAME.yaml)'
                           % known, name)
    params = load_yaml(read_text(yaml_path, MAX_PROFILE_BYTES, ProfileError, 'robot profile'), yaml_path,
                       ProfileError) or {}
    if not isinstance(params, dict) or not all(isinstance(v, dict) or v is None for v in params.values()):
        raise ProfileError(yaml_path, '(file)', 'a mapping of node names to their parameters', params)
    return Profile(name, robot_model.read_urdf(urdf_path), params)
