"""A robot description from wherever it lives: a URDF or xacro file of any package, with its meshes.

Free of rospy. ``$(find PKG)`` and ``package://PKG/`` are resolved through the ROS package path (rospkg), as
roslaunch, xacro and rviz resolve them. A ``.xacro`` file is expanded by ROS 1's own xacro (pinned,
``requirements.txt``) with its args, as ``<param command="xacro FILE ARG:=VALUE"/>`` would; nothing here
expands a macro. Every ``<mesh>`` (visual and collision) must be a file that pybullet reads as the robot's
geometry: binary STL, OBJ or COLLADA, at most :data:`MAX_MESH_BYTES`. What is wrong is one line naming the
file and what: a description that includes itself, a missing or oversized mesh, an ASCII STL.
"""
import functools
import os
import re
import xml.etree.ElementTree as ET

#: A description (URDF, or the xacro that makes it) larger than this is refused (bytes).
MAX_DESCRIPTION_BYTES = 4 * 1024 * 1024
#: A mesh larger than this is refused (bytes): a collision mesh is a few hundred kB; a scan of a real robot
#: of tens of MB would make every contact check slow.
MAX_MESH_BYTES = 20 * 1024 * 1024
MESH_FORMATS = ('.stl', '.obj', '.dae')
FIND = re.compile(r'^\$\(find ([A-Za-z0-9_]+)\)(/.*)?$')
PACKAGE_URI = re.compile(r'^package://([A-Za-z0-9_]+)(/.*)?$')


class DescriptionError(ValueError):
    """A robot description (its URDF or xacro, a mesh, what the simulator relies on in it) is unusable; the
    message names the source and what is wrong. ``closed_loop.robot_model.RobotModelError`` is this class."""


@functools.lru_cache(maxsize=None)
def _rospack():
    import rospkg
    return rospkg.RosPack()


def package_path(package, source):
    """The folder of ROS package ``package`` on the package path; ``source`` is named when it is not found."""
    import rospkg
    try:
        return _rospack().get_path(package)
    except rospkg.ResourceNotFound:
        raise DescriptionError('%s: no ROS package %r on the package path (ROS_PACKAGE_PATH: %s)' % (
            source, package, os.environ.get('ROS_PACKAGE_PATH') or 'not set')) from None


def resolve(reference, source, base_dir=None, package_relative=False):
    """The absolute path of ``reference``: ``$(find PKG)/rest``, ``package://PKG/rest``, ``file:///path``, an
    absolute path, a path relative to ``base_dir``, or (``package_relative``) ``PKG/rest`` as a sweep writes
    it. ``source`` names where the reference was read, for the error."""
    reference = reference.strip()
    for pattern in (FIND, PACKAGE_URI):
        match = pattern.match(reference)
        if match:
            return inside(package_path(match.group(1), source), (match.group(2) or '').lstrip('/'), reference,
                          source)
    if reference.startswith('file://'):
        return os.path.normpath(reference[len('file://'):])
    if os.path.isabs(reference):
        return os.path.normpath(reference)
    if base_dir is not None:
        return os.path.normpath(os.path.join(base_dir, reference))
    if package_relative and '/' in reference and not os.path.exists(reference):
        package, _, rest = reference.partition('/')
        return inside(package_path(package, source), rest, reference, source)
    return os.path.abspath(reference)


def inside(folder, rest, reference, source):
    """``folder/rest``, refused if ``rest`` leads out of ``folder`` (``..``)."""
    path = os.path.normpath(os.path.join(folder, rest))
    if path != folder and not path.startswith(folder.rstrip(os.sep) + os.sep):
        raise DescriptionError('%s: %s leads out of its package (%s)' % (source, reference, folder))
    return path


def expand(path, args=None):
    """The URDF text of the description file ``path`` (``.xacro``: expanded with ``args``, {name: value})."""
    if not os.path.isfile(path):
        raise DescriptionError('%s: no such robot description file' % path)
    if os.path.getsize(path) > MAX_DESCRIPTION_BYTES:
        raise DescriptionError('%s: %d bytes, over the %d a robot description may have' % (
            path, os.path.getsize(path), MAX_DESCRIPTION_BYTES))
    if not path.endswith('.xacro'):
        if args:
            raise DescriptionError('%s: xacro_args given for a file that is not a .xacro' % path)
        try:
            with open(path, encoding='utf-8') as f:
                return f.read()
        except (OSError, UnicodeDecodeError) as error:
            raise DescriptionError('%s: cannot read the robot description: %s' % (path, error)) from None
    return _xacro(path, tuple(sorted((str(k), _arg_text(v)) for k, v in (args or {}).items())))


def _arg_text(value):
    return str(value).lower() if isinstance(value, bool) else str(value)


def _xacro(path, args):
    import xacro
    try:
        document = xacro.process_file(path, mappings=dict(args))
    except RecursionError:
        raise DescriptionError('%s: its xacro includes itself (or nests includes or macros without end)'
                               % path) from None
    except xacro.XacroException as error:
        where = ' (in %s)' % ' <- '.join(reversed(xacro.filestack)) if getattr(xacro, 'filestack', None) else ''
        raise DescriptionError('%s: xacro: %s%s' % (path, ' '.join(str(error).split()), where)) from None
    except Exception as error:       # (xacro raises what its XML parser and its evaluator raise)
        raise DescriptionError('%s: xacro: %s: %s' % (path, type(error).__name__, ' '.join(str(error).split())))
    finally:
        del getattr(xacro, 'all_includes', [])[:]       # (xacro lists every file it read, for --deps, for good)
    return document.toprettyxml(indent='  ')


def meshes(urdf_text, source):
    """[(the filename as the description writes it, its absolute path, its scale (x, y, z))] of every
    ``<mesh>``, each checked (:func:`mesh_file`)."""
    try:
        robot = ET.fromstring(urdf_text)
    except ET.ParseError as error:
        raise DescriptionError('%s: cannot parse the robot description: %s' % (source, error)) from None
    return [(mesh.get('filename'),) + mesh_file(mesh, source) for mesh in robot.iter('mesh')]


def mesh_file(mesh, source):
    """(absolute path, scale (x, y, z)) of a ``<mesh>`` element, its file checked (:func:`check_mesh`)."""
    name = mesh.get('filename') or ''
    if not (FIND.match(name) or PACKAGE_URI.match(name) or name.startswith('file://') or os.path.isabs(name)):
        raise DescriptionError('%s: mesh %r: expected package://PKG/path, file:///path or an absolute path '
                               '(rviz and the simulator cannot tell what a relative one is relative to)'
                               % (source, name))
    path = resolve(name, source)
    try:
        scale = tuple(float(v) for v in (mesh.get('scale') or '1 1 1').split())
    except ValueError:
        scale = ()
    if len(scale) != 3:
        raise DescriptionError('%s: mesh %r: scale %r: expected three numbers' % (source, name, mesh.get('scale')))
    check_mesh(path, name, source)
    return path, scale


def check_mesh(path, name, source):
    """Refuse a mesh pybullet cannot take as geometry: missing, too large, not STL/OBJ/COLLADA, an ASCII STL."""
    where = '%s: mesh %s' % (source, name if name in (path, 'file://' + path) else '%s (%s)' % (name, path))
    extension = os.path.splitext(path)[1].lower()
    if extension not in MESH_FORMATS:
        raise DescriptionError('%s: expected a .stl, .obj or .dae file' % where)
    try:
        size = os.path.getsize(path)
    except OSError:
        raise DescriptionError('%s: no such file' % where) from None
    if size > MAX_MESH_BYTES:
        raise DescriptionError('%s: %.1f MB, over the %d MB a mesh may have (simplify it, or give a simpler '
                               'collision mesh)' % (where, size / 1e6, MAX_MESH_BYTES // (1024 * 1024)))
    if extension == '.stl':
        with open(path, 'rb') as f:
            head = f.read(84)
        triangles = int.from_bytes(head[80:84], 'little') if len(head) == 84 else -1
        if triangles < 0 or size != 84 + 50 * triangles:
            raise DescriptionError('%s: not a binary STL (%s): pybullet reads binary STL only; save it as '
                                   'binary STL, OBJ or COLLADA' % (where, 'an ASCII one' if head.lstrip()
                                                                   .startswith(b'solid') else 'its size and '
                                                                   'its count of triangles disagree'))


def for_pybullet(urdf_text, source):
    """``urdf_text`` with every mesh's filename made the absolute path of its (checked) file: pybullet knows no
    ROS package path."""
    paths = {name: path for name, path, _ in meshes(urdf_text, source)}
    if not paths:
        return urdf_text
    robot = ET.fromstring(urdf_text)
    for mesh in robot.iter('mesh'):
        mesh.set('filename', paths[mesh.get('filename')])
    return ET.tostring(robot, encoding='unicode')


def mesh_points(path, scale):
    """The vertices (n, 3) of the mesh at ``path``, scaled, in its own frame, as pybullet takes it for
    collisions (through its URDF importer, as the robot is loaded); read once per file as it is now."""
    stat = os.stat(path)
    return _mesh_points(path, tuple(scale), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=64)
def _mesh_points(path, scale, _mtime_ns, _size):
    import numpy as np
    import pybullet
    import tempfile
    client = pybullet.connect(pybullet.DIRECT)
    try:
        with tempfile.NamedTemporaryFile('w', suffix='.urdf', prefix='closed_loop-mesh-') as f:
            f.write('<robot name="mesh"><link name="mesh"><inertial><mass value="1"/><inertia ixx="1" ixy="0" '
                    'ixz="0" iyy="1" iyz="0" izz="1"/></inertial><collision><geometry><mesh filename=%s '
                    'scale="%r %r %r"/></geometry></collision></link></robot>'
                    % ((_xml_attr(path),) + tuple(scale)))
            f.flush()
            body = pybullet.loadURDF(f.name, physicsClientId=client)
        count, vertices = pybullet.getMeshData(body, -1, physicsClientId=client)
    except pybullet.error as error:
        raise DescriptionError('%s: pybullet cannot read this mesh: %s' % (path, error)) from None
    finally:
        pybullet.disconnect(physicsClientId=client)
    if not count:
        raise DescriptionError('%s: the mesh has no vertices' % path)
    return np.array(vertices, dtype=float).reshape(-1, 3)


def _xml_attr(text):
    from xml.sax.saxutils import quoteattr
    return quoteattr(text)
