"""Maps of the kind map_server serves, as worlds (closed_loop.sim.occupancy_map): the cells classed as map_server
classes them, merged into boxes that cover them exactly, where the map puts them; an office floor the navigator
crosses through its doors; and every fault of a map refused in one line that names the file and the field."""
import math

import cv2
import numpy as np
import pytest

from closed_loop.batch.episode import EpisodeError, EpisodeSpec, prepare, run_episode
from closed_loop.sim import occupancy_map, shapes
from closed_loop.sim.world import WorldError, load_world

FREE, UNKNOWN, OCCUPIED = 254, 205, 0       # what map_saver writes


def write_map(folder, pixels, name='map', **fields):
    cv2.imwrite(str(folder / (name + '.pgm')), np.asarray(pixels, np.uint8))
    keys = dict(image=name + '.pgm', resolution=0.1, origin='[0.0, 0.0, 0.0]', negate=0, occupied_thresh=0.65,
                free_thresh=0.196)
    keys.update(fields)
    path = folder / (name + '.yaml')
    path.write_text(''.join('%s: %s\n' % (k, v) for k, v in keys.items() if v is not None))
    return path


def test_cells_are_classed_as_map_server_classes_them(tmp_path):
    row = [0, 50, 100, 128, 204, 205, 230, 255]
    cells, resolution, origin = occupancy_map.read_map(write_map(tmp_path, [row]), WorldError)
    # p = (255 - v) / 255: occupied above 0.65 (v < 89.25), free below 0.196 (v > 205.02), unknown between.
    assert cells.tolist() == [[1, 1, -1, -1, -1, -1, 0, 0]] and resolution == 0.1 and origin == (0.0, 0.0, 0.0)
    negated, _, _ = occupancy_map.read_map(write_map(tmp_path, [row], negate=1), WorldError)
    assert negated.tolist() == [[0, -1, -1, -1, 1, 1, 1, 1]]                # p = v / 255
    raw, _, _ = occupancy_map.read_map(write_map(tmp_path, [[0, 10, 50, 70, 100, 101, 255]], mode='raw'),
                                       WorldError)
    assert raw.tolist() == [[0, 0, -1, 1, 1, -1, -1]]


def test_a_colour_png_is_read_by_the_mean_of_its_channels(tmp_path):
    rgb = np.zeros((1, 3, 3), np.uint8)
    rgb[0, 0], rgb[0, 1], rgb[0, 2] = (255, 255, 255), (0, 0, 0), (255, 255, 0)     # white, black, 170 grey
    cv2.imwrite(str(tmp_path / 'c.png'), rgb)
    path = tmp_path / 'c.yaml'
    path.write_text('image: c.png\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\noccupied_thresh: 0.65\n'
                    'free_thresh: 0.25\n')
    assert occupancy_map.read_map(path, WorldError)[0].tolist() == [[0, 1, -1]]


@pytest.mark.parametrize('seed', range(5))
def test_the_boxes_cover_exactly_the_solid_cells(seed):
    solid = np.random.default_rng(seed).random((37, 53)) < 0.3
    solid[10:20, 5:40] = True                                   # a block, which merges into few boxes
    covered = np.zeros(solid.shape, int)
    rects = occupancy_map.rectangles(solid)
    for r, c, nr, nc in rects:
        covered[r:r + nr, c:c + nc] += 1
    assert (covered == solid).all() and len(rects) < solid.sum()


def test_a_box_stands_where_the_map_puts_its_cells_turned_by_the_origins_yaw():
    cells = np.full((4, 6), 0, np.int8)
    cells[0, 5] = 1                          # the top row's last cell: x 5..6, y 3..4 cells from the origin
    cells[3, 0:2] = -1                       # unknown, at the origin
    (box,) = occupancy_map.map_boxes(cells, 0.5, (1.0, 2.0, 0.0), False, 0.8)
    assert box['position'] == pytest.approx((1.0 + 2.75, 2.0 + 1.75, 0.4)) and box['size'] == (0.5, 0.5, 0.8)
    assert len(occupancy_map.map_boxes(cells, 0.5, (1.0, 2.0, 0.0), True, 0.8)) == 2
    (turned,) = occupancy_map.map_boxes(cells, 0.5, (1.0, 2.0, math.pi / 2), False, 0.8)
    assert turned['position'] == pytest.approx((1.0 - 1.75, 2.0 + 2.75, 0.4)) and turned['yaw'] == math.pi / 2


def office(folder):
    """An office floor, 12 m by 8 m with 0.15 m walls, in unknown space: three rooms below a 1 m corridor and three
    above, doors 1 m wide into the left room below and the right room above; the robot starts in the first and
    its goal is in the second."""
    res, pad = 0.05, 1.0
    rows, cols = int((8.0 + 2 * pad) / res), int((12.0 + 2 * pad) / res)
    img = np.full((rows, cols), UNKNOWN, np.uint8)

    def fill(x0, y0, x1, y1, value):           # metres from the building's lower-left corner
        img[rows - int(round((y1 + pad) / res)):rows - int(round((y0 + pad) / res)),
            int(round((x0 + pad) / res)):int(round((x1 + pad) / res))] = value
    fill(0, 0, 12, 8, FREE)
    for x0, y0, x1, y1 in ((0, 0, 12, 0.15), (0, 7.85, 12, 8), (0, 0, 0.15, 8), (11.85, 0, 12, 8),
                           (0, 3.35, 12, 3.5), (0, 4.5, 12, 4.65), (4, 0, 4.15, 3.5), (8, 0, 8.15, 3.5),
                           (4, 4.5, 4.15, 8), (8, 4.5, 8.15, 8)):
        fill(x0, y0, x1, y1, OCCUPIED)
    for x0, y0, x1, y1 in ((2, 3.35, 3, 3.5), (9, 4.5, 10, 4.65)):
        fill(x0, y0, x1, y1, FREE)
    write_map(folder, img, 'office', resolution=res, origin='[-3.0, -2.5, 0.0]', saved_by='map_saver')
    world = folder / 'office_world.yaml'
    world.write_text('name: office\nmap: {file: office.yaml}\nrobot: {start: {x: 0.0, y: 0.0, yaw: 1.5708}}\n'
                     'goal: {x: 8.5, y: 5.0}\n')
    return world


def test_an_office_map_is_a_world_of_few_boxes_in_which_the_navigator_goes_through_the_doors(tmp_path):
    world = load_world(office(tmp_path))
    assert 10 <= len(world.obstacles) <= 40 and world.goal == (8.5, 5.0)
    # The wall between the first room and the corridor, with its door at x 0 to 1 (world): a way through.
    wall_y = 3.425 - 1.5                    # the building's lower-left corner is at (-2, -1.5)
    assert not any(abs(ob.position[1] - wall_y) < 0.1 and shapes.distance(ob, 0.5, wall_y) <= 0.0
                   for ob in world.obstacles)
    assert any(shapes.distance(ob, -0.5, wall_y) <= 0.0 for ob in world.obstacles)
    result = run_episode(EpisodeSpec(world=str(tmp_path / 'office_world.yaml'), controller='avoid_obstacles',
                                     time_limit_s=120.0))
    assert result.outcome == 'reached' and result.contacts == 0, result.why
    # The map's YAML file as it is is a world too: the robot at the origin, the unknown space around solid.
    bare = load_world(tmp_path / 'office.yaml')             # (a key map_server does not read is left alone)
    assert (bare.robot_start.x, bare.robot_start.y, bare.robot_start.yaw) == (0.0, 0.0, 0.0)
    assert len(bare.obstacles) == len(world.obstacles)
    # Started elsewhere (the simulator's ~start, sim.start of an episode): back from the far room to the origin.
    back = run_episode(EpisodeSpec(world=str(tmp_path / 'office.yaml'), controller='avoid_obstacles',
                                   goal=(0.0, 0.0), sim={'start': '8.5 5.0 -1.5708'}, time_limit_s=120.0))
    assert back.outcome == 'reached' and back.contacts == 0, back.why


@pytest.mark.parametrize('start, message', [
    ('-0.5 1.925 0', 'sim.start: expected a pose where the robot'),               # in the wall by the first door
    ('1 2', "sim: ~start: expected 'x y yaw' (3 finite numbers: m, m, rad; a launch file's start:= or start_x:= "
            "and start_y:=) or empty, got '1 2'"),
    ('1 2 nan', "sim: ~start: expected 'x y yaw'"),
])
def test_a_start_in_place_of_the_worlds_is_checked_as_the_worlds_is(tmp_path, start, message):
    office(tmp_path)
    with pytest.raises(EpisodeError) as error:
        prepare(EpisodeSpec(world=str(tmp_path / 'office.yaml'), controller='avoid_obstacles', sim={'start': start}))
    assert message in str(error.value) and '\n' not in str(error.value), str(error.value)


def test_a_world_of_several_robots_takes_no_start_in_place_of_theirs():
    with pytest.raises(EpisodeError, match='sim.start: expected a world of one robot'):
        prepare(EpisodeSpec(world='two_robots', sim={'start': '0 0 0'}))


@pytest.mark.parametrize('fields, pixels, message', [
    (dict(image='missing.pgm'), None, "image: expected a readable image file"),
    (dict(resolution=0), None, 'resolution: expected a number > 0'),
    (dict(occupied_thresh=1.5), None, 'occupied_thresh: expected a number in [0, 1]'),
    (dict(free_thresh=0.9), None, 'free_thresh: expected at most occupied_thresh'),
    (dict(negate=2), None, 'negate: expected 0 or 1'),
    (dict(mode='fancy'), None, 'mode: expected one of trinary, scale, raw'),
    (dict(origin='[0, 0]'), None, 'origin: expected [x, y, yaw]'),
    (dict(resolution='fine'), None, 'resolution: expected a number > 0'),
    (dict(image='map.yaml'), None, 'image: expected a PGM or PNG image OpenCV can read'),
])
def test_a_faulty_map_is_refused_naming_the_file_and_the_field(tmp_path, fields, pixels, message):
    path = write_map(tmp_path, pixels if pixels is not None else [[FREE, OCCUPIED]], **fields)
    with pytest.raises(WorldError) as error:
        load_world(path)
    text = str(error.value)
    assert str(path) in text and message in text and '\n' not in text, text


def test_a_world_whose_map_is_faulty_names_the_map(tmp_path):
    write_map(tmp_path, [[FREE]], free_thresh=0.9)
    world = tmp_path / 'w.yaml'
    world.write_text('name: w\nmap: {file: map.yaml, unknown: maybe}\n')
    with pytest.raises(WorldError, match=r'w\.yaml: map\.unknown: expected obstacle or free'):
        load_world(world)
    world.write_text('name: w\nmap: {file: map.yaml}\n')
    with pytest.raises(WorldError, match=r'map\.yaml: free_thresh: expected at most occupied_thresh'):
        load_world(world)


def test_a_map_of_more_boxes_than_the_simulator_takes_is_refused_before_any_is_made(tmp_path):
    """A checkerboard of single occupied cells merges into one box per cell: one row more than
    ``MAX_BOXES`` allows is refused in one line naming the file and the count."""
    side = int(math.ceil(math.sqrt(2 * occupancy_map.MAX_BOXES))) + 2
    board = np.where((np.add.outer(np.arange(side), np.arange(side)) % 2) == 0, OCCUPIED, FREE)
    path = write_map(tmp_path, board)
    with pytest.raises(WorldError) as error:
        load_world(path, check_starts=False)
    text = str(error.value)
    assert str(path) in text and 'at most %d boxes' % occupancy_map.MAX_BOXES in text and '\n' not in text, text
