"""A mesh standing in a world (or a shape tilted off the upright), as the boxes of its footprint.

Every obstacle of a world is a vertical prism (``closed_loop.sim.shapes``): that is what the planar LIDAR, the
clearance, the pictures and rviz share with the physics. A mesh is made one as a map is: its triangles (read by
trimesh, COLLADA through pycollada) are placed in the world, cut to the heights a ground robot meets
(:data:`FLOOR_M` to :data:`OVERHEAD_M`: a floor slab, a doormat or a ceiling is no obstacle), and seen from
above on cells of :data:`CELL_M`. A cell is solid where a triangle touches it (a wall's faces, upright and so seen
edge-on, are the lines of cells they cross) or where its centre is inside the mesh: inside as the faces' outward
normals tell it, along each row of cells through cross-sections of the mesh between its vertices' heights (a row
across a mesh that is not closed there keeps only the cells its faces touch; ``closed_loop.sim.footprint_kernel``
does both). The solid cells are merged into boxes as a map's are (``closed_loop.sim.occupancy_map``). The boxes
stand from the ground (or from the cut mesh's lowest point, where it floats above the floor band) to its
highest. So a building's walls are walls, a table is the block under its top, and the footprint is the mesh's
grown by at most a cell (a face on a cell's side makes both cells solid).

Free of ROS.
"""
import importlib
import math

import numpy

from closed_loop.sim import occupancy_map

#: The side of a footprint's cells (m): the footprint is the mesh's, grown by at most this much.
CELL_M = 0.05
#: What lies below this height (m) is floor, what lies above ``OVERHEAD_M`` is overhead: neither stands in a
#: ground robot's way.
FLOOR_M, OVERHEAD_M = 0.05, 2.0
#: The most cells a footprint may have (a 200 m square at 0.05 m); the most cross-sections through a mesh.
MAX_CELLS, MAX_SECTIONS = 4000 * 4000, 16


def read_triangles(path, scale):
    """The triangles (n, 3, 3) of the mesh file at ``path`` (STL, OBJ or COLLADA; a file of several meshes is
    one, each placed by its nodes), scaled by ``scale`` (x, y, z) in its own frame; ValueError naming what is
    wrong where trimesh cannot read it or it holds no triangle."""
    import trimesh
    try:
        mesh = trimesh.load(path, force='mesh', process=False)
    except Exception as error:          # trimesh raises what its readers raise (ValueError, KeyError, XML errors)
        raise ValueError('a mesh trimesh reads (STL, OBJ, COLLADA): %s' % (str(error) or type(error).__name__))
    triangles = numpy.asarray(getattr(mesh, 'triangles', ()), float).reshape(-1, 3, 3)
    if not len(triangles) or not numpy.isfinite(triangles).all():
        raise ValueError('a mesh of triangles with finite vertices')
    return triangles * numpy.asarray(scale, float)


def box_triangles(size):
    """The triangles of a box of ``size`` (x, y, z) about its centre (a tilted box's footprint)."""
    import trimesh
    return trimesh.creation.box(extents=size).triangles


def cylinder_triangles(radius, length):
    """The triangles of a cylinder along its z axis (a tilted cylinder's footprint), 64 sides."""
    import trimesh
    return trimesh.creation.cylinder(radius=radius, height=length, sections=64).triangles


def footprint_boxes(triangles, transform, name, fail):
    """The boxes (``closed_loop.sim.world.Obstacle`` fields as dicts, as ``occupancy_map.map_boxes`` gives them)
    of ``triangles`` (n, 3, 3, in the shape's frame) placed by ``transform`` (4x4, to the world), or [] where
    nothing of them lies between the floor and the overhead; ``fail(what, got)`` raises the caller's error
    when the footprint would be too large."""
    import trimesh
    from trimesh import intersections
    placed = triangles.reshape(-1, 3) @ transform[:3, :3].T + transform[:3, 3]
    mesh = trimesh.Trimesh(vertices=placed, faces=numpy.arange(len(placed)).reshape(-1, 3), process=False)
    vertices, faces = mesh.vertices, mesh.faces
    for normal, height in (((0.0, 0.0, 1.0), FLOOR_M), ((0.0, 0.0, -1.0), OVERHEAD_M)):
        if len(faces):
            vertices, faces = intersections.slice_faces_plane(vertices, faces, numpy.array(normal),
                                                              numpy.array((0.0, 0.0, height)))[:2]
    if not len(faces):
        return []
    cut = vertices[numpy.unique(faces)]
    low, top = float(cut[:, 2].min()), float(cut[:, 2].max())
    base = 0.0 if float(placed[:, 2].min()) <= FLOOR_M else low
    x0, y0 = (math.floor(float(cut[:, i].min()) / CELL_M) * CELL_M - CELL_M for i in (0, 1))
    nx, ny = (int(math.ceil((float(cut[:, i].max()) - start) / CELL_M)) + 1 for i, start in ((0, x0), (1, y0)))
    if nx * ny > MAX_CELLS:
        fail('a mesh whose footprint is at most %d cells of %g m' % (MAX_CELLS, CELL_M), '%d x %d' % (nx, ny))
    kernel = importlib.import_module('closed_loop.sim.footprint_kernel')   # numba only where a mesh is
    solid = numpy.zeros((ny, nx), numpy.uint8)
    kernel.touch(numpy.ascontiguousarray(vertices[faces][:, :, :2], float), x0, y0, CELL_M, solid)
    for height in _section_heights(cut[:, 2], low, top):
        lines, across = intersections.mesh_plane(mesh, (0.0, 0.0, 1.0), (0.0, 0.0, height), return_faces=True)
        if len(lines):
            weights = -numpy.sign(mesh.face_normals[across][:, 0]).astype(numpy.int64)
            kernel.fill_inside(numpy.ascontiguousarray(lines[:, :, :2], float), weights, x0, y0, CELL_M, solid)
    cells = numpy.where(solid[::-1], 1, 0)          # the map's way: its first row is the top
    boxes = occupancy_map.map_boxes(cells, CELL_M, (x0, y0, 0.0), False, max(top - base, CELL_M), name=name,
                                    error=fail)
    for box in boxes:
        x, y, z = box['position']
        box['position'] = (x, y, z + base)
    return boxes


def prepare():
    """The compiled rasteriser loaded (compiled on a machine's first use): the footprint of a small box."""
    footprint_boxes(box_triangles((0.2, 0.2, 0.5)), numpy.eye(4), 'box', lambda what, got: None)


def _section_heights(heights, low, top):
    """Where the mesh is cut across to find its inside: between each two heights of its vertices (``heights``,
    within ``low`` to ``top``), where its cross-section is the same all the way; at most
    :data:`MAX_SECTIONS`, evenly chosen."""
    levels = numpy.unique(numpy.concatenate(([low, top], heights)))
    middles = (levels[:-1] + levels[1:]) / 2.0 if len(levels) > 1 else levels
    if len(middles) > MAX_SECTIONS:
        middles = middles[numpy.linspace(0, len(middles) - 1, MAX_SECTIONS).round().astype(int)]
    return middles.tolist()
