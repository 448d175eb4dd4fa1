"""A sweep's rows on disk: ``OUTPUT/rows.csv`` (and ``trajectories.jsonl``), each row reaching its file whole or
not at all, and whatever an interrupted sweep left torn set aside rather than built on. Free of ROS.

A row is one line: one ``write`` on a file opened for appending, so a process killed at any moment leaves
the line written or not; a write the disk cannot hold is cut back to where the file ended (and raises
:class:`NoRoom`). A line break inside a cell becomes a space, so that a line is a row. Opening the file
again (``--resume``) reads it line by line: a line that is not a whole row of the sweep's columns (a last
line without its end, a row with too few or too many cells, an index that is not a number, a spec that is
not JSON, an outcome that is not one) is moved, its bytes kept, to ``rows.csv.torn``, and its episode is
run again.
"""
import csv
import errno
import io
import json
import os
import shutil

from closed_loop.batch.judge import OUTCOMES
from closed_loop.batch.sweep_file import SweepError

#: What the disk says when it cannot hold a write: no space, or the user's quota.
NO_ROOM = (errno.ENOSPC, errno.EDQUOT)
MIB = 1024.0 * 1024.0


class NoRoom(SweepError):
    """The disk that holds a sweep's folder is full; the message names the folder and the room needed."""


def no_room(folder, needed_bytes):
    """:class:`NoRoom` for ``folder``, which needs about ``needed_bytes`` more."""
    try:
        free = shutil.disk_usage(folder).free
    except OSError:
        free = 0
    return NoRoom('%s: the disk is full (%.1f MiB free; the rest of the sweep needs about %.1f MiB more): make '
                  'room and run it again with --resume (every row written so far is whole)'
                  % (folder, free / MIB, max(needed_bytes, 1) / MIB))


def _flat(value):
    if isinstance(value, str) and ('\n' in value or '\r' in value):
        return ' '.join(value.splitlines())
    return value


def csv_line(columns, row):
    """``row`` (a dict) as one CSV line of ``columns``, ending in CRLF as Python's csv writes it."""
    buffer = io.StringIO()
    csv.DictWriter(buffer, columns, extrasaction='ignore').writerow({k: _flat(v) for k, v in row.items()})
    return buffer.getvalue()


class LineFile:
    """A file of lines, appended one whole line at a time (``append``); ``check(text, position)`` says whether a
    line read back is whole (``position``: how many whole ones came before it). Opened, it reads the file a line at
    a time, hands each whole one to ``take(text, position)`` (if given), sets aside (to ``PATH.torn``) every line
    that is not, and ``count`` is how many are whole (the header first, if the file has one): a file of any size is
    opened in the memory of its torn lines."""

    def __init__(self, path, check, take=None):
        self.path = path
        with open(path, 'ab'):
            pass
        torn, count = {}, 0                    # {line number: its bytes} of the lines that are not whole
        for number, line in enumerate(_lines(path)):
            try:
                text = line.decode('utf-8')
            except UnicodeDecodeError:
                text = None
            if text is not None and text.endswith('\n') and check(text.rstrip('\r\n'), count):
                if take is not None:
                    take(text.rstrip('\r\n'), count)
                count += 1
            else:
                torn[number] = line
        self.torn, self.count = len(torn), count
        if torn:
            with open(path + '.torn', 'ab') as side:
                side.write(b''.join(line if line.endswith(b'\n') else line + b'\n' for line in torn.values()))
            with open(path + '.part', 'wb') as whole:
                for number, line in enumerate(_lines(path)):
                    if number not in torn:
                        whole.write(line)
            os.replace(path + '.part', path)
        self.fd = os.open(path, os.O_WRONLY | os.O_APPEND)

    def append(self, text):
        """Write ``text`` (one line, with its end) whole, or not at all and raise OSError."""
        data = text.encode('utf-8')
        size = os.fstat(self.fd).st_size
        try:
            written = os.write(self.fd, data)
            if written != len(data):            # the disk took part of it: the next write says why
                os.write(self.fd, data[written:])
        except OSError:
            os.ftruncate(self.fd, size)
            raise

    def close(self):
        os.close(self.fd)


def _lines(path):
    """The lines of the file at ``path`` as ``bytes.splitlines(keepends=True)`` has them (an end is \\n, \\r\\n or
    \\r), read a line at a time."""
    with open(path, 'rb') as f:
        for chunk in f:                        # (each ends at a line feed: a CR LF is never cut in two)
            yield from chunk.splitlines(keepends=True)


def open_rows(path, columns, each=None):
    """``(LineFile, rows)``: a sweep's rows file opened to append rows of ``columns`` (the header written if
    the file is new), and the whole rows already in it, as dicts of strings; with ``each``, each of them is handed
    to ``each(row)`` as it is read instead, and rows is None (a resumed sweep of any size is read in the memory of
    one row). A header of other columns (a different sweep's file) raises SweepError."""
    header = csv_line(columns, dict(zip(columns, columns))).rstrip('\r\n')

    def whole(text, position):
        if position == 0:
            return text == header
        cells = next(csv.reader([text]), [])
        if len(cells) != len(columns):
            return False
        row = dict(zip(columns, cells))
        try:
            int(row['index'])
            spec = json.loads(row['spec'])
        except ValueError:
            return False
        return isinstance(spec, dict) and row['outcome'] in OUTCOMES
    if os.path.exists(path):
        with open(path, 'rb') as f:
            first = f.readline().decode('utf-8', 'replace').rstrip('\r\n')
        if first and first != header and first.endswith(columns[-1]):
            raise SweepError("%s: its columns are another sweep's: choose another --output" % path)
    got = [] if each is None else None

    def take(text, position):
        if position:
            (each or got.append)(dict(zip(columns, next(csv.reader([text])))))
    rows = LineFile(path, whole, take)
    if not rows.count:
        rows.append(header + '\r\n')
        rows.count = 1
    return rows, got


class Rows:
    """A sweep's rows file, read as it is iterated (afresh each time): its rows as dicts of strings; ``len()``
    counts them. Nothing is held between rows, so a sweep of any size is read in the memory of one row (a file
    gone since raises FileNotFoundError: take ``list()`` of it first to keep the rows)."""

    def __init__(self, path):
        self.path = path

    def __iter__(self):
        with open(self.path, newline='') as f:
            yield from csv.DictReader(f)

    def __len__(self):
        return sum(1 for _ in self)


def open_trajectories(path):
    """The trajectories file (a JSON object per line) opened to append; torn lines set aside."""
    def whole(text, _position):
        try:
            return isinstance(json.loads(text), dict)
        except ValueError:
            return False
    return LineFile(path, whole)
