"""Robot profiles read without rospy: ``urdf/NAME.urdf`` and ``config/robots/NAME.yaml``, the same two files
``robot:=NAME`` loads in the launch files, for the in-process runs (episodes, benchmarks, the world
generator). The YAML maps each node's name (``sim``, ``avoid_obstacles``, ...) to its ``~parameters``.

A profile of the user's is a YAML file anywhere (``robot:=/path/my_robot.yaml``, ``$(find my_pkg)/...`` in a
launch file, ``my_pkg/config/my_robot.yaml`` in a sweep): the same mapping, and ``description``, which names the
robot's description and its xacro args::

    description:
      file: $(find my_robot_description)/urdf/my_robot.urdf.xacro   # or package://..., a path (relative: to here)
      xacro_args: {lidar: true}
    sim: {scan_frame: laser, left_wheel_joints: left_wheel_joint, right_wheel_joints: right_wheel_joint}

The description is expanded and its meshes checked (``closed_loop.description``) when the profile is loaded.
"""
import os
import sys
from dataclasses import dataclass, field

from closed_loop import cli, description, robot_model, robot_names
from closed_loop.paths import package_root
from closed_loop.sim.world_robots import PROFILE_NAME
from closed_loop.yaml_check import FileError, load_yaml, read_text

MAX_PROFILE_BYTES = 64 * 1024
#: The key of a user's profile that names its description (not a node).
DESCRIPTION_KEY = 'description'
DESCRIPTION_KEYS = ('file', 'xacro_args')

PACKAGE_ROOT = package_root()


class ProfileError(FileError):
    """A robot profile is unknown or unusable; the message names the file and what was wrong."""


@dataclass(frozen=True)
class Profile:
    """One robot profile: its name (a user's: its file's path), its URDF text, {node name: {parameter: value}}, and
    where the URDF came from (for errors)."""
    name: str
    urdf: str
    params: dict = field(default_factory=dict)
    source: str = ''
    #: The robot's parts (``closed_loop.robot_names``) as its description has them, where a profile of the
    #: user's does not name them ({} for this package's: they name theirs, or use the defaults).
    found: dict = field(default_factory=dict)

    @property
    def description_source(self):
        return self.source or 'urdf/%s.urdf' % self.name

    def node_params(self, node):
        """The profile's ``~parameters`` for ``node`` (the simulator is ``sim``), a new dict: with the parts
        found in the description that the profile does not name (the simulator's, and a controller's
        ``scan_frame``)."""
        params = dict(self.params.get(node) or {})
        for key, value in self.found.items():
            if node == 'sim' or key == 'scan_frame':
                params.setdefault(key, value)
        return params

    @property
    def footprint(self):
        return robot_model.footprint(self.urdf, source=self.description_source)

    def laser_pose(self, scan_frame):
        return robot_model.frame_pose_2d(self.urdf, scan_frame, source=self.description_source)


def available_profiles(root=PACKAGE_ROOT):
    """The profile names that have both files under ``root``."""
    config = os.path.join(root, 'config', 'robots')
    names = [f[:-5] for f in os.listdir(config) if f.endswith('.yaml')] if os.path.isdir(config) else []
    return sorted(n for n in names if os.path.isfile(os.path.join(root, 'urdf', n + '.urdf')))


def is_profile_file(name):
    """True if ``name`` names a profile file of the user's rather than one of this package's profiles."""
    return isinstance(name, str) and name.endswith(('.yaml', '.yml'))


def load_profile(name, root=PACKAGE_ROOT):
    """The :class:`Profile` called ``name``, one of this package's, or of the user's profile file ``name`` (a
    path, ``$(find PKG)/path`` or ``PKG/path``)."""
    if is_profile_file(name):
        return load_profile_file(name)
    known = ', '.join(available_profiles(root))
    if not isinstance(name, str) or not PROFILE_NAME.match(name):
        raise ProfileError('robot profile', 'name', 'a name of letters, digits and _ (one of %s)' % known, name)
    urdf_path = os.path.join(root, 'urdf', name + '.urdf')
    yaml_path = os.path.join(root, 'config', 'robots', name + '.yaml')
    if not os.path.isfile(urdf_path) or not os.path.isfile(yaml_path):
        raise ProfileError('robot profile', 'name', 'one of %s (urdf/NAME.urdf and config/robots/NAME.yaml)'
                           % known, name)
    return Profile(name, robot_model.read_urdf(urdf_path), _node_params(yaml_path))


def _node_params(yaml_path, described=False):
    params = load_yaml(read_text(yaml_path, MAX_PROFILE_BYTES, ProfileError, 'robot profile'), yaml_path,
                       ProfileError) or {}
    if not isinstance(params, dict) or not all(isinstance(v, dict) or v is None for k, v in params.items()
                                               if not (described and k == DESCRIPTION_KEY)):
        raise ProfileError(yaml_path, '(file)', 'a mapping of node names to their parameters', params)
    return params


def load_profile_file(reference):
    """The :class:`Profile` of the user's profile file ``reference`` (see the module's doc): its description
    expanded and checked, meshes and all; the profile's name is the file's absolute path."""
    try:
        path = description.resolve(reference, 'robot profile', package_relative=True)
    except description.DescriptionError as error:
        raise ProfileError('robot profile', 'file', 'a profile file (%s)' % error, reference) from None
    if not os.path.isfile(path):
        raise ProfileError('robot profile', 'file', 'an existing profile file (a path, $(find PKG)/path or '
                           'PKG/path)', reference)
    params = _node_params(path, described=True)
    spec = params.pop(DESCRIPTION_KEY, None)
    if not isinstance(spec, dict) or not isinstance(spec.get('file'), str) or set(spec) - set(DESCRIPTION_KEYS):
        raise ProfileError(path, DESCRIPTION_KEY, "a mapping with 'file' (the URDF or xacro: $(find PKG)/path, "
                           "package://PKG/path or a path) and, for a xacro, 'xacro_args'", spec)
    args = spec.get('xacro_args') or {}
    if not isinstance(args, dict) or not all(isinstance(v, (str, int, float, bool)) for v in args.values()):
        raise ProfileError(path, DESCRIPTION_KEY + '.xacro_args', 'a mapping of arg names to values', args)
    source = description.resolve(spec['file'], path, base_dir=os.path.dirname(path))
    urdf = description.expand(source, args)
    description.meshes(urdf, source)                 # every mesh there and usable, or nothing runs
    named = {k: v for k, v in (params.get('sim') or {}).items() if k in robot_names.DEFAULTS}
    found = {k: v for k, v in robot_names.parts(urdf, named, source).items() if k not in named}
    return Profile(path, urdf, params, source, found)


def main(argv=None):
    """``robot_description PROFILE``: the URDF of a robot profile on standard output, as
    ``<param name="robot_description" command="..."/>`` takes it (launch/robot_profile.launch); what is wrong,
    one line on standard error and exit status 1."""
    parser = cli.parser('robot_description', 'Print the URDF of a robot profile: one of this package\'s names, or '
                        'a profile file of yours (a path, $(find PKG)/path or PKG/path), its xacro expanded and its '
                        'meshes checked.')
    parser.add_argument('profile', help='a profile name (%s) or a profile file (.yaml)'
                        % ', '.join(available_profiles()))
    args = parser.parse_args(argv)
    try:
        text = load_profile(args.profile).urdf
    except (ProfileError, robot_model.RobotModelError) as error:
        sys.stderr.write('robot_description: %s\n' % error)
        return 1
    sys.stdout.write(text)
    return 0
