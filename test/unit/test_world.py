"""World files: the shipped worlds, every kind of bad file, and where moving obstacles are."""
import math
import os
import textwrap

import pytest

from closed_loop.sim.obstacles import disk_overlaps, motion_path, moving_obstacle_xy
from closed_loop.sim.world_robots import ROBOT_CLEARANCE_RADIUS_M
from closed_loop.sim.world import (NAMED_COLORS, Obstacle, Pose2D,
                               WorldError, available_worlds, load_world, parse_world, resolve_world)

WORLDS_DIR = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'worlds'))
SHIPPED = ('corridor', 'dead_end', 'empty', 'obstacle_course', 'obstacle_left', 'obstacle_right', 'person_and_wall',
           'person_crossing', 'posts', 'red_box', 'slalom', 'two_robots', 'wall')
RED = (0.9, 0.05, 0.05, 1.0)
# Sampling step along paths and in time for the clearance checks; fine enough for 0.2 m objects.
STEP_M = 0.05


def shipped(name):
    return load_world(os.path.join(WORLDS_DIR, name + '.yaml'))


def footprint_corners(obstacle):
    """The four (x, y) corners of a box's footprint."""
    c, s = math.cos(obstacle.yaw), math.sin(obstacle.yaw)
    hx, hy = obstacle.size[0] / 2.0, obstacle.size[1] / 2.0
    x, y = obstacle.position[0], obstacle.position[1]
    return [(x + c * u - s * v, y + s * u + c * v) for u, v in
            ((hx, hy), (-hx, hy), (-hx, -hy), (hx, -hy))]


def is_reddish(rgba):
    r, g, b = rgba[:3]
    return r > 0.6 and g < 0.3 and b < 0.3


def moved(obstacle, x, y):
    """``obstacle`` with its footprint centre at (x, y)."""
    return Obstacle(obstacle.name, obstacle.shape, (x, y, obstacle.position[2]), obstacle.yaw,
                    obstacle.size, obstacle.radius, obstacle.color, None)


def path_samples(obstacle):
    """Positions of a moving obstacle over one full cycle, every STEP_M of travel."""
    _, cycle_m = motion_path(obstacle)
    count = int(math.ceil(cycle_m / STEP_M))
    return [moving_obstacle_xy(obstacle, i * STEP_M / obstacle.motion.speed)
            for i in range(count + 1)]


def overlaps(a, b):
    """Footprint overlap of a cylinder ``a`` with any obstacle ``b`` (boxes checked via disks)."""
    assert a.shape == 'cylinder'
    return disk_overlaps(b, a.position[0], a.position[1], a.radius)


def disks_covering(obstacle):
    """Disks (x, y, r) that together cover a box footprint, to test box-vs-anything overlap."""
    if obstacle.shape == 'cylinder':
        return [(obstacle.position[0], obstacle.position[1], obstacle.radius)]
    radius = min(obstacle.size[0], obstacle.size[1]) / 2.0
    c, s = math.cos(obstacle.yaw), math.sin(obstacle.yaw)
    disks = []
    nx = max(1, int(math.ceil(obstacle.size[0] / radius)))
    ny = max(1, int(math.ceil(obstacle.size[1] / radius)))
    for i in range(nx + 1):
        for j in range(ny + 1):
            u = -obstacle.size[0] / 2.0 + obstacle.size[0] * i / nx
            v = -obstacle.size[1] / 2.0 + obstacle.size[1] * j / ny
            disks.append((obstacle.position[0] + c * u - s * v,
                          obstacle.position[1] + s * u + c * v, STEP_M))
    return disks


# --- shipped worlds ----------------------------------------------------------------------------

def test_every_shipped_world_is_listed_and_loads_with_its_file_name():
    assert available_worlds(WORLDS_DIR) == list(SHIPPED)
    for name in SHIPPED:
        world = shipped(name)
        assert world.name == name
        assert world.source == os.path.join(WORLDS_DIR, name + '.yaml')
        assert world.description


def test_empty_world_has_no_obstacles_and_starts_at_the_origin():
    world = shipped('empty')
    assert world.obstacles == ()
    assert world.robot_start == Pose2D(0.0, 0.0, 0.0)


def test_wall_world_has_one_wall_with_near_face_at_3_m_spanning_y_minus_2_to_2():
    world = shipped('wall')
    assert world.robot_start == Pose2D(0.0, 0.0, 0.0)
    assert len(world.obstacles) == 1
    wall = world.obstacles[0]
    assert wall.shape == 'box' and wall.motion is None
    xs = [x for x, _ in footprint_corners(wall)]
    ys = [y for _, y in footprint_corners(wall)]
    assert min(xs) == pytest.approx(3.0, abs=1e-9)
    assert min(ys) == pytest.approx(-2.0, abs=1e-9)
    assert max(ys) == pytest.approx(2.0, abs=1e-9)
    # Tall enough for the LIDAR at 0.17 m and standing on the ground.
    assert wall.position[2] - wall.size[2] / 2.0 == pytest.approx(0.0, abs=1e-9)
    assert wall.size[2] >= 0.5
    assert min(wall.color[:3]) > 0.6, 'light grey'
    assert max(wall.color[:3]) - min(wall.color[:3]) < 0.05, 'grey, not tinted'


def test_red_box_is_red_on_the_path_with_near_face_at_2_5_m_and_alone_in_red():
    world = shipped('red_box')
    reds = [o for o in world.obstacles if is_reddish(o.color)]
    assert len(reds) == 1
    box = reds[0]
    assert box.color == RED
    xs = [x for x, _ in footprint_corners(box)]
    ys = [y for _, y in footprint_corners(box)]
    assert min(xs) == pytest.approx(2.5, abs=1e-9)
    assert min(ys) < 0.0 < max(ys), 'centred on the robot path'
    assert max(ys) - min(ys) == pytest.approx(0.5, abs=0.1)
    assert box.size[2] == pytest.approx(0.5, abs=0.1)
    assert box.position[2] - box.size[2] / 2.0 == pytest.approx(0.0, abs=1e-9)
    assert not is_reddish(world.ground_color)


def test_corridor_lets_a_robot_drive_straight_until_the_end_wall():
    world = shipped('corridor')
    start = world.robot_start
    assert (start.x, start.y, start.yaw) == (0.0, 0.0, 0.0)
    # Free all the way to 0.25 m before the end wall's near face at x = 8.0 m ...
    x = 0.0
    while x <= 8.0 - ROBOT_CLEARANCE_RADIUS_M - STEP_M:
        assert not any(disk_overlaps(o, x, 0.0, ROBOT_CLEARANCE_RADIUS_M)
                       for o in world.obstacles), x
        x += STEP_M
    # ... and blocked there, so the robot cannot drive out of the end.
    assert any(disk_overlaps(o, 8.0, 0.0, ROBOT_CLEARANCE_RADIUS_M) for o in world.obstacles)
    # The side walls stop the robot leaving sideways anywhere along the way.
    for x in (0.0, 4.0, 7.5):
        for y in (-0.8, 0.8):
            assert any(disk_overlaps(o, x, y, 0.01) for o in world.obstacles), (x, y)


def test_obstacle_course_is_a_bounded_arena_with_variety_one_red_object_and_movers():
    world = shipped('obstacle_course')
    assert world.robot_start == Pose2D(0.0, 0.0, 0.0)
    movers = [o for o in world.obstacles if o.motion is not None]
    assert len(movers) >= 1
    assert {'box', 'cylinder'} <= {o.shape for o in world.obstacles}
    assert len({o.color for o in world.obstacles}) >= 5
    assert len([o for o in world.obstacles if is_reddish(o.color)]) == 1
    # Walls all round: leaving the origin in any direction hits a static obstacle before 10 m
    # (the farthest arena corner is 9.4 m away).
    for k in range(16):
        heading = 2.0 * math.pi * k / 16
        hit = False
        d = 0.0
        while d < 10.0 and not hit:
            hit = any(disk_overlaps(o, d * math.cos(heading), d * math.sin(heading), 0.01)
                      for o in world.obstacles if o.motion is None)
            d += STEP_M
        assert hit, heading


def test_obstacle_course_first_1_5_m_ahead_stays_clear_even_of_moving_obstacles():
    world = shipped('obstacle_course')
    statics = [o for o in world.obstacles if o.motion is None]
    movers = [o for o in world.obstacles if o.motion is not None]
    ahead = [i * STEP_M for i in range(int(1.5 / STEP_M) + 1)]
    for x in ahead:
        assert not any(disk_overlaps(o, x, 0.0, ROBOT_CLEARANCE_RADIUS_M) for o in statics), x
    for mover in movers:
        for mx, my in path_samples(mover):
            placed = moved(mover, mx, my)
            for x in ahead:
                assert not disk_overlaps(placed, x, 0.0, ROBOT_CLEARANCE_RADIUS_M), (mover.name, x)


@pytest.mark.parametrize('name', SHIPPED)
def test_moving_obstacles_never_pass_through_static_ones(name):
    world = shipped(name)
    statics = [o for o in world.obstacles if o.motion is None]
    for mover in (o for o in world.obstacles if o.motion is not None):
        for mx, my in path_samples(mover):
            for x, y, r in disks_covering(moved(mover, mx, my)):
                hits = [s.name for s in statics if disk_overlaps(s, x, y, r)]
                assert not hits, (mover.name, mx, my, hits)


def test_clearance_helpers_see_an_overlap_where_there_is_one():
    # The shipped-world checks above rely on these helpers; they must not pass vacuously.
    wall = shipped('wall').obstacles[0]
    walker = [o for o in shipped('obstacle_course').obstacles if o.name == 'walker'][0]
    assert overlaps(moved(walker, 2.9, 0.0), wall)
    assert not overlaps(moved(walker, 2.7, 0.0), wall)
    assert any(disk_overlaps(wall, x, y, r) for x, y, r in disks_covering(moved(wall, 3.05, 1.0)))
    samples = path_samples(walker)
    assert samples[0] == (3.0, 3.5)
    assert min(y for _, y in samples) == pytest.approx(-3.5)


# --- parsing defaults and shapes ---------------------------------------------------------------

def test_defaults_when_optional_sections_are_absent():
    world = parse_world({'name': 'bare'})
    assert world.source == '<string>'
    assert world.description == ''
    assert world.ground_color == (0.55, 0.55, 0.55, 1.0)
    assert world.robot_start == Pose2D(0.0, 0.0, 0.0)
    assert world.obstacles == ()
    assert parse_world({'name': 'bare', 'obstacles': None}).obstacles == ()


def test_box_and_cylinder_fill_in_height_centre_size_and_colour():
    world = parse_world({'name': 'shapes', 'obstacles': [
        {'name': 'b', 'type': 'box', 'position': [2, 1], 'size': [0.5, 0.4, 0.8], 'yaw': 0.3,
         'color': 'green'},
        {'name': 'c', 'type': 'cylinder', 'position': [2.0, -1.0, 0.9], 'radius': 0.2,
         'height': 0.6},
    ]})
    box, cyl = world.obstacles
    assert box.position == (2.0, 1.0, 0.4)
    assert box.size == (0.5, 0.4, 0.8)
    assert (box.yaw, box.radius, box.color) == (0.3, 0.0, NAMED_COLORS['green'])
    assert all(isinstance(v, float) for v in box.position)
    assert cyl.position == (2.0, -1.0, 0.9)
    assert cyl.size == (0.4, 0.4, 0.6)
    assert (cyl.yaw, cyl.radius, cyl.color) == (0.0, 0.2, NAMED_COLORS['grey'])
    assert box.motion is None and cyl.motion is None


def test_wall_becomes_a_box_along_its_centre_line():
    world = parse_world({'name': 'w', 'obstacles': [
        {'name': 'diag', 'type': 'wall', 'start': [1.0, 1.0], 'end': [4.0, 5.0]},
        {'name': 'thick', 'type': 'wall', 'start': [0.0, -2.0], 'end': [-2.0, -2.0],
         'thickness': 0.3, 'height': 0.5},
    ]})
    diag, thick = world.obstacles
    assert diag.shape == 'box' and diag.motion is None
    assert diag.position == pytest.approx((2.5, 3.0, 0.5))
    assert diag.size == pytest.approx((5.0, 0.1, 1.0))
    assert diag.yaw == pytest.approx(math.atan2(4.0, 3.0))
    assert thick.position == pytest.approx((-1.0, -2.0, 0.25))
    assert thick.size == pytest.approx((2.0, 0.3, 0.5))
    assert abs(thick.yaw) == pytest.approx(math.pi)
    # The footprint ends at start and end, not beyond.
    assert disk_overlaps(diag, 1.0, 1.0, 0.01) and disk_overlaps(diag, 4.0, 5.0, 0.01)
    assert not disk_overlaps(diag, 0.9, 0.87, 0.01)


def test_motion_is_parsed_with_loop_defaulting_to_true():
    world = parse_world({'name': 'm', 'obstacles': [
        {'name': 'c', 'type': 'cylinder', 'position': [2, 0], 'radius': 0.1, 'height': 1,
         'motion': {'waypoints': [[3, 0], [3, 1]], 'speed': 0.5}},
    ]})
    motion = world.obstacles[0].motion
    assert motion.waypoints == ((3.0, 0.0), (3.0, 1.0))
    assert motion.speed == 0.5
    assert motion.loop is True


# --- bad files ---------------------------------------------------------------------------------

GOOD_OBSTACLE = """\
  - name: pillar
    type: cylinder
    position: [2.0, 1.0]
    radius: 0.2
    height: 1.0
"""

# (case id, file text, expected field path)
BAD_FILES = [
    ('top level is a list', '- name: x\n', '(top level)'),
    ('empty file', '', '(top level)'),
    ('top level is a string', 'just words\n', '(top level)'),
    ('missing name', 'description: no name\n', 'name'),
    ('name not a string', 'name: 5\n', 'name'),
    ('name empty', 'name: ""\n', 'name'),
    ('description not a string', 'name: a\ndescription: [1]\n', 'description'),
    ('unknown top-level key', 'name: a\nobstacle: []\n', 'obstacle'),
    ('unknown key in ground', 'name: a\nground: {colour: red}\n', 'ground.colour'),
    ('unknown key in robot', 'name: a\nrobot: {pose: {x: 0, y: 0}}\n', 'robot.pose'),
    ('unknown key in robot start', 'name: a\nrobot: {start: {x: 0, y: 0, theta: 1}}\n',
     'robot.start.theta'),
    ('robot start missing y', 'name: a\nrobot: {start: {x: 0}}\n', 'robot.start.y'),
    ('robot start yaw NaN', 'name: a\nrobot: {start: {x: 0, y: 0, yaw: .nan}}\n',
     'robot.start.yaw'),
    ('robot start x bool', 'name: a\nrobot: {start: {x: true, y: 0}}\n', 'robot.start.x'),
    ('robot start x string', 'name: a\nrobot: {start: {x: "1.0", y: 0}}\n', 'robot.start.x'),
    ('obstacles not a list', 'name: a\nobstacles: {pillar: 1}\n', 'obstacles'),
    ('obstacle not a mapping', 'name: a\nobstacles: [5]\n', 'obstacles[0]'),
    ('unknown key in obstacle', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    colour: red\n',
     'obstacles[0].colour'),
    ('yaw on a cylinder', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    yaw: 0.5\n',
     'obstacles[0].yaw'),
    ('missing obstacle name', 'name: a\nobstacles:\n  - {type: box, position: [2, 0], '
     'size: [1, 1, 1]}\n', 'obstacles[0].name'),
    ('missing type', 'name: a\nobstacles:\n  - {name: b, position: [2, 0], size: [1, 1, 1]}\n',
     'obstacles[0].type'),
    ('unknown type', 'name: a\nobstacles:\n  - {name: b, type: sphere, position: [2, 0]}\n',
     'obstacles[0].type'),
    ('missing size', 'name: a\nobstacles:\n  - {name: b, type: box, position: [2, 0]}\n',
     'obstacles[0].size'),
    ('missing position', 'name: a\nobstacles:\n  - {name: b, type: box, size: [1, 1, 1]}\n',
     'obstacles[0].position'),
    ('radius as a string', 'name: a\nobstacles:\n  - {name: c, type: cylinder, position: [2, 0], '
     'radius: "0.2", height: 1}\n', 'obstacles[0].radius'),
    ('position as a string', 'name: a\nobstacles:\n  - {name: c, type: cylinder, '
     'position: "2, 0", radius: 0.2, height: 1}\n', 'obstacles[0].position'),
    ('position with 4 numbers', 'name: a\nobstacles:\n  - {name: c, type: cylinder, '
     'position: [2, 0, 0, 1], radius: 0.2, height: 1}\n', 'obstacles[0].position'),
    ('position with inf', 'name: a\nobstacles:\n  - {name: c, type: cylinder, '
     'position: [.inf, 0], radius: 0.2, height: 1}\n', 'obstacles[0].position'),
    ('radius NaN', 'name: a\nobstacles:\n  - {name: c, type: cylinder, position: [2, 0], '
     'radius: .nan, height: 1}\n', 'obstacles[0].radius'),
    ('height -inf', 'name: a\nobstacles:\n  - {name: c, type: cylinder, position: [2, 0], '
     'radius: 0.2, height: -.inf}\n', 'obstacles[0].height'),
    ('box yaw NaN', 'name: a\nobstacles:\n  - {name: b, type: box, position: [2, 0], '
     'size: [1, 1, 1], yaw: .NaN}\n', 'obstacles[0].yaw'),
    ('size zero', 'name: a\nobstacles:\n  - {name: b, type: box, position: [2, 0], '
     'size: [0.1, 0, 1]}\n', 'obstacles[0].size'),
    ('size negative', 'name: a\nobstacles:\n  - {name: b, type: box, position: [2, 0], '
     'size: [-1, 1, 1]}\n', 'obstacles[0].size'),
    ('size with a bool', 'name: a\nobstacles:\n  - {name: b, type: box, position: [2, 0], '
     'size: [true, 1, 1]}\n', 'obstacles[0].size'),
    ('size 1e3 read by YAML as a string', 'name: a\nobstacles:\n  - {name: b, type: box, '
     'position: [2, 0], size: [1e3, 1, 1]}\n', 'obstacles[0].size'),
    ('position too large for a float', 'name: a\nobstacles:\n  - {name: b, type: box, '
     'position: [2, 1' + '0' * 400 + '], size: [1, 1, 1]}\n', 'obstacles[0].position'),
    ('size with 2 numbers', 'name: a\nobstacles:\n  - {name: b, type: box, position: [2, 0], '
     'size: [1, 1]}\n', 'obstacles[0].size'),
    ('radius zero', 'name: a\nobstacles:\n  - {name: c, type: cylinder, position: [2, 0], '
     'radius: 0, height: 1}\n', 'obstacles[0].radius'),
    ('radius negative', 'name: a\nobstacles:\n  - {name: c, type: cylinder, position: [2, 0], '
     'radius: -0.2, height: 1}\n', 'obstacles[0].radius'),
    ('height zero', 'name: a\nobstacles:\n  - {name: c, type: cylinder, position: [2, 0], '
     'radius: 0.2, height: 0}\n', 'obstacles[0].height'),
    ('wall thickness zero', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [2, 0], '
     'end: [2, 3], thickness: 0}\n', 'obstacles[0].thickness'),
    ('wall thickness negative', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [2, 0], '
     'end: [2, 3], thickness: -0.1}\n', 'obstacles[0].thickness'),
    ('wall height negative', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [2, 0], '
     'end: [2, 3], height: -1}\n', 'obstacles[0].height'),
    ('wall start equals end', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [2, 1], '
     'end: [2.0, 1.0]}\n', 'obstacles[0].end'),
    ('wall missing end', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [2, 1]}\n',
     'obstacles[0].end'),
    ('wall with position', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [2, 1], '
     'end: [3, 1], position: [2, 1]}\n', 'obstacles[0].position'),
    ('motion on a wall', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [2, 1], '
     'end: [3, 1], motion: {waypoints: [[1, 1]], speed: 1}}\n', 'obstacles[0].motion'),
    ('color with 3 items', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    color: [1, 0, 0]\n',
     'obstacles[0].color'),
    ('color above 1', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    color: [1.5, 0, 0, 1]\n',
     'obstacles[0].color'),
    ('color below 0', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    color: [0.5, -0.1, 0, 1]\n',
     'obstacles[0].color'),
    ('color in 0-255', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    color: [255, 0, 0, 255]\n',
     'obstacles[0].color'),
    ('color unknown name', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    color: purple\n',
     'obstacles[0].color'),
    ('color NaN', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    color: [.nan, 0, 0, 1]\n',
     'obstacles[0].color'),
    ('ground color with 3 items', 'name: a\nground: {color: [0.5, 0.5, 0.5]}\n', 'ground.color'),
    ('duplicate obstacle names', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + GOOD_OBSTACLE.replace('[2.0, 1.0]', '[4.0, 1.0]'), 'obstacles[1].name'),
    ('unknown key in motion', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [[3, 1]], speeed: 1}\n', 'obstacles[0].motion.speeed'),
    ('motion not a mapping', 'name: a\nobstacles:\n' + GOOD_OBSTACLE + '    motion: [[3, 1]]\n',
     'obstacles[0].motion'),
    ('empty waypoints', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [], speed: 1}\n', 'obstacles[0].motion.waypoints'),
    ('missing waypoints', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {speed: 1}\n', 'obstacles[0].motion.waypoints'),
    ('waypoint with 3 numbers', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [[3, 1], [3, 2, 0]], speed: 1}\n',
     'obstacles[0].motion.waypoints[1]'),
    ('waypoints all at the position', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [[2, 1]], speed: 1}\n', 'obstacles[0].motion.waypoints'),
    ('speed zero', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [[3, 1]], speed: 0}\n', 'obstacles[0].motion.speed'),
    ('speed negative', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [[3, 1]], speed: -0.3}\n', 'obstacles[0].motion.speed'),
    ('speed inf', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [[3, 1]], speed: .inf}\n', 'obstacles[0].motion.speed'),
    ('loop not a bool', 'name: a\nobstacles:\n' + GOOD_OBSTACLE
     + '    motion: {waypoints: [[3, 1]], speed: 1, loop: 1}\n', 'obstacles[0].motion.loop'),
    ('start inside a box', 'name: a\nobstacles:\n  - {name: b, type: box, position: [0.45, 0], '
     'size: [0.5, 0.5, 0.5]}\n', 'robot.start'),
    ('start inside a rotated box', 'name: a\nobstacles:\n  - {name: b, type: box, '
     'position: [0, 1.0], size: [2.0, 0.2, 1], yaw: 1.5707963}\n', 'robot.start'),
    ('start within clearance of a cylinder', 'name: a\nrobot: {start: {x: 1, y: 1}}\n'
     'obstacles:\n  - {name: c, type: cylinder, position: [1.44, 1], radius: 0.2, height: 1}\n',
     'robot.start'),
    ('start on a wall', 'name: a\nobstacles:\n  - {name: w, type: wall, start: [-1, 0.2], '
     'end: [1, 0.2]}\n', 'robot.start'),
    ('start where a mover begins', 'name: a\nobstacles:\n  - {name: m, type: cylinder, '
     'position: [0.3, 0], radius: 0.1, height: 1, motion: {waypoints: [[5, 0]], speed: 1}}\n',
     'robot.start'),
]


@pytest.mark.parametrize('text, field', [(t, f) for _, t, f in BAD_FILES],
                         ids=[case for case, _, _ in BAD_FILES])
def test_bad_file_names_file_and_field(tmp_path, text, field):
    path = tmp_path / 'bad_world.yaml'
    path.write_text(text)
    with pytest.raises(WorldError) as caught:
        load_world(str(path))
    message = str(caught.value)
    assert caught.value.field == field
    assert message.startswith(str(path) + ': ' + field + ': expected ')
    assert caught.value.source == str(path)


def test_every_bad_case_is_fine_once_the_fault_is_removed():
    # Guards the table above: the base texts must be valid, so each failure is the fault's doing.
    assert parse_world({'name': 'a', 'obstacles': [
        {'name': 'pillar', 'type': 'cylinder', 'position': [2.0, 1.0], 'radius': 0.2,
         'height': 1.0, 'motion': {'waypoints': [[3, 1]], 'speed': 1}}]})
    # Just outside the clearance radius or rotated away, the start is accepted.
    ok = parse_world({'name': 'a', 'robot': {'start': {'x': 1, 'y': 1}}, 'obstacles': [
        {'name': 'c', 'type': 'cylinder', 'position': [1.46, 1], 'radius': 0.2, 'height': 1},
        {'name': 'b', 'type': 'box', 'position': [1, 2.0], 'size': [2.0, 0.2, 1], 'yaw': 0.0},
        {'name': 'w', 'type': 'wall', 'start': [-1, 1.3], 'end': [3, 1.3]}]})
    assert len(ok.obstacles) == 3


def test_value_is_shown_in_the_message():
    with pytest.raises(WorldError) as caught:
        parse_world({'name': 'a', 'obstacles': [
            {'name': 'c', 'type': 'cylinder', 'position': [2, 0], 'radius': float('nan'),
             'height': 1}]}, source='inline.yaml')
    assert str(caught.value).startswith('inline.yaml: obstacles[0].radius: expected ')
    assert str(caught.value).endswith('got nan')


def test_yaml_syntax_error_names_file_and_line(tmp_path):
    path = tmp_path / 'broken.yaml'
    path.write_text(textwrap.dedent("""\
        name: broken
        obstacles:
          - name: b
            type: box
            size: [1, 1, 1
          - name: c
        """))
    with pytest.raises(WorldError) as caught:
        load_world(str(path))
    message = str(caught.value)
    assert message.startswith(str(path) + ': line ')
    line = int(message.split(': line ')[1].split(',')[0])
    # PyYAML notices the unclosed flow list on the line after it opened, or on that line; the
    # message then points back at the line where the list began.
    assert line in (5, 6)
    assert 'started on line 5' in message


def test_duplicate_yaml_key_names_file_and_line(tmp_path):
    path = tmp_path / 'dup.yaml'
    path.write_text('name: dup\nobstacles:\n  - name: b\n    type: box\n    position: [2, 0]\n'
                    '    size: [1, 1, 1]\n    position: [3, 0]\n')
    with pytest.raises(WorldError) as caught:
        load_world(str(path))
    assert str(caught.value).startswith(str(path) + ': line 7, column 5: expected valid YAML')
    assert 'position' in str(caught.value)


def test_missing_file_names_the_path(tmp_path):
    path = str(tmp_path / 'nowhere.yaml')
    with pytest.raises(WorldError) as caught:
        load_world(path)
    assert str(caught.value).startswith(path + ': ')
    assert caught.value.source == path


def test_directory_instead_of_file_is_a_world_error(tmp_path):
    with pytest.raises(WorldError) as caught:
        load_world(str(tmp_path))
    assert str(caught.value).startswith(str(tmp_path) + ': ')


# --- resolving names ---------------------------------------------------------------------------

def test_resolve_name_to_file_in_worlds_dir():
    assert resolve_world('wall', WORLDS_DIR) == os.path.join(WORLDS_DIR, 'wall.yaml')


def test_resolve_existing_path_is_returned_unchanged(tmp_path):
    path = tmp_path / 'mine.yaml'
    path.write_text('name: mine\n')
    assert resolve_world(str(path), WORLDS_DIR) == str(path)


@pytest.mark.parametrize('bad', ['wal', 'wall.yaml', '', '../worlds/wall'])
def test_resolve_unknown_name_lists_the_available_worlds(bad, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(WorldError) as caught:
        resolve_world(bad, WORLDS_DIR)
    message = str(caught.value)
    assert message.startswith(WORLDS_DIR + ': world: expected ')
    assert ', '.join(SHIPPED) in message
    assert message.endswith('got %r' % bad)


# --- moving obstacles --------------------------------------------------------------------------

def mover(loop, speed=0.5):
    """A cylinder starting at (0, 0) that moves via (4, 0) and (4, 3): legs of 4, 3 and 5 m."""
    return parse_world({'name': 'm', 'robot': {'start': {'x': -5, 'y': -5}}, 'obstacles': [
        {'name': 'm', 'type': 'cylinder', 'position': [0, 0], 'radius': 0.1, 'height': 1,
         'motion': {'waypoints': [[4, 0], [4, 3]], 'speed': speed, 'loop': loop}}]}).obstacles[0]


@pytest.mark.parametrize('loop', [True, False])
def test_mover_is_at_its_position_at_time_zero(loop):
    assert moving_obstacle_xy(mover(loop), 0.0) == (0.0, 0.0)


@pytest.mark.parametrize('t_s, xy', [
    (4.0, (2.0, 0.0)),      # mid first leg: 0.5 m/s x 4 s = 2 m
    (8.0, (4.0, 0.0)),      # the first corner
    (11.0, (4.0, 1.5)),     # mid second leg
    (14.0, (4.0, 3.0)),     # the far corner
    (19.0, (2.0, 1.5)),     # half way down the closing diagonal (5 m leg)
    (24.0, (0.0, 0.0)),     # one full 12 m cycle: back at the start
    (28.0, (2.0, 0.0)),     # wrapped into the second cycle
    (244.0, (2.0, 0.0)),    # ten cycles later, same place
])
def test_loop_mover_goes_round_the_closed_path(t_s, xy):
    assert moving_obstacle_xy(mover(True), t_s) == pytest.approx(xy, abs=1e-9)


@pytest.mark.parametrize('t_s, xy', [
    (4.0, (2.0, 0.0)),      # mid first leg
    (14.0, (4.0, 3.0)),     # the far end
    (16.0, (4.0, 2.0)),     # coming back the way it came, not along the diagonal
    (20.0, (4.0, 0.0)),     # back at the corner
    (24.0, (2.0, 0.0)),     # half way home
    (28.0, (0.0, 0.0)),     # home after 14 m
    (30.0, (1.0, 0.0)),     # and out again
])
def test_ping_pong_mover_returns_along_the_same_path(t_s, xy):
    assert moving_obstacle_xy(mover(False), t_s) == pytest.approx(xy, abs=1e-9)


def test_speed_scales_the_timing():
    assert moving_obstacle_xy(mover(True, speed=2.0), 1.0) == pytest.approx((2.0, 0.0))
    assert moving_obstacle_xy(mover(True, speed=2.0), 4.75) == pytest.approx((2.0, 1.5))


def test_motion_path_lengths_and_corners():
    points, length = motion_path(mover(True))
    assert points == [(0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (0.0, 0.0)]
    assert length == pytest.approx(12.0)
    points, length = motion_path(mover(False))
    assert points == [(0.0, 0.0), (4.0, 0.0), (4.0, 3.0), (4.0, 0.0), (0.0, 0.0)]
    assert length == pytest.approx(14.0)


def test_repeated_waypoint_does_not_stall_the_mover():
    obstacle = parse_world({'name': 'm', 'robot': {'start': {'x': -5, 'y': -5}}, 'obstacles': [
        {'name': 'm', 'type': 'box', 'position': [0, 0], 'size': [0.2, 0.2, 0.2],
         'motion': {'waypoints': [[2, 0], [2, 0]], 'speed': 1.0, 'loop': True}}]}).obstacles[0]
    assert moving_obstacle_xy(obstacle, 3.0) == pytest.approx((1.0, 0.0))


def test_static_obstacle_stays_put():
    wall = shipped('wall').obstacles[0]
    assert moving_obstacle_xy(wall, 0.0) == (3.05, 0.0)
    assert moving_obstacle_xy(wall, 123.4) == (3.05, 0.0)


@pytest.mark.parametrize('t_s', [-0.1, float('nan'), float('inf'), '1.0', None])
def test_bad_time_is_rejected(t_s):
    with pytest.raises(ValueError, match='t_s'):
        moving_obstacle_xy(mover(True), t_s)


def test_a_world_may_name_a_goal_outside_its_obstacles():
    world = parse_world({'name': 'g', 'goal': {'x': 7.0, 'y': -1}, 'obstacles': []})
    assert world.goal == (7.0, -1.0)
    assert parse_world({'name': 'g'}).goal is None
    assert load_world(os.path.join(WORLDS_DIR, 'obstacle_course.yaml')).goal == (7.0, 0.0)
    box = {'name': 'b', 'type': 'box', 'position': [7.0, 0.0], 'size': [1, 1, 1]}
    with pytest.raises(WorldError, match=r'goal: expected a point outside every obstacle, got .*inside b'):
        parse_world({'name': 'g', 'goal': {'x': 7.2, 'y': 0.1}, 'obstacles': [box]})
    with pytest.raises(WorldError, match=r'goal.y: expected a finite number \(m\)'):
        parse_world({'name': 'g', 'goal': {'x': 1.0, 'y': 'ahead'}})
    with pytest.raises(WorldError, match=r'goal.z: expected a known key'):
        parse_world({'name': 'g', 'goal': {'x': 1.0, 'y': 0.0, 'z': 0.0}})
