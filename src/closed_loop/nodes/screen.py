"""A virtual screen for programs that need a display (rviz) on hosts without one: start Xvfb, take a
screenshot of it, and read the pixels. Plain subprocess and numpy; no ROS."""
import os
import shutil
import struct
import subprocess
import time

import numpy as np

# How long Xvfb may take to accept connections.
XVFB_START_S = 10.0
#: xwd reads every window on the screen; one closed while it reads (a program's splash screen giving way to its
#: main window) makes it fail with one of these X errors. The dump is then taken again, up to XWD_ATTEMPTS times
#: in all, XWD_RETRY_S apart.
XWD_RACES = ('BadDrawable', 'BadWindow', 'BadMatch')
XWD_ATTEMPTS, XWD_RETRY_S = 4, 0.25
SCREEN_SIZE = (1280, 900)


class ScreenError(RuntimeError):
    """The virtual screen could not be started or read; the message says which step and why."""


class VirtualScreen:
    """An Xvfb server on the first free display number from ``first``; use as a context manager."""

    def __init__(self, first=90, size=SCREEN_SIZE):
        self.size = size
        self.first = first
        self.proc = None
        self.display = None

    def __enter__(self):
        if shutil.which('Xvfb') is None:
            raise ScreenError('Xvfb is not installed (Debian package xvfb)')
        for number in range(self.first, self.first + 50):
            if os.path.exists('/tmp/.X%d-lock' % number) or os.path.exists('/tmp/.X11-unix/X%d' % number):
                continue
            proc = subprocess.Popen(['Xvfb', ':%d' % number, '-screen', '0', '%dx%dx24' % self.size, '-nolisten',
                                     'tcp'], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            deadline = time.monotonic() + XVFB_START_S
            while time.monotonic() < deadline:
                if proc.poll() is not None:
                    break
                if os.path.exists('/tmp/.X11-unix/X%d' % number):
                    self.proc, self.display = proc, ':%d' % number
                    return self
                time.sleep(0.05)
            if proc.poll() is None:
                proc.kill()
            proc.wait()
        raise ScreenError('Xvfb did not start on any display from :%d' % self.first)

    def __exit__(self, *exc):
        if self.proc is not None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        return False

    def screenshot(self):
        """The whole screen as an (h, w, 3) RGB uint8 array (via xwd, Debian package x11-apps)."""
        if shutil.which('xwd') is None:
            raise ScreenError('xwd is not installed (Debian package x11-apps)')
        for attempt in range(1, XWD_ATTEMPTS + 1):
            out = subprocess.run(['xwd', '-root', '-silent', '-display', self.display], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, timeout=30)
            if out.returncode == 0:
                return xwd_to_rgb(out.stdout)
            error = out.stderr.decode(errors='replace').strip()
            if not any(race in error for race in XWD_RACES):
                break
            time.sleep(XWD_RETRY_S)
        raise ScreenError('xwd failed (attempt %d of %d): %s' % (attempt, XWD_ATTEMPTS, error))


def xwd_to_rgb(data):
    """Decode an XWD dump of a 24/32-bit TrueColor screen into an (h, w, 3) RGB array."""
    if len(data) < 100:
        raise ScreenError('xwd: %d bytes is too short for a screen dump' % len(data))
    fields = struct.unpack('>25I', data[:100])
    header_size, version, width, height = fields[0], fields[1], fields[4], fields[5]
    byte_order, bits_per_pixel, bytes_per_line = fields[7], fields[11], fields[12]
    red_mask, green_mask, blue_mask = fields[14], fields[15], fields[16]
    colour_count = fields[19]  # XWDColor records (12 bytes each) between the header and the pixels
    if version != 7 or bits_per_pixel not in (24, 32):
        raise ScreenError('xwd: expected version 7 with 24 or 32 bits per pixel, got version %d, %d bits'
                          % (version, bits_per_pixel))
    offset = header_size + colour_count * 12
    step = bits_per_pixel // 8
    rows = np.frombuffer(data, dtype=np.uint8, count=bytes_per_line * height, offset=offset)
    raw = rows.reshape(height, bytes_per_line)[:, :width * step].reshape(height, width, step).astype(np.uint32)
    order = range(step) if byte_order == 0 else range(step - 1, -1, -1)  # 0: least significant byte first
    pixels = np.zeros((height, width), dtype=np.uint32)
    for significance, index in enumerate(order):
        pixels |= raw[:, :, index] << np.uint32(8 * significance)

    def channel(mask):
        shift = (mask & -mask).bit_length() - 1
        return ((pixels & mask) >> shift).astype(np.uint8)
    return np.dstack([channel(red_mask), channel(green_mask), channel(blue_mask)])
