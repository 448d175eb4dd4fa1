"""XWD screen dumps decode to the right RGB pixels for 24- and 32-bit layouts in either byte order; a dump that
races a window closing is taken again."""
import os
import shutil
import stat
import struct

import pytest

from closed_loop.nodes.screen import XWD_ATTEMPTS, ScreenError, VirtualScreen, xwd_to_rgb

PIXELS = [0x112233, 0x445566, 0x778899, 0xaabbcc]   # 0xRRGGBB, 2 x 2, row by row


def dump(bits_per_pixel, byte_order, colours=0):
    width = height = 2
    step = bits_per_pixel // 8
    header = [100, 7, 2, 24, width, height, 0, byte_order, 32, byte_order, 32, bits_per_pixel, width * step,
              4, 0xff0000, 0x00ff00, 0x0000ff, 8, 256, colours, width, height, 0, 0, 0]
    body = b''
    for value in PIXELS:
        word = value.to_bytes(4, 'little' if byte_order == 0 else 'big')
        body += word[:step] if byte_order == 0 else word[4 - step:]
    return struct.pack('>25I', *header) + b'\0' * (12 * colours) + body


@pytest.mark.parametrize('bits', [24, 32])
@pytest.mark.parametrize('order', [0, 1])
def test_pixels_decode_to_rgb(bits, order):
    rgb = xwd_to_rgb(dump(bits, order, colours=3))
    assert rgb.shape == (2, 2, 3)
    assert rgb[0, 0].tolist() == [0x11, 0x22, 0x33]
    assert rgb[0, 1].tolist() == [0x44, 0x55, 0x66]
    assert rgb[1, 1].tolist() == [0xaa, 0xbb, 0xcc]


def test_other_depths_are_refused_by_name():
    data = bytearray(dump(32, 0))
    data[44:48] = struct.pack('>I', 16)
    with pytest.raises(ScreenError, match='16 bits'):
        xwd_to_rgb(bytes(data))


def xwd_failing(folder, times, message):
    """A folder holding an ``xwd`` that fails ``times`` times with ``message``, then runs the real one."""
    real = shutil.which('xwd')
    count = os.path.join(folder, 'count')
    script = os.path.join(folder, 'xwd')
    with open(script, 'w') as f:
        f.write('#!/bin/sh\nn=$(cat %s 2>/dev/null || echo 0)\necho $((n + 1)) > %s\n'
                'if [ "$n" -lt %d ]; then echo "%s" >&2; exit 1; fi\nexec %s "$@"\n'
                % (count, count, times, message, real))
    os.chmod(script, os.stat(script).st_mode | stat.S_IEXEC)
    return count


def test_a_dump_that_races_a_closing_window_is_taken_again(tmp_path, monkeypatch):
    race = 'X Error of failed request:  BadDrawable (invalid Pixmap or Window parameter)'
    count = xwd_failing(str(tmp_path), 2, race)
    monkeypatch.setenv('PATH', '%s:%s' % (tmp_path, os.environ['PATH']))
    with VirtualScreen() as screen:
        rgb = screen.screenshot()
        assert rgb.shape == (screen.size[1], screen.size[0], 3)
        assert open(count).read().strip() == '3'                  # two races, then the dump
        os.remove(count)
        xwd_failing(str(tmp_path), XWD_ATTEMPTS, race)
        raced = r'attempt %d of %d\): X Error.*BadDrawable' % (XWD_ATTEMPTS, XWD_ATTEMPTS)
        with pytest.raises(ScreenError, match=raced):
            screen.screenshot()
        os.remove(count)
        xwd_failing(str(tmp_path), 1, 'xwd: unable to open display')
        with pytest.raises(ScreenError, match=r'attempt 1 of %d\): xwd: unable to open display' % XWD_ATTEMPTS):
            screen.screenshot()                                    # anything else is not taken again
