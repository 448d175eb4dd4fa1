"""Gazebo worlds (``.world``, ``.sdf``) as this package's worlds: their static shapes become obstacles.

Read: every ``<model>`` of the world, nested models, and ``<include>``d models (``model://NAME`` found on
``GAZEBO_MODEL_PATH``, as Gazebo finds it: ``NAME/model.config`` names the SDF file), their ``<link>``s and the
``<collision>`` geometry of each: ``box``, ``cylinder``, ``sphere`` and ``mesh`` (``model://``, ``file://`` or
a path beside the model, with its ``scale``). Poses (``<pose>x y z roll pitch yaw</pose>``) are composed from
the world down to each collision. A box or cylinder standing upright is a box or cylinder of the same size at
the same place, a sphere the upright cylinder round it; a mesh, and a box or cylinder tilted off the upright,
stand as the boxes of their footprint (``closed_loop.sim.mesh_footprint``: seen from above between the floor
and the overhead, in 5 cm cells). Both approximations are named in the world's ``left_out`` list. Left out,
and named there too: plugins, actors, models not found, geometry of another kind (a heightmap, a plane other
than the ground), and poses ``relative_to`` another frame. The ground plane and the sun (Gazebo's usual
includes) are the ground and the light this package has already.

Free of ROS. Returns the data of a world file (``closed_loop.sim.world`` checks it as it checks one) and the
footprints' boxes beside it.
"""
import math
import os
import xml.etree.ElementTree as ET

import numpy

from closed_loop.sim import mesh_footprint, occupancy_map

SUFFIXES = ('.world', '.sdf')
#: Includes that are not obstacles: Gazebo's own ground and light.
KNOWN_SCENERY = ('ground_plane', 'sun')
#: Include depth past which a model that includes itself is refused.
MAX_DEPTH = 16
#: Roll or pitch below this (rad) counts as upright.
UPRIGHT_RAD = 1e-9
DEFAULT_COLOR = [0.5, 0.5, 0.5, 1.0]
#: The geometry read, and its numbers: (element, count).
SIZES = {'box': (('size', 3),), 'cylinder': (('radius', 1), ('length', 1)), 'sphere': (('radius', 1),),
         'plane': (('normal', 3),)}
#: The most shapes a Gazebo world may give (as a world file's obstacles).
MAX_OBSTACLES = 2000


def is_gazebo_world(path):
    return os.fspath(path).lower().endswith(SUFFIXES)


def pose_matrix(text):
    """The 4x4 transform of an SDF pose, 'x y z roll pitch yaw' (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    values = [float(v) for v in (text or '').split()] or [0.0] * 6
    if len(values) != 6 or not all(math.isfinite(v) for v in values):
        raise ValueError('a pose of six finite numbers (x y z roll pitch yaw), got %r' % text)
    x, y, z, roll, pitch, yaw = values
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw),
                              math.sin(yaw))
    m = numpy.eye(4)
    m[:3, :3] = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                 [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                 [-sp, cp * sr, cp * cr]]
    m[:3, 3] = x, y, z
    return m


class Reader:
    """One world file read into obstacles (:meth:`world_data`); ``fail(what, got)`` raises the caller's error."""

    def __init__(self, path, fail, model_path=None):
        self.path = os.path.abspath(path)
        self.fail = fail
        self.model_path = [p for p in (model_path if model_path is not None else
                                       os.environ.get('GAZEBO_MODEL_PATH', '')).split(os.pathsep) if p]
        self.obstacles, self.left_out, self.names, self.footprints = [], [], {}, []

    def world_data(self, text):
        try:
            root = ET.fromstring(text)
        except ET.ParseError as error:
            self.fail('SDF (XML)', 'XML that does not parse (%s)' % error)
        world = root.find('world') if root.tag == 'sdf' else None
        if world is None:
            self.fail('an SDF world (<sdf><world>...)', '<%s>' % root.tag)
        # A world Gazebo saved holds where each model stood then in its <state>, which Gazebo applies over the
        # models' own poses when it loads the world.
        self.state = {m.get('name'): m for m in world.findall('state/model') if m.find('pose') is not None}
        for element in world:
            if element.tag == 'model':
                self._model(element, numpy.eye(4), element.get('name', 'model'), os.path.dirname(self.path), 0,
                            top=True)
            elif element.tag == 'include':
                self._include(element, numpy.eye(4), '', 0, top=True)
            elif element.tag in ('plugin', 'actor', 'population'):
                self.left_out.append('%s %s' % (element.tag, element.get('name') or element.get('filename') or ''))
        return {'name': world.get('name') or os.path.splitext(os.path.basename(self.path))[0],
                'description': 'Gazebo world %s' % self.path, 'obstacles': self.obstacles}

    # -- models --------------------------------------------------------------------------------------
    def _placed(self, element, name, top):
        """The pose of a model or include ``element`` called ``name``: the world's <state> of it for one of the
        world's own (``top``), else its own."""
        return self._pose(self.state[name] if top and name in self.state else element, name)

    def _pose(self, element, name):
        pose = element.find('pose')
        if pose is not None and pose.get('relative_to'):
            self.left_out.append('%s: pose relative_to %s (taken relative to its parent)' % (name, pose.get('relative_to')))
        try:
            return pose_matrix(pose.text if pose is not None else '')
        except ValueError:
            self.fail('%s: a pose of six finite numbers (x y z roll pitch yaw)' % name, pose.text)

    def _model(self, model, parent, name, folder, depth, top=False, placed=None):
        here = parent @ (placed if placed is not None else self._placed(model, name, top))
        static = (model.findtext('static') or 'false').strip() in ('true', '1')
        if not static and (model.find('link') is not None):
            self.left_out.append('%s: not static (held where it stands)' % name)
        for element in model:
            if element.tag == 'model':
                self._model(element, here, '%s/%s' % (name, element.get('name', 'model')), folder, depth)
            elif element.tag == 'include':
                self._include(element, here, name + '/', depth)
            elif element.tag == 'link':
                link = here @ self._pose(element, name)
                for collision in element.findall('collision'):
                    self._collision(collision, link, '%s/%s/%s' % (name, element.get('name', 'link'),
                                                                    collision.get('name', 'collision')), folder)
            elif element.tag == 'plugin':
                self.left_out.append('%s: plugin %s' % (name, element.get('name') or element.get('filename')))

    def _include(self, include, parent, prefix, depth, top=False):
        uri = (include.findtext('uri') or '').strip()
        model_name = uri[len('model://'):] if uri.startswith('model://') else uri
        if model_name in KNOWN_SCENERY:
            return
        if depth >= MAX_DEPTH:
            self.fail('includes nested at most %d deep (a model that includes itself?)' % MAX_DEPTH, uri)
        found = self._model_file(uri)
        if found is None:
            self.left_out.append('%s: model not found on GAZEBO_MODEL_PATH' % uri)
            return
        sdf, folder = found
        try:
            root = ET.parse(sdf).getroot()
        except (ET.ParseError, OSError) as error:
            self.fail('%s: a readable SDF model: %s' % (sdf, error), uri)
        model = root.find('model') if root.tag == 'sdf' else root if root.tag == 'model' else None
        if model is None:
            self.fail('%s: an SDF model (<sdf><model>...)' % sdf, uri)
        name = prefix + (include.findtext('name') or model.get('name') or model_name).strip()
        static = include.findtext('static')
        if static is not None and model.find('static') is None:
            ET.SubElement(model, 'static').text = static
        # An include's pose (or the world's state of it) stands in for the model's own, as in Gazebo.
        given = include.find('pose') is not None or (top and name in self.state)
        self._model(model, parent, name, folder, depth + 1,
                    placed=self._placed(include, name, top) if given else self._pose(model, name))

    def _model_file(self, uri):
        """(the model's SDF file, its folder) for ``model://NAME`` on the model path, or None."""
        if not uri.startswith('model://'):
            return None
        name = uri[len('model://'):].strip('/')
        for base in self.model_path:
            folder = os.path.realpath(os.path.join(base, name))
            if not folder.startswith(os.path.realpath(base) + os.sep):
                self.fail('a model inside its folder on GAZEBO_MODEL_PATH', uri)
            config = os.path.join(folder, 'model.config')
            if os.path.isfile(config):
                try:
                    files = [e.text.strip() for e in ET.parse(config).getroot().iter('sdf') if e.text]
                except ET.ParseError as error:
                    self.fail('%s: a readable model.config: %s' % (config, error), uri)
                for sdf in files[-1:] or ['model.sdf']:
                    return os.path.join(folder, sdf), folder
        return None

    # -- shapes ----------------------------------------------------------------------------------------
    def _collision(self, collision, link, name, folder):
        m = link @ self._pose(collision, name)
        geometry = collision.find('geometry')
        shape = geometry[0] if geometry is not None and len(geometry) else None
        kind = shape.tag if shape is not None else None
        upright = abs(m[2, 0]) < UPRIGHT_RAD and abs(m[2, 1]) < UPRIGHT_RAD
        yaw = math.atan2(m[1, 0], m[0, 0])
        if kind == 'mesh':
            return self._footprint(name, m, self._mesh_triangles(shape, name, folder), 'a mesh')
        if kind not in SIZES:
            self.left_out.append('%s: %s geometry' % (name, kind or 'no'))
            return None
        try:
            sizes = {key: _numbers(shape.findtext(key) or ('0 0 1' if key == 'normal' else ''), count, key != 'normal')
                     for key, count in SIZES[kind]}
        except ValueError:
            self.fail('%s: %s geometry with its sizes as numbers > 0' % (name, kind),
                      ' '.join(ET.tostring(shape, encoding='unicode').split()))
        if kind == 'plane':
            if not (upright and abs(m[2, 3]) < UPRIGHT_RAD and sizes['normal'] == [0.0, 0.0, 1.0]):
                self.left_out.append('%s: a plane other than the ground' % name)
            return None
        if kind == 'sphere':
            radius = sizes['radius'][0]
            self.left_out.append('%s: a sphere (the cylinder round it)' % name)
            return self._add(name, 'cylinder', m[:3, 3], 0.0, (radius, 2 * radius))
        if kind == 'box':
            if upright:
                return self._add(name, 'box', m[:3, 3], yaw, sizes['size'])
            return self._footprint(name, m, mesh_footprint.box_triangles(sizes['size']), 'a tilted box')
        radius, length = sizes['radius'][0], sizes['length'][0]
        if upright:
            return self._add(name, 'cylinder', m[:3, 3], 0.0, (radius, length))
        return self._footprint(name, m, mesh_footprint.cylinder_triangles(radius, length), 'a tilted cylinder')

    def _footprint(self, name, m, triangles, what):
        """The boxes of the footprint of ``triangles`` placed by ``m`` (``what`` they are, for left_out)."""
        boxes = mesh_footprint.footprint_boxes(triangles, m, name, self.fail)
        if not boxes:
            self.left_out.append('%s: %s, all of it below %g m or above %g m (no obstacle)' % (
                name, what, mesh_footprint.FLOOR_M, mesh_footprint.OVERHEAD_M))
            return
        self.left_out.append('%s: %s (its footprint, %d box%s of %g m cells)' % (
            name, what, len(boxes), '' if len(boxes) == 1 else 'es', mesh_footprint.CELL_M))
        for box in boxes:
            box.update(type='box', color=tuple(DEFAULT_COLOR))
        self.footprints += boxes
        if len(self.footprints) > occupancy_map.MAX_BOXES:
            self.fail('footprints of at most %d boxes in all' % occupancy_map.MAX_BOXES, '%d' % len(self.footprints))

    def _mesh_triangles(self, mesh, name, folder):
        from closed_loop import description
        uri = (mesh.findtext('uri') or '').strip()
        if uri.startswith('model://'):
            model, _, rest = uri[len('model://'):].partition('/')
            found = self._model_file('model://' + model)
            if found is None:
                self.fail('%s: a mesh whose model is on GAZEBO_MODEL_PATH' % name, uri)
            path = os.path.realpath(os.path.join(found[1], rest))
            if not path.startswith(os.path.realpath(found[1]) + os.sep):
                self.fail('%s: a mesh inside its model\'s folder' % name, uri)
        elif uri.startswith('file://') or os.path.isabs(uri):
            path = uri[len('file://'):] if uri.startswith('file://') else uri
        else:
            path = os.path.join(folder, uri)
        scale = tuple(_numbers(mesh.findtext('scale') or '1 1 1', 3))
        try:
            description.check_mesh(path, uri, self.path)
        except description.DescriptionError as error:
            self.fail('%s: a mesh' % name, str(error))
        try:
            return mesh_footprint.read_triangles(path, scale)
        except ValueError as error:
            self.fail('%s: %s' % (name, error), path)

    def _add(self, name, kind, position, yaw, size):
        if len(self.obstacles) >= MAX_OBSTACLES:
            self.fail('at most %d shapes (obstacles)' % MAX_OBSTACLES, 'more')
        taken = self.names.get(name, 0)
        self.names[name] = taken + 1
        name = name if not taken else '%s#%d' % (name, taken + 1)
        position = [float(v) for v in position]
        if kind == 'box':
            obstacle = {'name': name, 'type': 'box', 'position': position, 'size': [float(v) for v in size],
                        'yaw': float(yaw)}
        else:
            obstacle = {'name': name, 'type': 'cylinder', 'position': position, 'radius': float(size[0]),
                        'height': float(size[1])}
        obstacle['color'] = list(DEFAULT_COLOR)
        self.obstacles.append(obstacle)
        return obstacle


def _numbers(text, count, positive=True):
    values = [float(v) for v in (text or '').split()]
    if len(values) != count or not all(math.isfinite(v) and (v > 0 or not positive) for v in values):
        raise ValueError('%d numbers%s, got %r' % (count, ' > 0' if positive else '', text))
    return values


def world_data(path, text, error_class, model_path=None):
    """(the data of a world file, for ``closed_loop.sim.world.parse_world``; what was left out or approximated;
    the boxes of the meshes' and tilted shapes' footprints, as obstacles' fields) from the Gazebo world ``text``
    read from ``path``; what is wrong raises ``error_class(path, field, expected, got)`` (a
    :class:`closed_loop.yaml_check.FileError`)."""
    def fail(what, got):
        raise error_class(path, '(Gazebo world)', what, got)
    reader = Reader(path, fail, model_path)
    return reader.world_data(text), tuple(reader.left_out), reader.footprints
