"""Red-object detection by HSV thresholds: pure functions over numpy images, no ROS.

The rule follows the lesson (HSV lower [0, 100, 100], upper [10, 255, 255]; red when more than 100
pixels match) and adds the other end of OpenCV's hue circle: 8-bit hue is degrees / 2 in [0, 179]
and red straddles 0, so a red that leans towards magenta (hue 170-179) is red too.

Coordinates are image pixels: ``u`` is the column (to the right), ``v`` the row (down), and a
pixel's centre sits at integer coordinates, as in OpenCV.
"""
import dataclasses
from typing import Optional, Tuple

import cv2
import numpy

from closed_loop.settings import SettingsError, param

#: Largest 8-bit OpenCV hue (hue is degrees / 2, so 180 would be 360 degrees, i.e. 0 again).
HUE_MAX = 179
#: Largest 8-bit saturation and value.
CHANNEL_MAX = 255
#: Encodings :func:`detect_red_encoded` accepts (mono8 carries no colour and is never red).
SUPPORTED_ENCODINGS = ('rgb8', 'bgr8', 'mono8')

_HUE_UNIT = 'OpenCV hue (degrees / 2, 0-179)'


class VisionError(ValueError):
    """An image cannot be examined; the message names the argument and what was expected."""


@dataclasses.dataclass
class VisionSettings:
    """Thresholds of the red detector and the vision node's logging period (``~`` parameters)."""

    hue_low_max: int = param(10, _HUE_UNIT, 'first red band: hue in [0, hue_low_max]',
                             minimum=0, maximum=HUE_MAX)
    hue_high_min: int = param(170, _HUE_UNIT,
                              'second red band: hue in [hue_high_min, 179]; 180 turns the band off',
                              minimum=0, maximum=HUE_MAX + 1)
    saturation_min: int = param(100, 'OpenCV saturation (0-255)',
                                'least saturation of a red pixel (greys and whites are below)',
                                minimum=0, maximum=CHANNEL_MAX)
    value_min: int = param(100, 'OpenCV value (0-255)',
                           'least brightness of a red pixel (dark reds and shadows are below)',
                           minimum=0, maximum=CHANNEL_MAX)
    min_area_px: int = param(100, 'px', 'red is detected when more than this many pixels match',
                             minimum=0)
    log_period_s: float = param(1.0, 's', 'least time between two repeated log lines of the node',
                                minimum=0.0, exclusive_minimum=True)

    def check_together(self):
        """The two hue bands must not meet, or together they would call every saturated hue red."""
        if not self.hue_low_max < self.hue_high_min:
            raise SettingsError('~hue_high_min: expected more than ~hue_low_max (%d) so the two '
                                'red bands stay apart, got %d'
                                % (self.hue_low_max, self.hue_high_min))


@dataclasses.dataclass(frozen=True, eq=False)
class RedDetection:
    """What one image shows.

    ``area_px`` counts matching pixels, whether or not it passes ``min_area_px``. ``centroid_px``
    is the (u, v) mean of the matching pixels when ``detected``, else None. ``mask`` is a uint8
    image of the input's height and width, 255 where a pixel matches and 0 elsewhere.
    (Compared by identity: arrays have no single truth value.)
    """

    detected: bool
    area_px: int
    centroid_px: Optional[Tuple[float, float]]
    mask: numpy.ndarray


def _check_colour_image(image, name):
    if not isinstance(image, numpy.ndarray):
        raise VisionError('%s: expected a numpy.ndarray, got %s' % (name, type(image).__name__))
    if image.dtype != numpy.uint8 or image.ndim != 3 or image.shape[2] != 3:
        raise VisionError('%s: expected a (height, width, 3) uint8 array, got shape %s dtype %s'
                          % (name, image.shape, image.dtype))


def _bound(hue, saturation, value):
    """An inclusive HSV bound for cv2.inRange."""
    return numpy.array([hue, saturation, value], dtype=numpy.uint8)


def _mask(image, settings, conversion):
    """The red mask of a checked 3-channel uint8 image converted to HSV with ``conversion``."""
    height, width = image.shape[:2]
    if height == 0 or width == 0:
        return numpy.zeros((height, width), dtype=numpy.uint8)
    hsv = cv2.cvtColor(numpy.ascontiguousarray(image), conversion)
    mask = cv2.inRange(hsv, _bound(0, settings.saturation_min, settings.value_min),
                       _bound(settings.hue_low_max, CHANNEL_MAX, CHANNEL_MAX))
    if settings.hue_high_min <= HUE_MAX:
        high_band = cv2.inRange(hsv, _bound(settings.hue_high_min, settings.saturation_min,
                                            settings.value_min),
                                _bound(HUE_MAX, CHANNEL_MAX, CHANNEL_MAX))
        cv2.bitwise_or(mask, high_band, dst=mask)
    return mask


def _detection(mask, settings):
    area = cv2.countNonZero(mask)
    if not area > settings.min_area_px:
        return RedDetection(False, int(area), None, mask)
    # Moments cost a full pass over the mask: only worth it when there is something to locate.
    moments = cv2.moments(mask, binaryImage=True)
    centroid = (moments['m10'] / moments['m00'], moments['m01'] / moments['m00'])
    return RedDetection(True, int(area), centroid, mask)


def red_mask(bgr: numpy.ndarray, settings: VisionSettings) -> numpy.ndarray:
    """A uint8 mask (0 or 255) of the pixels of ``bgr`` that are red under ``settings``.

    ``bgr`` is a (height, width, 3) uint8 BGR image; the mask is (height, width). A pixel is red
    when its saturation >= ``saturation_min``, its value >= ``value_min`` and its hue is in
    [0, ``hue_low_max``] or [``hue_high_min``, 179]. An empty image gives an empty mask.
    Raises VisionError naming ``bgr`` for any other shape or dtype.
    """
    _check_colour_image(bgr, 'bgr')
    return _mask(bgr, settings, cv2.COLOR_BGR2HSV)


def detect_red(bgr: numpy.ndarray, settings: VisionSettings) -> RedDetection:
    """Whether ``bgr`` (a (height, width, 3) uint8 BGR image) shows red, how much, and where.

    Red is detected when strictly more than ``settings.min_area_px`` pixels match :func:`red_mask`
    (exactly ``min_area_px`` is not enough, as in the lesson). Raises VisionError naming ``bgr``
    for any other shape or dtype.
    """
    return _detection(red_mask(bgr, settings), settings)


def detect_red_encoded(array: numpy.ndarray, encoding: str,
                       settings: VisionSettings) -> RedDetection:
    """:func:`detect_red` for a decoded image of ``encoding`` (rgb8, bgr8 or mono8).

    rgb8 is converted to HSV directly, with no BGR copy. mono8, shape (height, width), has no
    colour: the result is never detected, with area 0 and an all-zero mask. Raises VisionError
    naming ``encoding`` for other encodings, ``array`` for a shape or dtype that does not fit, and
    for an image with no pixels (0 rows or columns), of which nothing can be said either way.
    """
    if getattr(array, 'size', None) == 0:
        raise VisionError('array: the image has no pixels (%s), so it shows neither red nor its absence'
                          % ('x'.join(str(n) for n in array.shape[1::-1])))
    if encoding == 'mono8':
        if not isinstance(array, numpy.ndarray) or array.dtype != numpy.uint8 or array.ndim != 2:
            raise VisionError('array: expected a (height, width) uint8 array for mono8, got %s'
                              % (getattr(array, 'shape', type(array).__name__),))
        return RedDetection(False, 0, None, numpy.zeros(array.shape, dtype=numpy.uint8))
    if encoding == 'bgr8':
        conversion = cv2.COLOR_BGR2HSV
    elif encoding == 'rgb8':
        conversion = cv2.COLOR_RGB2HSV
    else:
        raise VisionError('encoding: expected one of %s, got %r'
                          % (', '.join(SUPPORTED_ENCODINGS), encoding))
    _check_colour_image(array, 'array')
    return _detection(_mask(array, settings, conversion), settings)
