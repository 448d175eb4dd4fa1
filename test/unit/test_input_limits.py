"""Bad input named in one short line, limits checked before work: worlds, images, rates, commands, URDFs."""
import math

import numpy
import pytest

from closed_loop.control import decisions, vision
from closed_loop.sim import drive, world
from closed_loop import robot_model, yaml_check
from closed_loop.settings import MIN_RATE_HZ, SettingsError, check


def test_a_long_value_is_quoted_as_an_excerpt():
    text = yaml_check.quote('x' * 5000)
    assert len(text) < yaml_check.MAX_QUOTE_CHARS + 40 and '5002 characters in all' in text
    assert yaml_check.quote([1, 2]) == '[1, 2]'


def test_a_text_file_as_world_is_one_short_line(tmp_path):
    path = tmp_path / 'notes.txt'
    path.write_text('\n'.join('line %d of some text that is not a world' % i for i in range(1000)))
    with pytest.raises(world.WorldError) as error:
        world.load_world(path)
    message = str(error.value)
    assert '\n' not in message and len(message) < 400 and 'expected a mapping' in message


def test_size_and_count_limits_come_before_parsing(tmp_path):
    big = tmp_path / 'big.yaml'
    big.write_text('name: big\n#' + ' ' * world.MAX_WORLD_FILE_BYTES)
    with pytest.raises(world.WorldError, match='at most %d bytes' % world.MAX_WORLD_FILE_BYTES):
        world.load_world(big)
    many = {'name': 'many', 'obstacles': [{'name': 'c%d' % i, 'type': 'cylinder', 'position': [10 + i, 0],
                                           'radius': 0.1, 'height': 0.5} for i in range(world.MAX_OBSTACLES + 1)]}
    with pytest.raises(world.WorldError, match='at most %d obstacles' % world.MAX_OBSTACLES):
        world.parse_world(many)
    many['obstacles'].pop()
    assert len(world.parse_world(many).obstacles) == world.MAX_OBSTACLES


@pytest.mark.parametrize('shape, encoding', [((0, 0, 3), 'rgb8'), ((0, 4, 3), 'bgr8'), ((3, 0), 'mono8')])
def test_an_image_with_no_pixels_makes_no_claim(shape, encoding):
    with pytest.raises(vision.VisionError, match='no pixels'):
        vision.detect_red_encoded(numpy.zeros(shape, numpy.uint8), encoding, check(vision.VisionSettings()))


@pytest.mark.parametrize('rate', [0.001, 0.5, MIN_RATE_HZ - 1e-9])
def test_rates_below_the_floor_are_refused(rate):
    with pytest.raises(SettingsError, match='~rate_hz: expected at least'):
        check(decisions.StopSettings(rate_hz=rate))


def test_the_watchdog_looks_at_least_twice_per_timeout():
    assert check(decisions.StopSettings()).watchdog_period_s == pytest.approx(0.1)
    assert check(decisions.StopSettings(rate_hz=1.0, scan_timeout=0.5)).watchdog_period_s == pytest.approx(0.25)
    with pytest.raises(SettingsError, match='~scan_timeout'):
        check(decisions.StopSettings(scan_timeout=60.0))


def test_clipping_is_said_with_value_and_limit():
    found = drive.clipped_fields(drive.VelocityCommand(1e308, -4.0), 1.5, 3.0)
    assert found == ['linear.x 1e+308 m/s clipped to the limit 1.5 m/s (~max_linear_speed)',
                     'angular.z -4 rad/s clipped to the limit -3 rad/s (~max_angular_speed)']
    assert drive.clipped_fields(drive.VelocityCommand(1.5, 3.0), 1.5, 3.0) == []


def test_footprint_of_a_turned_and_offset_box():
    urdf = '''<robot name="r"><link name="base_footprint"/>
      <joint name="j" type="fixed"><parent link="base_footprint"/><child link="body"/>
        <origin xyz="0.1 0 0.05" rpy="0 0 1.5707963267948966"/></joint>
      <link name="body"><collision><geometry><box size="0.4 0.2 0.1"/></geometry></collision></link>
      <joint name="s" type="fixed"><parent link="body"/><child link="laser"/>
        <origin xyz="0.1 0 0.1" rpy="0 0 0.5"/></joint><link name="laser"/></robot>'''
    fp = robot_model.footprint(urdf)
    assert (fp.x_min, fp.x_max, fp.y_min, fp.y_max) == pytest.approx((0.0, 0.2, -0.2, 0.2))
    laser = robot_model.frame_pose_2d(urdf, 'laser')
    assert (laser.x, laser.y, laser.yaw) == pytest.approx((0.1, 0.1, math.pi / 2 + 0.5))


@pytest.mark.parametrize('urdf, match', [
    ('<robot', 'cannot parse'),
    ('<robot name="r"><link name="base_footprint"/></robot>', 'no collision shapes'),
    ('<robot name="r"><link name="base_footprint"><collision><geometry><mesh filename="x"/></geometry>'
     '</collision></link></robot>', "mesh 'x': expected package://PKG/path"),
    ('<robot name="r"><link name="base_link"/></robot>', "'base_footprint' is missing"),
])
def test_bad_urdfs_are_refused_by_name(urdf, match):
    with pytest.raises(robot_model.RobotModelError, match=match):
        robot_model.footprint(urdf)
