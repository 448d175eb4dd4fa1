"""A graph episode's folder, back on the client whatever machine ran it.

A sweep's client marks its folder of graph episodes (``OUTPUT/graphs/.client``, a token of its own). A worker
that finds that mark sees the client's files (this machine, or a shared filesystem): it runs each graph episode
in ``OUTPUT/graphs/episode-INDEX`` itself, as before. A worker that does not (a machine of its own) runs it in a
temporary folder of its own, packs the folder (the generated launch file, the world, the graph's and each
node's logs, ``verdict.json``: up to ``LIMIT_BYTES`` of files, the smallest first after the verdict and the
launch file) and sends it back with the row; the client unpacks it into ``OUTPUT/graphs/episode-INDEX``, so
that the row's ``logs`` names a folder on the client. The worker then removes its folder; what did not fit
stays there, and ``LEFT_ON_WORKER.txt`` in the client's folder says where and which files.
"""
import io
import os
import shutil
import socket
import tarfile
import tempfile
import uuid

MARK = '.client'
#: The most of a graph episode's files (bytes, before compression) that come back with its row.
LIMIT_BYTES = 8 * 1024 * 1024
#: What is packed first, whatever its size.
FIRST = ('verdict.json', 'episode.launch', 'world.yaml', 'keeper_error')
LEFT_NOTE = 'LEFT_ON_WORKER.txt'


def claim(logs_root):
    """Mark ``logs_root`` as this client's; returns the token a worker compares."""
    os.makedirs(logs_root, exist_ok=True)
    token = uuid.uuid4().hex
    with open(os.path.join(logs_root, MARK), 'w') as f:
        f.write(token)
    return token


def shares(logs_root, token):
    """True if this process sees the client's ``logs_root`` (its mark holds ``token``)."""
    try:
        with open(os.path.join(logs_root, MARK)) as f:
            return f.read() == token
    except OSError:
        return False


def local_folder():
    """A new folder of this worker's for one graph episode."""
    return tempfile.mkdtemp(prefix='closed_loop-episode-')


def pack(folder, limit=LIMIT_BYTES):
    """(a gzipped tar of ``folder``'s files, the relative paths of those left out past ``limit``)."""
    files = []
    for top, dirs, names in os.walk(folder):
        dirs.sort()
        for name in sorted(names):
            path = os.path.join(top, name)
            if os.path.isfile(path) and not os.path.islink(path):
                files.append((os.path.relpath(path, folder), os.path.getsize(path)))
    files.sort(key=lambda item: (item[0] not in FIRST, item[1], item[0]))
    data, left, total = io.BytesIO(), [], 0
    with tarfile.open(fileobj=data, mode='w:gz') as tar:
        for name, size in files:
            if total + size > limit and name not in FIRST:
                left.append(name)
                continue
            total += size
            tar.add(os.path.join(folder, name), arcname=name, recursive=False)
    return data.getvalue(), left


def unpack(data, folder):
    """Write the files of ``data`` (from ``pack``) into ``folder``: regular files only, each inside it."""
    os.makedirs(folder, exist_ok=True)
    root = os.path.realpath(folder)
    with tarfile.open(fileobj=io.BytesIO(data), mode='r:gz') as tar:
        for member in tar.getmembers():
            target = os.path.realpath(os.path.join(root, member.name))
            if not member.isfile() or os.path.isabs(member.name) or not target.startswith(root + os.sep):
                continue
            os.makedirs(os.path.dirname(target), exist_ok=True)
            with tar.extractfile(member) as source, open(target, 'wb') as out:
                shutil.copyfileobj(source, out)


def send_back(local, row, limit=LIMIT_BYTES):
    """Put ``local``'s files into ``row`` (``logs_packed``; ``logs_left``: where the rest stays) and remove
    ``local`` when all of it went."""
    row['logs_packed'], left = pack(local, limit)
    if left:
        row['logs_left'] = '%s:%s (%s)' % (socket.gethostname(), local, ', '.join(left))
    else:
        shutil.rmtree(local, ignore_errors=True)


def receive(row, folder, set_aside):
    """Unpack what ``row`` brought back into ``folder`` (an earlier one there set aside with ``set_aside``)."""
    data, left = row.pop('logs_packed', None), row.pop('logs_left', None)
    if data is None:
        return
    set_aside(folder)
    unpack(data, folder)
    if left:
        with open(os.path.join(folder, LEFT_NOTE), 'w') as f:
            f.write('Past the %d MB that come back, these files stayed on the worker that ran the episode: %s\n'
                    % (LIMIT_BYTES // (1024 * 1024), left))
