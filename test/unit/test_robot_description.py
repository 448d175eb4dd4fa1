"""A robot of the user's: a profile file anywhere that names a xacro description of another package (includes,
args, macros, STL and COLLADA collision meshes with a scale, a caster on a link of its own, the LIDAR on a mount:
test/fixtures/fixture_robot_description), expanded by xacro and driven in the simulator; and what is refused,
one line naming the file and what is wrong."""
import os
import shutil
import subprocess
import sys

import pytest

from closed_loop import description, robot_model, robot_names
from closed_loop.batch.episode import EpisodeSpec, run_episode
from closed_loop.sim import profiles
from closed_loop.sim.profiles import ProfileError, load_profile

# A robot's description is expanded by xacro through roslaunch's $(find): ROS 1 itself (not under make compat).
pytest.importorskip('roslaunch', reason='ROS 1 is not on this interpreter (make compat)')

FIXTURES = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'fixtures')
PACKAGE = os.path.join(FIXTURES, 'fixture_robot_description')
PROFILE = os.path.join(PACKAGE, 'config', 'my_robot.yaml')


def _forget_packages():
    description._rospack.cache_clear()
    from roslaunch import substitution_args       # xacro's $(find) goes through roslaunch's cached RosPack
    substitution_args._rospack = None


@pytest.fixture(autouse=True)
def package_path(monkeypatch):
    monkeypatch.setenv('ROS_PACKAGE_PATH', os.pathsep.join(filter(None, (FIXTURES, os.environ.get('ROS_PACKAGE_PATH')))))
    _forget_packages()
    yield
    _forget_packages()


def test_a_profile_file_is_found_by_path_by_find_and_as_a_sweep_names_it():
    for reference in (PROFILE, '$(find fixture_robot_description)/config/my_robot.yaml',
                      'fixture_robot_description/config/my_robot.yaml'):
        profile = load_profile(reference)
        assert profile.name == PROFILE and profile.source == os.path.join(PACKAGE, 'urdf', 'my_robot.urdf.xacro')
        assert profile.node_params('sim')['scan_frame'] == 'laser' and 'description' not in profile.params


def test_the_xacro_is_expanded_with_its_includes_macros_and_args(tmp_path):
    urdf = load_profile(PROFILE).urdf
    assert '<xacro:' not in urdf and 'left_wheel_joint' in urdf and 'right_wheel_link' in urdf
    _, poses = robot_model.link_transforms(urdf)
    # base_link 0.04 up (the wheel radius, a property); the LIDAR at the arg's height above it, through its mount.
    assert poses['laser'][2, 3] == pytest.approx(0.04 + 0.2) and poses['laser'][0, 3] == pytest.approx(0.05)
    other = tmp_path / 'tall.yaml'
    other.write_text(open(PROFILE).read().replace('lidar_height: 0.2', 'lidar_height: 0.3'))
    _, poses = robot_model.link_transforms(load_profile(str(other)).urdf)
    assert poses['laser'][2, 3] == pytest.approx(0.04 + 0.3)


def test_the_meshes_give_the_footprint_and_the_model():
    profile = load_profile(PROFILE)
    footprint = profile.footprint
    # The STL chassis is 0.36 m long (pybullet's hull of it, within 0.1 mm); the wheels reach 0.165 m to the side.
    assert footprint.x_max == pytest.approx(0.18, abs=1e-4) and footprint.x_min == pytest.approx(-0.18, abs=1e-4)
    assert footprint.y_max == pytest.approx(0.165) and footprint.y_min == pytest.approx(-0.165)
    # The COLLADA LIDAR, scaled 0.07 x 0.07 x 0.05 from a unit cube.
    (path, scale), = {(p, s) for _, p, s in description.meshes(profile.urdf, 'x') if p.endswith('.dae')}
    points = description.mesh_points(path, scale)
    assert points.max(axis=0) == pytest.approx([0.035, 0.035, 0.025], abs=1e-4)
    model = robot_model.load_robot_model(profile.urdf, robot_model.RobotNames(
        scan_frame='laser', camera_frame='', left_wheel_joints=('left_wheel_joint',),
        right_wheel_joints=('right_wheel_joint',)))
    assert model.wheel_radius_m == pytest.approx(0.04) and model.wheel_separation_m == pytest.approx(0.3)


def test_the_shipped_controllers_drive_it_in_process():
    stop = run_episode(EpisodeSpec(world='wall', controller='stop_on_obstacle', robot=PROFILE, time_limit_s=30))
    assert stop.outcome == 'stopped' and stop.contacts == 0 and abs(stop.final_pose[1]) < 0.02, stop.why
    # The caster on its own link slides: the robot goes straight and stops with the chassis' front short of 2.5 m.
    assert 2.2 < stop.final_pose[0] + 0.18 < 2.7, stop.final_pose
    course = run_episode(EpisodeSpec(world='obstacle_course', goal=(7.0, 0.0), controller='avoid_obstacles',
                                     robot=PROFILE, time_limit_s=40))
    assert course.outcome == 'reached' and course.contacts == 0, course.why


def test_what_plays_which_part_is_found_in_the_description():
    # The profile names none of them: the LIDAR on its mount, the wheels by side, no camera.
    profile = load_profile(PROFILE)
    assert profile.found == {'base_frame': 'base_footprint', 'body_link': 'base_link', 'scan_frame': 'laser',
                             'left_wheel_joints': 'left_wheel_joint', 'right_wheel_joints': 'right_wheel_joint',
                             'camera_frame': '', 'camera_optical_frame': 'camera_optical_frame'}
    assert profile.node_params('sim')['scan_frame'] == 'laser' and profile.node_params('avoid_obstacles') == {
        'max_speed': 0.5, 'scan_frame': 'laser'}
    # This package's robots without their profiles' names: the same as the profiles name them.
    for name, named in (('jackal', {'scan_frame': 'front_laser', 'left_wheel_joints': 'front_left_wheel_joint '
                                    'rear_left_wheel_joint', 'right_wheel_joints': 'front_right_wheel_joint '
                                    'rear_right_wheel_joint', 'camera_frame': ''}),
                        ('burger', {'scan_frame': 'base_scan', 'camera_frame': ''}),
                        ('closed_loop', {'scan_frame': 'base_scan', 'camera_frame': 'camera_link'})):
        found = robot_names.parts(load_profile(name).urdf)
        assert {k: found[k] for k in named} == named, (name, found)
    # What the profile names stays as it is; two candidates for the LIDAR leave the default (the load names it).
    assert robot_names.parts(profile.urdf, {'scan_frame': 'lidar_mount'})['scan_frame'] == 'lidar_mount'
    two = profile.urdf.replace('<link name="laser">', '<link name="laser"/><link name="rear_laser">', 1)
    assert robot_names.parts(two)['scan_frame'] == 'base_scan'


def test_the_command_prints_the_urdf_and_one_line_when_it_cannot(capsys):
    assert profiles.main([PROFILE]) == 0
    assert capsys.readouterr().out.startswith('<?xml')
    assert profiles.main(['/nowhere/robot.yaml']) == 1
    err = capsys.readouterr().err
    assert err.count('\n') == 1 and "/nowhere/robot.yaml" in err, err


def copy_package(tmp_path):
    folder = tmp_path / 'pkg'
    shutil.copytree(PACKAGE, str(folder))
    return folder


def refused(folder, match):
    with pytest.raises((ProfileError, robot_model.RobotModelError)) as error:
        load_profile(str(folder / 'config' / 'my_robot.yaml'))
    text = str(error.value)
    assert '\n' not in text and match in text, text
    return text


def use_copy(folder):
    """The copy's profile names its own files (not the package's, by $(find))."""
    profile = folder / 'config' / 'my_robot.yaml'
    profile.write_text(profile.read_text().replace('$(find fixture_robot_description)/urdf/', '../urdf/'))
    for xacro_file in (folder / 'urdf').iterdir():
        xacro_file.write_text(xacro_file.read_text().replace('$(find fixture_robot_description)', str(folder))
                              .replace('package://fixture_robot_description', 'file://' + str(folder)))


def test_a_xacro_that_includes_itself_is_refused(tmp_path):
    folder = copy_package(tmp_path)
    use_copy(folder)
    wheel = folder / 'urdf' / 'wheel.xacro'
    wheel.write_text(wheel.read_text().replace('<xacro:macro', '<xacro:include filename="%s"/>\n  <xacro:macro' % wheel, 1))
    refused(folder, 'my_robot.urdf.xacro: its xacro includes itself')


def test_a_missing_a_huge_and_an_ascii_mesh_are_refused(tmp_path):
    folder = copy_package(tmp_path)
    use_copy(folder)
    chassis = folder / 'meshes' / 'chassis.stl'
    chassis.unlink()
    refused(folder, 'chassis.stl: no such file')
    with open(str(chassis), 'wb') as f:                  # 50 MB, sparse
        f.truncate(50 * 1024 * 1024)
    refused(folder, 'chassis.stl: 52.4 MB, over the 20 MB a mesh may have')
    chassis.write_text('solid chassis\nendsolid chassis\n')
    refused(folder, 'chassis.stl: not a binary STL (an ASCII one)')
    (folder / 'meshes' / 'lidar.dae').rename(folder / 'meshes' / 'lidar.ply')
    shutil.copy(os.path.join(PACKAGE, 'meshes', 'chassis.stl'), str(chassis))
    refused(folder, 'lidar.dae: no such file')


def test_a_relative_mesh_a_xacro_error_and_a_profile_without_description_are_refused(tmp_path):
    folder = copy_package(tmp_path)
    use_copy(folder)
    robot = folder / 'urdf' / 'my_robot.urdf.xacro'
    text = robot.read_text()
    robot.write_text(text.replace('file://%s/meshes/chassis.stl' % folder, 'meshes/chassis.stl'))
    refused(folder, "mesh 'meshes/chassis.stl': expected package://PKG/path, file:///path or an absolute path")
    robot.write_text(text.replace('${wheel_radius}"/>', '${wheel_radiuss}"/>', 1))
    refused(folder, 'my_robot.urdf.xacro: xacro:')
    profile = folder / 'config' / 'my_robot.yaml'
    profile.write_text('sim: {scan_frame: laser}\n')
    refused(folder, "description: expected a mapping with 'file'")


def test_a_path_out_of_its_package_is_refused():
    for reference in ('$(find fixture_robot_description)/../fixture_controllers/package.xml',
                      'package://fixture_robot_description/../../x.stl', 'fixture_robot_description/../x.yaml'):
        with pytest.raises(description.DescriptionError, match='leads out of its package'):
            description.resolve(reference, 'here', package_relative=True)


def test_a_description_that_cannot_drive_says_so(tmp_path):
    folder = copy_package(tmp_path)
    use_copy(folder)
    wheel = folder / 'urdf' / 'wheel.xacro'
    wheel.write_text(wheel.read_text().replace('type="continuous"', 'type="fixed"'))
    profile = load_profile(str(folder / 'config' / 'my_robot.yaml'))
    with pytest.raises(robot_model.RobotModelError, match="joint 'wheel_left_joint' is missing; the description has "
                                                          "no continuous joints: without wheels it cannot drive"):
        run_episode(EpisodeSpec(world='wall', controller='stop_on_obstacle', robot=profile.name, time_limit_s=5))


def test_the_launch_files_script_is_installed_and_runs(tmp_path):
    script = os.path.join(os.path.dirname(FIXTURES), '..', 'scripts', 'robot_description')
    done = subprocess.run([sys.executable, script, PROFILE], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, timeout=60, env=dict(os.environ, PYTHONPATH=os.pathsep.join(
                              sys.path)))
    assert done.returncode == 0 and 'fixture_robot_description/meshes/chassis.stl' in done.stdout, done.stderr


def test_a_world_of_several_robots_takes_a_profile_file_and_knows_it_however_written():
    from closed_loop.nodes.sim_node import same_profile
    from closed_loop.sim.world import WorldError, parse_world
    robots = [{'name': 'r1', 'profile': 'fixture_robot_description/config/my_robot.yaml'},
              {'name': 'r2', 'profile': 'closed_loop', 'start': {'x': 4.0, 'y': 0.0, 'yaw': 3.14159}}]
    world = parse_world({'name': 'two', 'robots': robots})
    assert [r.profile for r in world.robots] == ['fixture_robot_description/config/my_robot.yaml', 'closed_loop']
    # The launch gives it as $(find) made it: the same profile; another file, or a name, is not.
    assert same_profile(PROFILE, 'fixture_robot_description/config/my_robot.yaml')
    assert same_profile('$(find fixture_robot_description)/config/my_robot.yaml', PROFILE)
    assert not same_profile(PROFILE, 'fixture_robot_description/config/other.yaml')
    assert not same_profile('closed_loop', 'burger') and same_profile('burger', 'burger')
    with pytest.raises(WorldError, match=r"robots\[0\]\.profile: expected a robot profile name"):
        parse_world({'name': 'two', 'robots': [{'name': 'r1', 'profile': '../robot.urdf'}]})
