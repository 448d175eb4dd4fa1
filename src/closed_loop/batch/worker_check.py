"""The right workers, or none: a worker of a cluster of yours runs a sweep's episodes only where it has what decides
their outcome as the client has it.

What is compared (``fingerprint``): this package (its version and a digest of its Python source, so that two
checkouts of one version with different code differ), the pinned versions of the packages that decide an
episode's outcome (``DECIDING``: pybullet, numpy, numba), and, for graph episodes, whether each launch file the
sweep names in a package is found there (by rospack, as the worker's roslaunch will find it). Before the first episode every worker is asked (``check_all``): a
mismatch is refused in one line naming the worker and what differs. Each episode carries the client's
fingerprint too (``matches``), so that a worker that joined later and differs runs nothing: its row comes back
as ``wrong_worker``, the client retires that worker and runs the episode elsewhere, and no row of another
version is ever written.
"""
import functools
import hashlib
import os
import subprocess

from closed_loop.batch.sweep_file import SweepError

DECIDING = ('pybullet', 'numpy', 'numba')
SOURCE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAUNCH = 'launch file '


class WrongWorker(SweepError):
    """A worker that differs from the client (the message names it and what differs)."""


@functools.lru_cache(maxsize=None)
def _own():
    from importlib import metadata
    digest = hashlib.sha256()
    for top, dirs, names in os.walk(SOURCE):
        dirs[:] = sorted(d for d in dirs if d != '__pycache__')
        for name in sorted(n for n in names if n.endswith('.py')):
            path = os.path.join(top, name)
            digest.update(os.path.relpath(path, SOURCE).encode() + b'\0')
            with open(path, 'rb') as f:
                digest.update(f.read())
    from closed_loop.paths import package_root
    version = '?'
    try:
        with open(os.path.join(package_root(), 'package.xml')) as f:
            text = f.read()
        version = text.split('<version>', 1)[1].split('</version>', 1)[0].strip()
    except (OSError, IndexError):
        pass
    found = {}
    for name in DECIDING:
        try:
            found[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            found[name] = 'none'
    return (('closed_loop', '%s (source %s)' % (version, digest.hexdigest()[:12])),) + tuple(sorted(found.items()))


def fingerprint(launches=()):
    """{what: this process's} for this package, the deciding packages and each launch file of ``launches``
    (``PKG/path/in/it.launch``: found, or not and why)."""
    found = dict(_own())
    places = {}
    for launch in sorted(launches):
        package, _, rest = launch.partition('/')
        if package not in places:
            places[package] = _package_path(package)
        place = places[package]
        found[LAUNCH + launch] = ('not found (no package %s)' % package if place is None else
                                  'found' if os.path.isfile(os.path.join(place, rest)) else 'not found')
    return found


def _package_path(name):
    """Where this worker's ROS finds package ``name`` (rospack, as its roslaunch will), or None."""
    try:
        done = subprocess.run(['rospack', 'find', name], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                              universal_newlines=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return None
    return done.stdout.strip() if done.returncode == 0 and done.stdout.strip() else None


def graph_launches(specs):
    """The launch files (``PKG/path``) the graph controllers of ``specs`` (EpisodeSpecs) name in a package (not by
    an absolute path, nor from a workspace of their own)."""
    names = set()
    for spec in specs:
        launch = spec.controller.get('launch') if isinstance(spec.controller, dict) else None
        if launch and not os.path.isabs(launch) and not spec.controller.get('workspace'):
            names.add(launch)
    return tuple(sorted(names))


def differences(mine, theirs):
    """What differs, as 'WHAT X where this client has Y', each once."""
    return ['%s %s where this client has %s' % (what, theirs.get(what, 'nothing'), value)
            for what, value in sorted(mine.items()) if theirs.get(what) != value]


def matches(expected):
    """None where this worker has ``expected`` (the client's fingerprint), else what differs (one line)."""
    if expected is None:
        return None
    found = differences(expected, fingerprint([k[len(LAUNCH):] for k in expected if k.startswith(LAUNCH)]))
    return '; '.join(found) or None


def check_all(client, expected):
    """Every worker of ``client`` asked before the first episode; raises WrongWorker naming the first that
    differs."""
    answers = client.run(fingerprint, [k[len(LAUNCH):] for k in expected if k.startswith(LAUNCH)])
    names = {addr: info.get('name') for addr, info in client.scheduler_info()['workers'].items()}
    for address in sorted(answers):
        found = differences(expected, answers[address])
        if found:
            name = names.get(address)
            raise WrongWorker('worker %s%s: %s; it runs no episode of this sweep (keep every worker at the '
                              "client's commit and pinned versions: make provision)"
                              % (address, ' (%s)' % name if name and str(name) != address else '', '; '.join(found)))


def expected(client, cluster, specs):
    """The client's fingerprint for ``specs`` (EpisodeSpecs, for the launch files they need), every worker of a
    cluster of the user's checked against it first (raises WrongWorker); what each episode then carries (the
    versions). None for a local cluster: its workers are this client's own processes."""
    if cluster is not None:
        return None
    mine = fingerprint(graph_launches(specs))
    check_all(client, mine)
    return {k: v for k, v in mine.items() if not k.startswith(LAUNCH)}


def right_result(client, future, resubmit, stream):
    """``future``'s row; where a worker that differs from the client sent it back unrun, that worker is retired
    (said on ``stream``) and the episode runs again elsewhere (``resubmit()``: a new future of it)."""
    result = future.result()
    while 'wrong_worker' in result:
        stream.write('\nsweep: worker %s differs from this client: %s; retired, its episodes run elsewhere\n'
                     % (result['worker'], result['wrong_worker']))
        stream.flush()
        client.retire_workers(workers=[result['worker']], close_workers=True)
        result = resubmit().result()
    return result
