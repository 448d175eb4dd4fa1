"""Maps of the kind ROS's ``map_server`` serves, as the obstacles of a world.

A map is a YAML file (``image``, ``resolution``, ``origin``, ``occupied_thresh``, ``free_thresh``, ``negate``,
and optionally ``mode``, as ``map_server`` reads them: what gmapping's or cartographer's ``map_saver`` writes)
and its image (PGM or PNG, grey or colour; a colour pixel is the mean of its colour channels). Each cell is
classed as ``map_server`` classes it: with ``p = (255 - v) / 255`` (``v / 255`` with ``negate: 1``), occupied
where ``p > occupied_thresh``, free where ``p < free_thresh``, unknown between (mode ``trinary`` and ``scale``;
in mode ``raw`` the value is the occupancy in percent, 0 to 100, anything above unknown). The image's first
row is the map's top: cell (row r, column c) spans x from ``origin.x + c * resolution`` and y from
``origin.y + (rows - 1 - r) * resolution``, turned by the origin's yaw about the origin.

Occupied cells (and unknown ones, unless the world says ``unknown: free``: a robot is not sent where the map
has not looked) become static boxes of the world's wall height, merged: each row's runs of cells, then the
same run on consecutive rows, into one rectangle. A map of rooms and corridors is then a few hundred boxes.

Free of ROS; reads the image with OpenCV.
"""
import math
import os

import numpy

from closed_loop.yaml_check import Checker, load_yaml, read_text

#: The keys of map_server's YAML (others are left alone, as map_server leaves them).
MAP_KEYS = ('image', 'resolution', 'origin', 'negate', 'occupied_thresh', 'free_thresh', 'mode')
MODES = ('trinary', 'scale', 'raw')
MAX_MAP_FILE_BYTES = 64 * 1024
#: The largest image (cells) and the most boxes a map may make (a map past them is refused, not loaded for
#: minutes).
MAX_CELLS = 20000 * 20000
MAX_BOXES = 100000
MAP_COLOR = (0.45, 0.45, 0.5, 1.0)


def is_map(data):
    """True if a loaded YAML document is a map_server map (it has ``image`` and ``resolution``)."""
    return isinstance(data, dict) and 'image' in data and 'resolution' in data


def read_map(path, error_class):
    """The map at ``path`` (its YAML file): (cells, resolution m, origin (x, y, yaw)), ``cells`` an int8 array
    (rows, columns) of 1 occupied, 0 free, -1 unknown, row 0 the map's top. Errors are ``error_class``
    (a :class:`closed_loop.yaml_check.FileError`), naming the file and the field."""
    path = os.fspath(path)
    data = load_yaml(read_text(path, MAX_MAP_FILE_BYTES, error_class, 'map file'), path, error_class)
    check = Checker(path, error_class)
    # Keys map_server does not read are left alone, as map_server leaves them.
    top = check.mapping(data, '(top level)', tuple(data) if isinstance(data, dict) else MAP_KEYS)
    image = check.string(check.get(top, 'image', 'image'), 'image')
    resolution = check.number(check.get(top, 'resolution', 'resolution'), 'resolution', 'a number > 0 (m per cell)',
                              positive=True)
    origin = check.numbers(check.get(top, 'origin', 'origin'), 'origin', (3,), '[x, y, yaw]: finite numbers (m, rad)')
    negate = top.get('negate', 0)
    if negate not in (0, 1) or isinstance(negate, bool):
        check.fail('negate', '0 or 1', negate)
    occupied = check.number(check.get(top, 'occupied_thresh', 'occupied_thresh'), 'occupied_thresh',
                            'a number in [0, 1]')
    free = check.number(check.get(top, 'free_thresh', 'free_thresh'), 'free_thresh', 'a number in [0, 1]')
    for name, value in (('occupied_thresh', occupied), ('free_thresh', free)):
        if not 0.0 <= value <= 1.0:
            check.fail(name, 'a number in [0, 1]', value)
    if not free <= occupied:
        check.fail('free_thresh', 'at most occupied_thresh (%g)' % occupied, free)
    mode = top.get('mode', 'trinary')
    if mode not in MODES:
        check.fail('mode', 'one of %s' % ', '.join(MODES), mode)
    image_path = image if os.path.isabs(image) else os.path.join(os.path.dirname(os.path.abspath(path)), image)
    values = _read_image(image_path, check)
    if mode == 'raw':
        cells = numpy.where(values > 100, -1, numpy.where(values > occupied * 100, 1,
                                                          numpy.where(values < free * 100, 0, -1)))
    else:
        p = values / 255.0 if negate else (255.0 - values) / 255.0
        cells = numpy.where(p > occupied, 1, numpy.where(p < free, 0, -1))
    return cells.astype(numpy.int8), resolution, tuple(origin)


def _read_image(path, check):
    """The image's grey values as floats in [0, 255] (rows, columns)."""
    import cv2
    try:
        size = os.path.getsize(path)
    except OSError as error:
        check.fail('image', 'a readable image file', '%s (%s)' % (path, error.strerror))
    if size > 4 * MAX_CELLS:
        check.fail('image', 'an image of at most %d cells' % MAX_CELLS, '%s (%d bytes)' % (path, size))
    pixels = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if pixels is None or pixels.size == 0:
        check.fail('image', 'a PGM or PNG image OpenCV can read', path)
    if pixels.ndim == 3:
        pixels = pixels[:, :, :3].mean(axis=2) if pixels.shape[2] >= 3 else pixels[:, :, 0]
    scale = 255.0 / numpy.iinfo(pixels.dtype).max if numpy.issubdtype(pixels.dtype, numpy.integer) else 1.0
    return numpy.asarray(pixels, float) * scale if scale != 1.0 else numpy.asarray(pixels, float)


def rectangles(solid):
    """The cells of the boolean array ``solid`` as rectangles (row, column, rows, columns), each cell in exactly
    one: each row's runs, merged with the same run of the rows below."""
    out, open_runs = [], {}                 # (c0, c1) -> first row, of the runs still growing
    padded = numpy.zeros((solid.shape[0] + 1, solid.shape[1] + 2), bool)
    padded[:-1, 1:-1] = solid
    for r in range(padded.shape[0]):
        edges = numpy.flatnonzero(numpy.diff(padded[r].astype(numpy.int8)))
        runs = set(zip(edges[::2].tolist(), edges[1::2].tolist()))
        for run in [run for run in open_runs if run not in runs]:
            first = open_runs.pop(run)
            out.append((first, run[0], r - first, run[1] - run[0]))
        for run in runs:
            open_runs.setdefault(run, r)
    return out


def map_boxes(cells, resolution, origin, unknown_solid, height_m, name='map', error=None):
    """The static boxes (``closed_loop.sim.world.Obstacle`` fields as dicts) of a map's occupied cells (and its
    unknown ones if ``unknown_solid``), merged into rectangles, ``height_m`` tall. ``error``: called with a
    message when the map makes more than MAX_BOXES boxes."""
    solid = (cells == 1) | ((cells == -1) if unknown_solid else False)
    rects = rectangles(solid)
    if len(rects) > MAX_BOXES and error is not None:
        error('at most %d boxes (merged occupied cells)' % MAX_BOXES, '%d boxes' % len(rects))
    rows = cells.shape[0]
    ox, oy, yaw = origin
    c, s = math.cos(yaw), math.sin(yaw)
    boxes = []
    for index, (r, col, nr, nc) in enumerate(sorted(rects)):
        # The rectangle's centre in the map's own frame (origin at its lower-left corner), then turned.
        mx, my = (col + 0.5 * nc) * resolution, (rows - r - 0.5 * nr) * resolution
        boxes.append(dict(name='%s_%d' % (name, index), position=(ox + c * mx - s * my, oy + s * mx + c * my,
                                                                   0.5 * height_m),
                          size=(nc * resolution, nr * resolution, height_m), yaw=yaw))
    return boxes
