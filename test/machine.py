"""What this machine lets a test do, asked once each by trying it.

Some tests need a privilege that a container without it cannot give: a network namespace (the graph and its
peer in test_network, the browser kept off the network), a mount (a read-only or a full disk), or dropping
root's capabilities (a user who can write nowhere). Where the machine cannot, the test is skipped with one line
that says what was missing and why (``tools/run_tests.py`` prints it and counts it in the closing line). A tool
that provisioning installs is never a reason to skip: its absence fails the test.

Each ``cannot_*`` function returns None where the machine can, or the one-line reason where it cannot; the
``needs_*`` marks skip a test on it.
"""
import functools
import os
import subprocess
import tempfile

import pytest

PROBE_LIMIT_S = 30


def _refused(argv, what):
    """None if ``argv`` ran and succeeded; else the reason, naming ``what`` and the first line it printed."""
    try:
        done = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                              timeout=PROBE_LIMIT_S)
    except (OSError, subprocess.TimeoutExpired) as error:
        return '%s: %s' % (what, error)
    if done.returncode == 0:
        return None
    said = (done.stdout.strip().splitlines() or ['exit %d' % done.returncode])[-1]
    return '%s: %s' % (what, said)


@functools.lru_cache(maxsize=None)
def cannot_unshare_network():
    """Why a network namespace of its own cannot be made here (``unshare --net --uts``), or None."""
    return _refused(['unshare', '--net', '--uts', 'true'],
                    'this machine gives no network namespace (a container without CAP_SYS_ADMIN?)')


@functools.lru_cache(maxsize=None)
def cannot_mount():
    """Why a tmpfs cannot be mounted here (tried in a mount namespace of its own, so nothing stays), or None."""
    folder = tempfile.mkdtemp(prefix='closed_loop_mount_probe_')
    try:
        return _refused(['unshare', '--mount', '--propagation', 'private', 'mount', '-t', 'tmpfs', '-o', 'size=64k',
                         'closed_loop_probe', folder], 'this machine lets no test mount a file system')
    finally:
        os.rmdir(folder)


@functools.lru_cache(maxsize=None)
def cannot_drop_capabilities():
    """Why a process cannot be started with none of root's capabilities here, or None. As another user,
    nothing needs dropping; as root, ``setpriv`` drops them from the bounding set (which needs CAP_SETPCAP)."""
    if os.geteuid() != 0:
        return None
    return _refused(WITHOUT_CAPABILITIES + ['true'], "this machine does not let root drop its capabilities")


#: A command's prefix that runs it with root's uid but none of root's capabilities: permission bits then hold
#: for it as for any user (it cannot write a file it owns that is read-only, nor read another user's).
WITHOUT_CAPABILITIES = ['setpriv', '--bounding-set=-all', '--inh-caps=-all', '--']


def as_unprivileged(argv):
    """``argv`` to run with no privilege beyond the permission bits: as is for a user, without root's
    capabilities for root."""
    return (WITHOUT_CAPABILITIES if os.geteuid() == 0 else []) + list(argv)


def _mark(reason):
    return pytest.mark.skipif(reason is not None, reason=reason or '')


def needs_network_namespace():
    return _mark(cannot_unshare_network())


def needs_mount():
    return _mark(cannot_mount())


def needs_capabilities_dropped():
    return _mark(cannot_drop_capabilities())
