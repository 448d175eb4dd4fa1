"""pybullet without its own chatter: its C++ core writes straight to the process's stdout and stderr (a
"pybullet build time" banner at import, "No inertial data for link" and the like at every URDF load), where
it would flood a sweep's progress line and look like our errors.

:func:`native_output` catches what file descriptors 1 and 2 receive for the length of a call and drops
pybullet's own lines; anything else written meanwhile (another thread's log line) is written back. With
``CLOSED_LOOP_VERBOSE=1`` in the environment (``--verbose`` of the commands sets it) everything is written
back, as it came. Free of ROS.
"""
import contextlib
import ctypes
import importlib
import os
import re
import sys
import tempfile
import threading

VERBOSE_VARIABLE = 'CLOSED_LOOP_VERBOSE'
#: pybullet's lines: its banner, and its b3Printf / b3Warning / b3Error reports (a header line with the
#: source file, then the text, which the next report may follow without a line break).
NOISE = re.compile(r'pybullet build time:[^\n]*\n?'
                   r'|b3(?:Printf|Warning|Error)(?:\[[^\]\n]*\])?:[ \t]*\n?[^\n]*?(?=b3(?:Printf|Warning|Error)|\n|$)\n?')
_LOCK = threading.Lock()
_LIBC = ctypes.CDLL(None)


def verbose():
    return os.environ.get(VERBOSE_VARIABLE, '') not in ('', '0')


def set_verbose(on):
    """With ``on``, let pybullet's own output through, in this process and the ones it starts (otherwise
    leave the environment as the user set it)."""
    if on:
        os.environ[VERBOSE_VARIABLE] = '1'


def without_noise(text):
    """``text`` with pybullet's own lines taken out."""
    return NOISE.sub('', text)


@contextlib.contextmanager
def native_output():
    """Catch what fds 1 and 2 receive meanwhile; write back all of it (verbose) or all but pybullet's."""
    if verbose():
        yield
        return
    with _LOCK:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = [os.dup(1), os.dup(2)]
        with tempfile.TemporaryFile() as caught:
            os.dup2(caught.fileno(), 1)
            os.dup2(caught.fileno(), 2)
            try:
                yield
            finally:
                _LIBC.fflush(None)           # C's buffered stdout, before fd 1 is given back
                sys.stdout.flush()
                sys.stderr.flush()
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
                for fd in saved:
                    os.close(fd)
                caught.seek(0)
                rest = without_noise(caught.read().decode('utf-8', 'replace'))
                if rest.strip():
                    sys.stderr.write(rest)
                    sys.stderr.flush()


def import_pybullet():
    """The pybullet module, imported without its banner."""
    with native_output():
        return importlib.import_module('pybullet')
