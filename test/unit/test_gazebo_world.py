"""A Gazebo world as a world: boxes, cylinders, a sphere, a mesh, a nested model and an included one (found on
GAZEBO_MODEL_PATH), poses composed; a mesh and a tilted box stand as the boxes of their footprints; what is left
out or approximated named; the same scan to the bit as the same world written
in this package's YAML; faulty worlds refused in one line."""
import math
import os
import shutil

import numpy
import pytest
import yaml

from closed_loop.batch.episode import EpisodeSpec, run_episode
from closed_loop.sim import mesh_footprint, shapes
from closed_loop.sim.sensors.lidar import Lidar, LidarSettings
from closed_loop.sim.simulation import RobotSetup, SimSettings, Simulation
from closed_loop.sim.world import WorldError, load_world

CHASSIS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'fixtures',
                       'fixture_robot_description', 'meshes', 'chassis.stl')

POST = '''<?xml version="1.0"?>
<sdf version="1.6">
  <model name="post">
    <static>true</static>
    <link name="link">
      <pose>0 0 0.5 0 0 0</pose>
      <collision name="collision"><geometry><cylinder><radius>0.1</radius><length>1.0</length></cylinder></geometry></collision>
      <visual name="visual"><geometry><cylinder><radius>0.1</radius><length>1.0</length></cylinder></geometry></visual>
    </link>
  </model>
</sdf>
'''
CRATE = '''<?xml version="1.0"?>
<sdf version="1.6">
  <model name="crate">
    <static>true</static>
    <link name="link">
      <collision name="collision"><pose>0 0 0.05 0 0 0</pose>
        <geometry><mesh><uri>model://crate/meshes/crate.stl</uri><scale>2 1 1</scale></mesh></geometry></collision>
    </link>
  </model>
</sdf>
'''
CONFIG = '<?xml version="1.0"?><model><name>%s</name><sdf version="1.6">model.sdf</sdf></model>\n'

#: The world's shapes that stand upright (its boxes, cylinders, the nested model and the included post).
UPRIGHT = '''
    <model name="wall">
      <static>true</static>
      <pose>3 0 0.5 0 0 0</pose>
      <link name="link">
        <collision name="collision"><geometry><box><size>0.2 4 1</size></box></geometry></collision>
        <visual name="visual"><geometry><box><size>0.2 4 1</size></box></geometry></visual>
      </link>
    </model>
    <model name="barrel">
      <static>true</static>
      <pose>1.5 -1 0.25 0 0 0</pose>
      <link name="link"><collision name="c"><geometry><cylinder><radius>0.25</radius><length>0.5</length></cylinder></geometry></collision></link>
    </model>
    <model name="table">
      <static>true</static>
      <pose>1 1.5 0 0 0 0</pose>
      <model name="leg">
        <pose>0.5 0.25 0 0 0 0</pose>
        <link name="link">
          <pose>0 0 0.375 0 0 0</pose>
          <collision name="c"><geometry><box><size>0.1 0.1 0.75</size></box></geometry></collision>
        </link>
      </model>
    </model>
    <include>
      <uri>model://post</uri>
      <name>post_a</name>
      <pose>2 -1.5 0 0 0 0</pose>
    </include>
'''
YAML_WORLD = {'name': 'same', 'obstacles': [
    {'name': 'wall/link/collision', 'type': 'box', 'position': [3.0, 0.0, 0.5], 'size': [0.2, 4.0, 1.0], 'yaw': 0.0},
    {'name': 'barrel/link/c', 'type': 'cylinder', 'position': [1.5, -1.0, 0.25], 'radius': 0.25, 'height': 0.5},
    {'name': 'table/leg/link/c', 'type': 'box', 'position': [1.5, 1.75, 0.375], 'size': [0.1, 0.1, 0.75],
     'yaw': 0.0},
    {'name': 'post_a/link/collision', 'type': 'cylinder', 'position': [2.0, -1.5, 0.5], 'radius': 0.1,
     'height': 1.0}]}
EXTRAS = '''
    <include><uri>model://ground_plane</uri></include>
    <include><uri>model://sun</uri></include>
    <include><uri>model://crate</uri><pose>-2 0 0 0 0 0.5</pose></include>
    <include><uri>model://nowhere_to_be_found</uri></include>
    <model name="ball">
      <static>true</static>
      <link name="link"><pose>-1 2 0.3 0 0 0</pose><collision name="c"><geometry><sphere><radius>0.3</radius></sphere></geometry></collision></link>
    </model>
    <model name="ramp">
      <static>true</static>
      <pose>-1 -2 0.2 0.3 0 0</pose>
      <link name="link"><collision name="c"><geometry><box><size>1 1 0.1</size></box></geometry></collision></link>
    </model>
    <plugin name="clock_plugin" filename="libgazebo_ros_init.so"/>
    <actor name="walker"><skin><filename>walk.dae</filename></skin></actor>
'''


def world_file(folder, models, name='test.world'):
    path = folder / name
    path.write_text('<?xml version="1.0"?>\n<sdf version="1.6">\n  <world name="test">%s  </world>\n</sdf>\n' % models)
    return str(path)


@pytest.fixture
def model_path(tmp_path, monkeypatch):
    models = tmp_path / 'models'
    for name, sdf in (('post', POST), ('crate', CRATE)):
        (models / name).mkdir(parents=True)
        (models / name / 'model.config').write_text(CONFIG % name)
        (models / name / 'model.sdf').write_text(sdf)
    (models / 'crate' / 'meshes').mkdir()
    shutil.copy(CHASSIS, str(models / 'crate' / 'meshes' / 'crate.stl'))
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(tmp_path / 'elsewhere') + os.pathsep + str(models))
    return models


def test_the_shapes_stand_where_their_composed_poses_put_them(tmp_path, model_path):
    world = load_world(world_file(tmp_path, UPRIGHT + EXTRAS))
    by_name = {o.name: o for o in world.obstacles}
    footprints = {}
    for o in world.obstacles:
        if o.name.startswith(('crate/', 'ramp/')):
            footprints.setdefault(o.name.rsplit('_', 1)[0], []).append(o)
    assert set(by_name) - {o.name for boxes in footprints.values() for o in boxes} == {
        'wall/link/collision', 'barrel/link/c', 'table/leg/link/c', 'post_a/link/collision', 'ball/link/c'}
    assert by_name['table/leg/link/c'].position == (1.5, 1.75, 0.375)      # model, nested model, link
    assert by_name['post_a/link/collision'].position == (2.0, -1.5, 0.5) and by_name['post_a/link/collision'].radius == 0.1
    ball = by_name['ball/link/c']                                       # a sphere: the cylinder round it
    assert (ball.shape, ball.radius, ball.size[2], ball.position) == ('cylinder', 0.3, 0.6, (-1.0, 2.0, 0.3))
    # The mesh (an STL 0.36 x 0.26 x 0.1, scaled 2 x 1 x 1, from the ground up), turned 0.5 rad: the boxes of
    # its footprint, 0.72 x 0.26 turned, to within a cell, standing 0.1 m from the ground.
    crate = footprints['crate/link/collision']
    assert_footprint(crate, (-2.0, 0.0), 0.5, (0.72, 0.26))
    assert all(o.position[2] - o.size[2] / 2 == 0.0 and o.position[2] + o.size[2] / 2 == pytest.approx(0.1)
               for o in crate)
    # A box 1 x 1 x 0.1 tilted 0.3 rad about x, its centre 0.2 m up: seen from above it is 1 wide and
    # cos(0.3) + 0.1 sin(0.3) deep; its lowest edge is within the floor band, so it stands from the ground to
    # its highest, 0.2 + 0.5 sin(0.3) + 0.05 cos(0.3).
    ramp = footprints['ramp/link/c']
    assert_footprint(ramp, (-1.0, -2.0), 0.0, (1.0, math.cos(0.3) + 0.1 * math.sin(0.3)))
    top = 0.2 + 0.5 * math.sin(0.3) + 0.05 * math.cos(0.3)
    assert all(o.position[2] - o.size[2] / 2 == 0.0 and o.position[2] + o.size[2] / 2 == pytest.approx(top)
               for o in ramp)
    left = '; '.join(world.left_out)
    for said in ('plugin clock_plugin', 'actor walker', 'model://nowhere_to_be_found: model not found on '
                 'GAZEBO_MODEL_PATH', 'ball/link/c: a sphere', 'crate/link/collision: a mesh (its footprint, %d '
                 'boxes of 0.05 m cells)' % len(crate), 'ramp/link/c: a tilted box (its footprint'):
        assert said in left, left
    assert 'ground_plane' not in left and 'sun' not in left


def assert_footprint(boxes, centre, yaw, size):
    """Every point of the rectangle ``size`` at ``centre`` turned by ``yaw`` is in one of ``boxes``, and every
    point of theirs within one cell's diagonal of it."""
    c, s = math.cos(yaw), math.sin(yaw)
    xs, ys = numpy.meshgrid(numpy.arange(-1.0, 1.0, 0.01), numpy.arange(-1.0, 1.0, 0.01))
    for x, y in zip(xs.ravel() + centre[0], ys.ravel() + centre[1]):
        u, v = c * (x - centre[0]) + s * (y - centre[1]), -s * (x - centre[0]) + c * (y - centre[1])
        outside = math.hypot(max(abs(u) - size[0] / 2, 0.0), max(abs(v) - size[1] / 2, 0.0))
        covered = min(shapes.distance(o, x, y) for o in boxes) <= 0.0
        assert covered or outside > 0.0, (x, y)
        assert not covered or outside <= mesh_footprint.CELL_M * math.sqrt(2) + 1e-9, (x, y, outside)


def test_the_same_world_in_yaml_gives_the_same_scan_to_the_bit(tmp_path, model_path):
    yaml_path = tmp_path / 'same.yaml'
    yaml_path.write_text(yaml.safe_dump(YAML_WORLD))
    scans = []
    for path in (world_file(tmp_path, UPRIGHT), str(yaml_path)):
        world = load_world(path)
        settings = SimSettings()
        sim = Simulation(world, settings, robots=[RobotSetup('', settings, None, world.robot_start)])
        try:
            for caster in ('planar', 'pybullet'):
                view = sim.view(0)
                scans.append(Lidar(LidarSettings(scan_samples=720, ray_caster=caster), view).sample(view))
        finally:
            sim.close()
    gazebo_planar, gazebo_bullet, yaml_planar, yaml_bullet = scans
    assert numpy.array_equal(gazebo_planar, yaml_planar) and numpy.array_equal(gazebo_bullet, yaml_bullet)
    assert numpy.isfinite(gazebo_planar).sum() > 100          # (it sees the wall, the barrel, the post)


@pytest.mark.parametrize('world, message', [
    ('<sdf><world name="w"><model name="m">', "expected SDF (XML), got 'XML that does not parse (no element found"),
    ('<sdf><model name="m"/></sdf>', 'expected an SDF world (<sdf><world>...), got'),
    ('<sdf><world name="w"><model name="m"><link name="l"><collision name="c"><geometry><box><size>1 0 1</size>'
     '</box></geometry></collision></link></model></world></sdf>', "m/l/c: box geometry with its sizes as numbers > 0, "
                                                                   "got '<box><size>1 0 1</size></box>'"),
    ('<sdf><world name="w"><model name="m"><pose>1 2 nan 0 0 0</pose></model></world></sdf>',
     "m: a pose of six finite numbers (x y z roll pitch yaw), got '1 2 nan 0 0 0'"),
    ('<sdf><world name="w"><include><uri>model://../models/post</uri></include></world></sdf>',
     'expected a model inside its folder on GAZEBO_MODEL_PATH'),
])
def test_a_faulty_world_is_refused_in_one_line(tmp_path, model_path, world, message):
    path = tmp_path / 'bad.world'
    path.write_text(world)
    with pytest.raises(WorldError) as error:
        load_world(str(path))
    assert str(error.value).startswith(str(path) + ': (Gazebo world): ') and message in str(error.value)
    assert '\n' not in str(error.value)


def test_a_model_that_includes_itself_and_a_world_of_a_hundred_thousand_models_are_refused(tmp_path, model_path):
    (model_path / 'post' / 'model.sdf').write_text(POST.replace('</model>', '<include><uri>model://post</uri>'
                                                                            '</include></model>'))
    with pytest.raises(WorldError, match='includes nested at most 16 deep'):
        load_world(world_file(tmp_path, '<include><uri>model://post</uri></include>'))
    many = ''.join('<model name="m%d"><static>true</static><link name="l"><collision name="c"><geometry><box>'
                   '<size>1 1 1</size></box></geometry></collision></link></model>' % i for i in range(100000))
    with pytest.raises(WorldError, match='bytes'):
        load_world(world_file(tmp_path, many, 'many.world'))
    few_thousand = many[:many.index('<model name="m2500">')]
    with pytest.raises(WorldError, match='at most 2000 shapes'):
        load_world(world_file(tmp_path, few_thousand, 'thousands.world'))


def test_a_saved_worlds_state_and_an_includes_pose_stand_in_for_the_models_own(tmp_path, model_path):
    # Gazebo saves where each model stood in <state>, and applies it over the models' poses; an <include>'s
    # pose stands in for the included model's own (the post's model has one of its own here: left aside).
    (model_path / 'post' / 'model.sdf').write_text(POST.replace('<static>true</static>',
                                                                '<static>true</static><pose>5 5 0 0 0 0</pose>'))
    world = load_world(world_file(tmp_path, UPRIGHT + '''
    <include><uri>model://post</uri><name>post_b</name></include>
    <state world_name="test">
      <model name="wall"><pose>4 1 0.5 0 0 0</pose></model>
      <model name="post_b"><pose>-3 0 0 0 0 0</pose></model>
    </state>'''))
    at = {o.name: o.position for o in world.obstacles}
    assert at['wall/link/collision'] == (4.0, 1.0, 0.5)                 # the state's, not the model's 3 0 0.5
    assert at['post_a/link/collision'] == (2.0, -1.5, 0.5)              # the include's pose, not 5 5 0 + it
    assert at['post_b/link/collision'] == (-3.0, 0.0, 0.5)              # the state's pose of an include


def building_mesh(path):
    """An STL of two rooms (8 x 4 m inside, 0.1 m walls 2.5 m high) with a door 1 m wide from one to the other
    at y 0.5 to 1.5, on a floor slab 2 cm thick, under a lamp hanging at 2.4 m: one mesh, as a building's
    model often is."""
    import trimesh
    parts = [((4.0, -0.05, 1.25), (8.2, 0.1, 2.5)), ((4.0, 4.05, 1.25), (8.2, 0.1, 2.5)),
             ((-0.05, 2.0, 1.25), (0.1, 4.0, 2.5)), ((8.05, 2.0, 1.25), (0.1, 4.0, 2.5)),
             ((4.0, 0.25, 1.25), (0.1, 0.5, 2.5)), ((4.0, 2.75, 1.25), (0.1, 2.5, 2.5)),      # the door between
             ((4.0, 2.0, 0.01), (8.4, 4.4, 0.02)), ((2.0, 2.0, 2.45), (0.4, 0.4, 0.1))]      # the floor, the lamp
    meshes = []
    for centre, size in parts:
        box = trimesh.creation.box(extents=size)
        box.apply_translation(centre)
        meshes.append(box)
    trimesh.util.concatenate(meshes).export(str(path))


def test_a_building_that_is_one_mesh_stands_as_its_walls_and_the_navigator_goes_through_its_door(tmp_path,
                                                                                                  model_path):
    (model_path / 'building' / 'meshes').mkdir(parents=True)
    building_mesh(model_path / 'building' / 'meshes' / 'building.stl')
    (model_path / 'building' / 'model.config').write_text(CONFIG % 'building')
    (model_path / 'building' / 'model.sdf').write_text(CRATE.replace('crate', 'building').replace(
        '<pose>0 0 0.05 0 0 0</pose>', '').replace('<scale>2 1 1</scale>', ''))
    path = world_file(tmp_path, '<include><uri>model://building</uri></include>')
    world = load_world(path, check_starts=False)
    solid = lambda x, y: any(shapes.distance(o, x, y) <= 0.0 for o in world.obstacles)     # noqa: E731
    assert not solid(2.0, 2.0) and not solid(6.0, 2.0)          # the floor slab and the lamp stand in no way
    assert solid(4.0, 3.0) and solid(4.0, 0.2) and not solid(4.0, 1.0)     # the wall between, and its door
    assert solid(-0.05, 2.0) and solid(4.0, 4.05) and not solid(3.8, 1.0)
    assert max(o.position[2] + o.size[2] / 2 for o in world.obstacles) == pytest.approx(mesh_footprint.OVERHEAD_M)
    assert len(world.obstacles) < 40                            # walls along the cells merge into few boxes
    result = run_episode(EpisodeSpec(world=path, controller='avoid_obstacles', goal=(6.5, 2.0),
                                     sim={'start': '1.5 2.5 0'}, time_limit_s=90.0))
    assert result.outcome == 'reached' and result.contacts == 0, result.why


def test_a_mesh_below_the_floor_band_or_overhead_is_named_and_stands_nowhere(tmp_path, model_path):
    (model_path / 'crate' / 'model.sdf').write_text(CRATE.replace('<pose>0 0 0.05 0 0 0</pose>',
                                                                  '<pose>0 0 2.5 0 0 0</pose>'))
    world = load_world(world_file(tmp_path, '<include><uri>model://crate</uri><pose>1 1 0 0 0 0</pose></include>'))
    assert not world.obstacles
    assert 'crate/link/collision: a mesh, all of it below 0.05 m or above 2 m (no obstacle)' in world.left_out


def test_a_collada_mesh_stands_as_its_footprint(tmp_path, model_path):
    """A COLLADA mesh (the fixture robot's LIDAR housing, a 1 m cube about its origin), scaled and placed."""
    shutil.copy(os.path.join(os.path.dirname(CHASSIS), 'lidar.dae'), str(model_path / 'crate' / 'meshes'))
    (model_path / 'crate' / 'model.sdf').write_text(CRATE.replace('crate.stl', 'lidar.dae').replace(
        '<pose>0 0 0.05 0 0 0</pose>', '<pose>0 0 0.3 0 0 0</pose>').replace('2 1 1', '0.8 0.4 0.6'))
    world = load_world(world_file(tmp_path, '<include><uri>model://crate</uri><pose>2 1 0 0 0 0.3</pose></include>'))
    assert_footprint(world.obstacles, (2.0, 1.0), 0.3, (0.8, 0.4))
    assert all(o.position[2] - o.size[2] / 2 == 0.0 and o.position[2] + o.size[2] / 2 == pytest.approx(0.6)
               for o in world.obstacles)
