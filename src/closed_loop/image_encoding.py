"""Conversion between ``sensor_msgs/Image`` fields and numpy arrays, driven by one encoding table.

The ROS layer hands in the plain fields of an image message (``encoding``, ``height``,
``width``, ``step``, ``data``, ``is_bigendian``); nothing here imports rospy or message packages.
A row of an image message may be padded: ``step`` (bytes per row) can exceed ``width * bytes per
pixel``, and the padding is dropped by slicing each row, never by reshaping the buffer as if it
were dense.

Every problem raises :class:`ImageEncodingError`, whose message starts with the offending field
(``encoding``, ``height``, ``width``, ``step``, ``data``, ``is_bigendian`` or ``array``).
"""
import numbers
import types
from typing import Tuple

import numpy


class ImageEncodingError(ValueError):
    """Image fields or an array do not fit together; the message names the field and the need."""


def _table():
    """The encoding table: name -> (element dtype without byte order, channels)."""
    table = {}
    for name, base, channels in (
            ('rgb8', 'u1', 3), ('bgr8', 'u1', 3), ('rgba8', 'u1', 4), ('bgra8', 'u1', 4),
            ('mono8', 'u1', 1),
            ('rgb16', 'u2', 3), ('bgr16', 'u2', 3), ('rgba16', 'u2', 4), ('bgra16', 'u2', 4),
            ('mono16', 'u2', 1)):
        table[name] = (numpy.dtype(base), channels)
    for pattern in ('rggb', 'bggr', 'gbrg', 'grbg'):
        # Bayer images are one raw sample per pixel; demosaicing is not this module's job.
        table['bayer_%s8' % pattern] = (numpy.dtype('u1'), 1)
        table['bayer_%s16' % pattern] = (numpy.dtype('u2'), 1)
    for depth, base in (('8U', 'u1'), ('8S', 'i1'), ('16U', 'u2'), ('16S', 'i2'),
                        ('32S', 'i4'), ('32F', 'f4'), ('64F', 'f8')):
        for channels in (1, 2, 3, 4):
            table['%sC%d' % (depth, channels)] = (numpy.dtype(base), channels)
    return types.MappingProxyType(table)


#: Every known encoding: name -> (element dtype in native byte order, channels per pixel).
ENCODINGS = _table()

#: Encodings :func:`to_bgr8` understands, with the source channel for each of B, G and R.
_BGR_SOURCE_CHANNELS = types.MappingProxyType({
    'bgr8': (0, 1, 2), 'bgra8': (0, 1, 2),
    'rgb8': (2, 1, 0), 'rgba8': (2, 1, 0),
    'mono8': (0, 0, 0),
})


def _format(encoding):
    """(dtype, channels) of ``encoding``, or ImageEncodingError naming the field ``encoding``."""
    if not isinstance(encoding, str):
        raise ImageEncodingError('encoding: expected a string, got %r' % (encoding,))
    try:
        return ENCODINGS[encoding]
    except KeyError:
        raise ImageEncodingError('encoding: unknown image encoding %r; expected one of %s'
                                 % (encoding, ', '.join(sorted(ENCODINGS)))) from None


def bytes_per_pixel(encoding: str) -> int:
    """Bytes one pixel of ``encoding`` takes (e.g. 3 for rgb8, 2 for mono16, 4 for 32FC1)."""
    dtype, channels = _format(encoding)
    return dtype.itemsize * channels


def _non_negative_int(name, value):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ImageEncodingError('%s: expected a non-negative integer, got %r' % (name, value))
    if value < 0:
        raise ImageEncodingError('%s: expected a non-negative integer, got %d' % (name, value))
    return int(value)


def image_to_array(encoding: str, height: int, width: int, step: int, data: bytes,
                   is_bigendian: int = 0) -> numpy.ndarray:
    """Decode image message fields into a new numpy array.

    ``step`` is the row stride in bytes and may include padding after ``width`` pixels; the padding
    is sliced off. ``is_bigendian`` (0 or 1) gives the byte order of multi-byte elements (mono16,
    16UC1, 32FC1, ...); it does not matter for 8-bit encodings. ``data`` is any bytes-like object.

    Returns an array of shape (height, width) for one-channel encodings and (height, width,
    channels) otherwise, with the table's dtype in native byte order. The array is always a fresh,
    writable, C-contiguous copy: it never shares memory with ``data``, which its owner may reuse.
    Float pixels are returned as they are, NaN and Inf included (depth images use them).

    Raises ImageEncodingError when the encoding is unknown, height/width/step are not
    non-negative integers, ``step < width * bytes per pixel``, ``step`` is not a multiple of the
    element size, ``is_bigendian`` is not 0 or 1, or ``len(data) != step * height``.
    """
    dtype, channels = _format(encoding)
    height = _non_negative_int('height', height)
    width = _non_negative_int('width', width)
    step = _non_negative_int('step', step)
    if isinstance(is_bigendian, bool):
        is_bigendian = int(is_bigendian)
    if not isinstance(is_bigendian, numbers.Integral) or is_bigendian not in (0, 1):
        raise ImageEncodingError('is_bigendian: expected 0 or 1, got %r' % (is_bigendian,))
    row_bytes = width * channels * dtype.itemsize
    if step < row_bytes:
        raise ImageEncodingError(
            'step: expected at least width * bytes per pixel = %d * %d = %d bytes for %s, got %d'
            % (width, channels * dtype.itemsize, row_bytes, encoding, step))
    if step % dtype.itemsize:
        raise ImageEncodingError('step: expected a multiple of the %d-byte element size of %s, '
                                 'got %d' % (dtype.itemsize, encoding, step))
    try:
        buffer = numpy.frombuffer(data, dtype=numpy.uint8)
    except (TypeError, ValueError, AttributeError):
        raise ImageEncodingError('data: expected a contiguous bytes-like object, got %s'
                                 % type(data).__name__) from None
    if buffer.size != step * height:
        raise ImageEncodingError('data: expected step * height = %d * %d = %d bytes, got %d'
                                 % (step, height, step * height, buffer.size))
    # The copy drops the row padding and detaches the result from ``data``; viewing the dense
    # copy as wider elements works on every numpy version (old ones refuse strided views).
    rows = buffer.reshape(height, step)[:, :row_bytes].copy()
    wire_dtype = dtype.newbyteorder('>' if is_bigendian else '<') if dtype.itemsize > 1 else dtype
    shape = (height, width) if channels == 1 else (height, width, channels)
    array = rows.view(wire_dtype).reshape(shape)
    if wire_dtype != dtype:
        array = array.astype(dtype)
    return array


def _check_array(array, encoding):
    """Check that ``array`` holds pixels of ``encoding``; return it as (height, width, channels)."""
    dtype, channels = _format(encoding)
    if not isinstance(array, numpy.ndarray):
        raise ImageEncodingError('array: expected a numpy.ndarray, got %s' % type(array).__name__)
    if array.dtype.kind != dtype.kind or array.dtype.itemsize != dtype.itemsize:
        raise ImageEncodingError('array: encoding %s needs dtype %s, got %s'
                                 % (encoding, dtype.name, array.dtype))
    if channels == 1 and array.ndim == 2:
        return array[:, :, numpy.newaxis]
    if array.ndim != 3 or array.shape[2] != channels:
        expected = ('(height, width) or (height, width, 1)' if channels == 1
                    else '(height, width, %d)' % channels)
        raise ImageEncodingError('array: encoding %s needs shape %s, got %s'
                                 % (encoding, expected, array.shape))
    return array


def array_to_image(array: numpy.ndarray, encoding: str) -> Tuple[int, int, int, bytes]:
    """Encode ``array`` as image message fields: (height, width, step, data).

    ``array`` has shape (height, width) or (height, width, 1) for one-channel encodings and
    (height, width, channels) otherwise, and a dtype of the table's kind and size (any byte order).
    Rows are not padded: ``step = width * bytes per pixel``. Multi-byte elements are written
    little-endian, so the message's ``is_bigendian`` must be 0.

    Raises ImageEncodingError (field ``encoding`` or ``array``) when they do not match.
    """
    pixels = _check_array(array, encoding)
    dtype, channels = ENCODINGS[encoding]
    height, width = pixels.shape[0], pixels.shape[1]
    little = dtype.newbyteorder('<') if dtype.itemsize > 1 else dtype
    data = pixels.astype(little, copy=False).tobytes()
    return height, width, width * channels * dtype.itemsize, data


def to_bgr8(array: numpy.ndarray, encoding: str) -> numpy.ndarray:
    """A (height, width, 3) uint8 BGR array for OpenCV from rgb8, bgr8, rgba8, bgra8 or mono8.

    Alpha is dropped; mono8 is copied into all three channels. For bgr8 input that is already
    C-contiguous the input array itself is returned (no copy); otherwise the result is new.

    Raises ImageEncodingError naming ``encoding`` for any other encoding, or ``array`` when its
    shape or dtype does not fit the encoding.
    """
    _format(encoding)
    if encoding not in _BGR_SOURCE_CHANNELS:
        raise ImageEncodingError('encoding: cannot convert %r to bgr8; expected one of %s'
                                 % (encoding, ', '.join(sorted(_BGR_SOURCE_CHANNELS))))
    pixels = _check_array(array, encoding)
    sources = _BGR_SOURCE_CHANNELS[encoding]
    if encoding == 'bgr8':
        return numpy.ascontiguousarray(pixels)
    bgr = numpy.empty(pixels.shape[:2] + (3,), dtype=numpy.uint8)
    # Per-channel copies are several times faster than one reversed-stride copy.
    for target, source in enumerate(sources):
        bgr[:, :, target] = pixels[:, :, source]
    return bgr
