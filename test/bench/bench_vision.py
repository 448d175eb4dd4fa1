#!/usr/bin/env python3
"""Time decoding an image message and detecting red in it, as the vision node does per frame.

Run: ``python test/bench/bench_vision.py``. Prints the median and 95th percentile per frame in ms
at 320x240 and 640x480, for bgr8 and rgb8 messages with padded rows (rgb8 both converted to HSV
directly, as the node does, and through a to_bgr8 copy), and their ratio to the 3 ms target.
It reports figures; it does not pass or fail on time.
"""
import os
import sys
import time

import numpy

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'src'))

from closed_loop.image_encoding import array_to_image, image_to_array, to_bgr8  # noqa: E402
from closed_loop.control.vision import VisionSettings, detect_red, detect_red_encoded  # noqa: E402

TARGET_MS = 3.0
SIZES = ((320, 240), (640, 480))
FRAMES = 200
WARMUP_FRAMES = 10
ROW_PADDING_BYTES = 64


def synthetic_scene(width, height, seed=0):
    """A noisy grey floor with a red box, a green box and a blue box (BGR, uint8)."""
    rng = numpy.random.default_rng(seed)
    image = rng.integers(90, 160, size=(height, width, 3), dtype=numpy.uint8)
    image[height // 4:height // 2, width // 5:width // 3] = (20, 30, 210)
    image[height // 2:3 * height // 4, width // 2:3 * width // 4] = (40, 200, 40)
    image[height // 8:height // 4, 3 * width // 4:7 * width // 8] = (200, 60, 30)
    return image


def message_fields(bgr, encoding):
    """(height, width, step, data) of ``bgr`` sent as ``encoding`` with padded rows."""
    pixels = bgr[:, :, ::-1] if encoding == 'rgb8' else bgr
    height, width, step, data = array_to_image(numpy.ascontiguousarray(pixels), encoding)
    padded_step = step + ROW_PADDING_BYTES
    rows = numpy.zeros((height, padded_step), numpy.uint8)
    rows[:, :step] = numpy.frombuffer(data, numpy.uint8).reshape(height, step)
    return height, width, padded_step, rows.tobytes()


def node_path(encoding, fields, settings):
    """What the vision node does: decode, then detect in the decoded channel order."""
    return detect_red_encoded(image_to_array(encoding, *fields), encoding, settings)


def bgr_copy_path(encoding, fields, settings):
    """Decode, convert to a BGR copy with to_bgr8, then detect_red."""
    return detect_red(to_bgr8(image_to_array(encoding, *fields), encoding), settings)


#: (label, message encoding, frame function) of each timed path.
PATHS = (('bgr8', 'bgr8', node_path),
         ('rgb8', 'rgb8', node_path),
         ('rgb8 via to_bgr8', 'rgb8', bgr_copy_path))


def time_frames(frame_function, encoding, fields, settings):
    """Per-frame times in ms of ``frame_function`` over FRAMES frames."""
    times = []
    for frame in range(WARMUP_FRAMES + FRAMES):
        start = time.perf_counter()
        detection = frame_function(encoding, fields, settings)
        elapsed = time.perf_counter() - start
        if frame >= WARMUP_FRAMES:
            times.append(elapsed * 1e3)
    if not detection.detected:
        raise RuntimeError('the synthetic scene shows no red: its timings would mean nothing')
    return numpy.array(times)


def main():
    settings = VisionSettings()
    print('decode + detect_red per frame (%d frames, rows padded by %d bytes); target %.1f ms'
          % (FRAMES, ROW_PADDING_BYTES, TARGET_MS))
    print('%-9s %-17s %10s %10s %16s %13s' % ('size', 'path', 'median ms', 'p95 ms',
                                              'median / target', 'p95 / target'))
    for width, height in SIZES:
        scene = synthetic_scene(width, height)
        for label, encoding, frame_function in PATHS:
            times = time_frames(frame_function, encoding, message_fields(scene, encoding), settings)
            median, p95 = numpy.median(times), numpy.percentile(times, 95)
            print('%-9s %-17s %10.3f %10.3f %16.2f %13.2f'
                  % ('%dx%d' % (width, height), label, median, p95, median / TARGET_MS,
                     p95 / TARGET_MS))


if __name__ == '__main__':
    main()
