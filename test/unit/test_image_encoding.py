"""Image message fields <-> numpy arrays: round trips for every encoding, padded rows, errors."""
import numpy
import pytest

from closed_loop.image_encoding import (ENCODINGS, ImageEncodingError, array_to_image,
                                        bytes_per_pixel, image_to_array, to_bgr8)

HEIGHT, WIDTH = 3, 5


def _sample(encoding, height=HEIGHT, width=WIDTH):
    """An array of ``encoding`` whose elements differ from their neighbours and from padding."""
    dtype, channels = ENCODINGS[encoding]
    shape = (height, width) if channels == 1 else (height, width, channels)
    values = numpy.arange(1, 1 + numpy.prod(shape)).reshape(shape)
    if dtype.kind == 'f':
        return (values * 0.25 - 3.0).astype(dtype)
    # Spread the values over the element's range so multi-byte elements use both bytes.
    info = numpy.iinfo(dtype)
    spread = (values * 7919) % (int(info.max) - int(info.min)) + int(info.min)
    return spread.astype(dtype)


def _padded(data, row_bytes, step, height, fill=0xAB):
    """``data`` (dense ``row_bytes`` rows) re-laid in ``step``-byte rows padded with ``fill``."""
    out = bytearray([fill]) * (step * height)
    for row in range(height):
        out[row * step:row * step + row_bytes] = data[row * row_bytes:(row + 1) * row_bytes]
    return bytes(out)


def test_table_holds_the_encodings_the_nodes_use():
    for name, (dtype, channels) in {
            'rgb8': ('uint8', 3), 'bgr8': ('uint8', 3), 'rgba8': ('uint8', 4),
            'bgra8': ('uint8', 4), 'mono8': ('uint8', 1), 'mono16': ('uint16', 1),
            '8UC1': ('uint8', 1), '8UC3': ('uint8', 3), '16UC1': ('uint16', 1),
            '32FC1': ('float32', 1)}.items():
        assert ENCODINGS[name] == (numpy.dtype(dtype), channels), name
    assert bytes_per_pixel('rgb8') == 3
    assert bytes_per_pixel('mono16') == 2
    assert bytes_per_pixel('32FC1') == 4
    assert bytes_per_pixel('64FC3') == 24


@pytest.mark.parametrize('encoding', sorted(ENCODINGS))
def test_round_trip_dense(encoding):
    array = _sample(encoding)
    height, width, step, data = array_to_image(array, encoding)
    assert (height, width) == (HEIGHT, WIDTH)
    assert step == WIDTH * bytes_per_pixel(encoding)
    assert len(data) == step * height
    back = image_to_array(encoding, height, width, step, data)
    assert back.dtype == ENCODINGS[encoding][0]
    assert back.shape == array.shape
    numpy.testing.assert_array_equal(back, array)


@pytest.mark.parametrize('encoding', sorted(ENCODINGS))
def test_round_trip_padded_rows(encoding):
    array = _sample(encoding)
    height, width, step, data = array_to_image(array, encoding)
    padded_step = step + 3 * ENCODINGS[encoding][0].itemsize
    back = image_to_array(encoding, height, width, padded_step,
                          _padded(data, step, padded_step, height))
    numpy.testing.assert_array_equal(back, array)


@pytest.mark.parametrize('step', [16, 20])
def test_rgb8_width_5_with_padded_step(step):
    array = _sample('rgb8')
    _, _, dense_step, data = array_to_image(array, 'rgb8')
    assert dense_step == 15
    back = image_to_array('rgb8', HEIGHT, WIDTH, step, _padded(data, 15, step, HEIGHT))
    assert back.shape == (HEIGHT, WIDTH, 3)
    numpy.testing.assert_array_equal(back, array)


def test_known_bytes_decode_row_major_with_padding_dropped():
    data = bytes([0, 1, 2, 99, 3, 4, 5, 99])
    numpy.testing.assert_array_equal(image_to_array('mono8', 2, 3, 4, data), [[0, 1, 2], [3, 4, 5]])
    rgb = image_to_array('rgb8', 1, 2, 8, bytes([10, 20, 30, 40, 50, 60, 77, 77]))
    numpy.testing.assert_array_equal(rgb, [[[10, 20, 30], [40, 50, 60]]])


@pytest.mark.parametrize('encoding', ['mono16', '16UC1'])
def test_sixteen_bit_honours_is_bigendian(encoding):
    data = bytes([0x01, 0x02, 0x03, 0x04])
    big = image_to_array(encoding, 1, 2, 4, data, is_bigendian=1)
    little = image_to_array(encoding, 1, 2, 4, data, is_bigendian=0)
    numpy.testing.assert_array_equal(big, [[0x0102, 0x0304]])
    numpy.testing.assert_array_equal(little, [[0x0201, 0x0403]])
    assert big.dtype.isnative and big.dtype == numpy.uint16


def test_big_endian_float_and_padded_big_endian_rows():
    data = numpy.array([1.5, -2.25], dtype='>f4').tobytes()
    numpy.testing.assert_array_equal(image_to_array('32FC1', 1, 2, 8, data, 1), [[1.5, -2.25]])
    rows = numpy.array([[258, 772], [1, 65535]], dtype='>u2')
    padded = _padded(rows.tobytes(), 4, 6, 2)
    numpy.testing.assert_array_equal(image_to_array('mono16', 2, 2, 6, padded, 1), rows)


def test_float_nan_and_inf_are_kept():
    values = numpy.array([[numpy.nan, numpy.inf, -numpy.inf, 0.5]], dtype=numpy.float32)
    back = image_to_array('32FC1', 1, 4, 16, values.tobytes())
    assert numpy.isnan(back[0, 0]) and back[0, 1] == numpy.inf and back[0, 2] == -numpy.inf


def test_array_to_image_writes_little_endian_whatever_the_array_byte_order():
    expected = bytes([0x02, 0x01])
    assert array_to_image(numpy.array([[258]], dtype='<u2'), 'mono16')[3] == expected
    assert array_to_image(numpy.array([[258]], dtype='>u2'), 'mono16')[3] == expected


def test_array_to_image_accepts_one_channel_with_trailing_axis_and_non_contiguous_arrays():
    array = _sample('mono8')
    assert array_to_image(array[:, :, numpy.newaxis], 'mono8') == array_to_image(array, 'mono8')
    wide = _sample('rgb8', width=10)
    view = wide[:, ::2]
    height, width, step, data = array_to_image(view, 'rgb8')
    numpy.testing.assert_array_equal(image_to_array('rgb8', height, width, step, data), view)


@pytest.mark.parametrize('padding', [0, 4])
def test_result_does_not_alias_the_message_buffer(padding):
    step = 3 + padding
    data = bytearray(range(step * 2))
    array = image_to_array('mono8', 2, 3, step, data)
    before = array.copy()
    data[0] = 200
    data[step] = 201
    numpy.testing.assert_array_equal(array, before)
    assert array.flags.writeable and array.flags.c_contiguous
    array[0, 0] = 7  # writable without touching the caller's buffer
    assert data[0] == 200


def test_empty_images():
    assert image_to_array('rgb8', 0, 5, 16, b'').shape == (0, 5, 3)
    assert image_to_array('mono16', 2, 0, 0, b'').shape == (2, 0)
    assert array_to_image(numpy.zeros((0, 4, 3), numpy.uint8), 'rgb8') == (0, 4, 12, b'')


def _error(call, *args, **kwargs):
    with pytest.raises(ImageEncodingError) as caught:
        call(*args, **kwargs)
    return str(caught.value)


def test_decode_errors_name_the_field():
    assert _error(image_to_array, 'yuv9', 1, 1, 1, b'x').startswith('encoding:')
    assert _error(image_to_array, None, 1, 1, 1, b'x').startswith('encoding:')
    message = _error(image_to_array, 'rgb8', 2, 5, 14, bytes(28))
    assert message.startswith('step:') and '15' in message
    assert _error(image_to_array, 'rgb8', 2, 5, 15, bytes(29)).startswith('data:')
    assert _error(image_to_array, 'rgb8', 2, 5, 15, bytes(31)).startswith('data:')
    assert _error(image_to_array, 'rgb8', 2, 5, 16, bytes(30)).startswith('data:')
    assert _error(image_to_array, 'mono16', 1, 2, 5, bytes(5)).startswith('step:')
    assert _error(image_to_array, 'mono8', -1, 2, 2, b'').startswith('height:')
    assert _error(image_to_array, 'mono8', 1, -2, 2, bytes(2)).startswith('width:')
    assert _error(image_to_array, 'mono8', 1, 2, -2, bytes(2)).startswith('step:')
    assert _error(image_to_array, 'mono8', 1.0, 2, 2, bytes(2)).startswith('height:')
    assert _error(image_to_array, 'mono8', True, 2, 2, bytes(2)).startswith('height:')
    assert _error(image_to_array, 'mono16', 1, 1, 2, bytes(2), 2).startswith('is_bigendian:')
    assert _error(image_to_array, 'mono8', 1, 2, 2, 'ab').startswith('data:')
    assert _error(image_to_array, 'mono8', 1, 2, 2, [1, 2]).startswith('data:')
    assert issubclass(ImageEncodingError, ValueError)


def test_encode_errors_name_the_field():
    assert _error(array_to_image, numpy.zeros((2, 2, 3)), 'rgb8').startswith('array:')
    assert _error(array_to_image, numpy.zeros((2, 2), numpy.uint8), 'rgb8').startswith('array:')
    assert _error(array_to_image, numpy.zeros((2, 2, 4), numpy.uint8), 'rgb8').startswith('array:')
    assert _error(array_to_image, numpy.zeros((2, 2, 2), numpy.uint8), 'mono8').startswith('array:')
    assert _error(array_to_image, numpy.zeros((2, 2), numpy.int16), 'mono16').startswith('array:')
    assert _error(array_to_image, [[0]], 'mono8').startswith('array:')
    assert _error(array_to_image, numpy.zeros((2, 2), numpy.uint8), 'gray').startswith('encoding:')


@pytest.mark.parametrize('encoding, pixel, bgr', [
    ('rgb8', [1, 2, 3], [3, 2, 1]),
    ('bgr8', [1, 2, 3], [1, 2, 3]),
    ('rgba8', [1, 2, 3, 4], [3, 2, 1]),
    ('bgra8', [1, 2, 3, 4], [1, 2, 3]),
])
def test_to_bgr8_orders_channels(encoding, pixel, bgr):
    image = numpy.zeros((2, 3, len(pixel)), numpy.uint8)
    image[1, 2] = pixel
    out = to_bgr8(image, encoding)
    assert out.shape == (2, 3, 3) and out.dtype == numpy.uint8 and out.flags.c_contiguous
    assert out[1, 2].tolist() == bgr
    assert out[0, 0].tolist() == [0, 0, 0]


def test_to_bgr8_spreads_mono8_over_three_channels():
    out = to_bgr8(numpy.array([[7, 200]], numpy.uint8), 'mono8')
    assert out.tolist() == [[[7, 7, 7], [200, 200, 200]]]


def test_to_bgr8_refuses_other_encodings_and_mismatched_arrays():
    assert _error(to_bgr8, numpy.zeros((2, 2), numpy.uint16), 'mono16').startswith('encoding:')
    assert _error(to_bgr8, numpy.zeros((2, 2), numpy.uint8), 'rgb8').startswith('array:')
