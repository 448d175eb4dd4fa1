"""Red detection: both ends of the hue circle, non-reds, area threshold, centroids, encodings."""
import dataclasses
import os
import subprocess
import sys

import cv2
import numpy
import pytest

from closed_loop.image_encoding import array_to_image, image_to_array, to_bgr8
from closed_loop.settings import SettingsError, check, from_params
from closed_loop.control.vision import (RedDetection, VisionError, VisionSettings, detect_red,
                                detect_red_encoded, red_mask)

HEIGHT, WIDTH = 60, 80
GREY = (128, 128, 128)


def hsv_to_bgr(hue, saturation, value):
    """The BGR pixel of an OpenCV HSV colour, checked to convert back to the same hue."""
    bgr = cv2.cvtColor(numpy.uint8([[[hue, saturation, value]]]), cv2.COLOR_HSV2BGR)[0, 0]
    back = cv2.cvtColor(bgr.reshape(1, 1, 3), cv2.COLOR_BGR2HSV)[0, 0]
    assert int(back[0]) == hue, 'test colour does not keep its hue through BGR'
    return tuple(int(c) for c in bgr)


def scene(colour, count, background=GREY):
    """A grey BGR image whose first ``count`` pixels (row by row) have ``colour``."""
    image = numpy.empty((HEIGHT, WIDTH, 3), numpy.uint8)
    image[:] = background
    image.reshape(-1, 3)[:count] = colour
    return image


def settings(**overrides):
    return check(dataclasses.replace(VisionSettings(), **overrides))


def test_defaults_are_the_lessons_thresholds_plus_the_upper_hue_band():
    s = check(VisionSettings())
    assert (s.hue_low_max, s.saturation_min, s.value_min, s.min_area_px) == (10, 100, 100, 100)
    assert s.hue_high_min == 170


@pytest.mark.parametrize('hue', [0, 5, 10, 170, 175, 179])
def test_saturated_red_at_both_ends_of_the_hue_circle(hue):
    result = detect_red(scene(hsv_to_bgr(hue, 255, 255), 500), VisionSettings())
    assert result.detected
    assert result.area_px == 500


def test_pure_bgr_red_is_red():
    result = detect_red(scene((0, 0, 255), 500), VisionSettings())
    assert result.detected and result.area_px == 500


def test_upper_band_off_reproduces_the_lesson_rule():
    image = scene(hsv_to_bgr(175, 255, 255), 500)
    assert not detect_red(image, settings(hue_high_min=180)).detected
    assert detect_red(scene((0, 0, 255), 500), settings(hue_high_min=180)).detected


@pytest.mark.parametrize('name, colour', [
    ('green', (0, 255, 0)),
    ('blue', (255, 0, 0)),
    ('orange hue 20', hsv_to_bgr(20, 255, 255)),
    ('just past the low band, hue 11', hsv_to_bgr(11, 255, 255)),
    ('just before the high band, hue 169', hsv_to_bgr(169, 255, 255)),
    ('dark red below value_min', hsv_to_bgr(0, 255, 99)),
    ('pale red below saturation_min', hsv_to_bgr(0, 99, 255)),
    ('grey', GREY),
    ('white', (255, 255, 255)),
    ('black', (0, 0, 0)),
])
def test_non_red_colours(name, colour):
    result = detect_red(scene(colour, 1000, background=(0, 0, 0)), VisionSettings())
    assert not result.detected, name
    assert result.area_px == 0, name
    assert result.centroid_px is None
    assert not result.mask.any()


def test_value_and_saturation_minimums_are_inclusive():
    assert detect_red(scene(hsv_to_bgr(0, 255, 100), 200), VisionSettings()).area_px == 200
    assert detect_red(scene(hsv_to_bgr(0, 100, 255), 200), VisionSettings()).area_px == 200


def test_area_threshold_is_strictly_more_than_min_area():
    red = (0, 0, 255)
    at = detect_red(scene(red, 100), VisionSettings())
    above = detect_red(scene(red, 101), VisionSettings())
    assert (at.detected, at.area_px, at.centroid_px) == (False, 100, None)
    assert (above.detected, above.area_px) == (True, 101)
    assert above.centroid_px is not None
    assert detect_red(scene(red, 1), settings(min_area_px=0)).detected
    assert not detect_red(scene(red, 0), settings(min_area_px=0)).detected


def test_centroid_and_mask_of_a_known_rectangle():
    image = scene(GREY, 0)
    image[10:20, 30:50] = (0, 0, 255)  # rows v 10..19, columns u 30..49
    result = detect_red(image, settings(min_area_px=10))
    assert result.detected and result.area_px == 200
    assert result.centroid_px == pytest.approx((39.5, 14.5))
    assert result.mask.shape == (HEIGHT, WIDTH) and result.mask.dtype == numpy.uint8
    expected = numpy.zeros((HEIGHT, WIDTH), numpy.uint8)
    expected[10:20, 30:50] = 255
    numpy.testing.assert_array_equal(result.mask, expected)
    numpy.testing.assert_array_equal(red_mask(image, VisionSettings()), expected)


def test_centroid_of_two_bands_lies_between_them():
    image = scene(GREY, 0)
    image[0:10, 0:10] = hsv_to_bgr(0, 255, 255)
    image[0:10, 70:80] = hsv_to_bgr(175, 255, 255)
    result = detect_red(image, VisionSettings())
    assert result.area_px == 200
    assert result.centroid_px == pytest.approx((39.5, 4.5))


def _mixed_scene():
    image = scene(GREY, 0)
    image[5:25, 10:30] = (0, 0, 255)
    image[30:50, 40:70] = (0, 255, 0)
    image[40:55, 0:20] = (255, 0, 0)
    image[50:58, 60:78] = hsv_to_bgr(176, 230, 200)
    return image


def _same(a, b):
    assert (a.detected, a.area_px) == (b.detected, b.area_px)
    assert a.centroid_px == pytest.approx(b.centroid_px)
    numpy.testing.assert_array_equal(a.mask, b.mask)


def test_rgb8_and_bgr8_messages_of_one_scene_give_the_same_answer():
    bgr_scene = _mixed_scene()
    expected = detect_red(bgr_scene, VisionSettings())
    assert expected.detected and expected.area_px == 400 + 144
    rgb_fields = array_to_image(numpy.ascontiguousarray(bgr_scene[:, :, ::-1]), 'rgb8')
    bgr_fields = array_to_image(bgr_scene, 'bgr8')
    rgb = image_to_array('rgb8', *rgb_fields)
    bgr = image_to_array('bgr8', *bgr_fields)
    for encoding, array in (('rgb8', rgb), ('bgr8', bgr)):
        _same(detect_red(to_bgr8(array, encoding), VisionSettings()), expected)
        _same(detect_red_encoded(array, encoding, VisionSettings()), expected)
    # The comparison can tell the orders apart: read as BGR, the RGB red square is blue.
    assert detect_red(rgb, VisionSettings()).area_px != expected.area_px


def test_mono8_is_never_red():
    bright = numpy.full((HEIGHT, WIDTH), 255, numpy.uint8)
    result = detect_red_encoded(bright, 'mono8', settings(min_area_px=0))
    assert not result.detected and result.area_px == 0 and result.centroid_px is None
    assert result.mask.shape == (HEIGHT, WIDTH) and not result.mask.any()


def test_bad_images_and_encodings_are_refused_by_name():
    with pytest.raises(VisionError, match='^encoding:'):
        detect_red_encoded(scene(GREY, 0), 'rgba8', VisionSettings())
    with pytest.raises(VisionError, match='^array:'):
        detect_red_encoded(numpy.zeros((4, 4), numpy.uint8), 'rgb8', VisionSettings())
    with pytest.raises(VisionError, match='^array:'):
        detect_red_encoded(numpy.zeros((4, 4, 3), numpy.uint8), 'mono8', VisionSettings())
    with pytest.raises(VisionError, match='^bgr:'):
        detect_red(numpy.zeros((4, 4), numpy.uint8), VisionSettings())
    with pytest.raises(VisionError, match='^bgr:'):
        detect_red(numpy.zeros((4, 4, 3), numpy.float32), VisionSettings())
    with pytest.raises(VisionError, match='^bgr:'):
        red_mask([[0, 0, 255]], VisionSettings())


def test_empty_and_non_contiguous_images():
    empty = detect_red(numpy.zeros((0, 5, 3), numpy.uint8), settings(min_area_px=0))
    assert not empty.detected and empty.mask.shape == (0, 5)
    wide = numpy.zeros((10, 40, 3), numpy.uint8)
    wide[:, :20] = (0, 0, 255)
    result = detect_red(wide[:, ::2], settings(min_area_px=0))
    assert result.area_px == 100 and result.centroid_px == pytest.approx((4.5, 4.5))


def test_detection_is_immutable():
    result = detect_red(scene((0, 0, 255), 200), VisionSettings())
    assert isinstance(result, RedDetection)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.detected = False


def test_settings_reject_bad_values_by_name():
    with pytest.raises(SettingsError, match='hue_high_min'):
        settings(hue_low_max=170, hue_high_min=170)
    with pytest.raises(SettingsError, match='hue_high_min'):
        settings(hue_high_min=181)
    with pytest.raises(SettingsError, match='hue_low_max'):
        settings(hue_low_max=180)
    with pytest.raises(SettingsError, match='saturation_min'):
        settings(saturation_min=256)
    with pytest.raises(SettingsError, match='log_period_s'):
        settings(log_period_s=0.0)
    params = {'~min_area_px': -1}
    with pytest.raises(SettingsError, match='min_area_px'):
        from_params(VisionSettings, lambda name, default: params.get(name, default))
    params = {'~min_area_px': 250.0, '~hue_high_min': 180}
    loaded = from_params(VisionSettings, lambda name, default: params.get(name, default))
    assert loaded.min_area_px == 250 and isinstance(loaded.min_area_px, int)
    assert loaded.hue_high_min == 180


def test_core_modules_import_without_ros():
    blocked = ('rospy', 'roslib', 'cv_bridge', 'sensor_msgs', 'std_msgs', 'geometry_msgs',
               'tf2_ros')
    code = ('import sys\n'
            'for name in %r:\n'
            '    sys.modules[name] = None\n'
            'import closed_loop.image_encoding, closed_loop.control.vision\n' % (blocked,))
    src = os.path.join(os.path.dirname(__file__), '..', '..', 'src')
    env = dict(os.environ, PYTHONPATH=os.path.abspath(src))
    run = subprocess.run([sys.executable, '-c', code], env=env, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
