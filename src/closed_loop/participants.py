"""Which processes take part in a lockstepped graph (``closed_loop.quiescence``): a root process's descendants, the
master beside them, and the simulator's own threads but the one that waits. Free of ROS: it reads ``/proc``."""
import os
import threading


class Participants:
    """The processes that take part: ``root_pid``'s descendants and ``extra`` pids but ``exclude`` ones (a set, or
    a callable that gives one from the pids found, asked at each look-up), and the calling process (``own_pid``) but
    its calling thread (``own_tid``)."""

    def __init__(self, root_pid, own_pid=None, own_tid=None, extra=(), exclude=()):
        self.root_pid = root_pid
        self.own_pid = os.getpid() if own_pid is None else own_pid
        self.own_tid = threading.get_native_id() if own_tid is None else own_tid
        self.extra = tuple(extra)
        self.exclude = exclude if callable(exclude) else frozenset(exclude)

    def pids(self):
        """The participants' pids now (the calling process among them; the root itself is not)."""
        children = {}
        for name in os.listdir('/proc'):
            if name.isdigit():
                ppid = _ppid(int(name))
                if ppid is not None:
                    children.setdefault(ppid, []).append(int(name))
        found, todo = set(), [self.root_pid] if self.root_pid else []
        while todo:
            for child in children.get(todo.pop(), ()):
                if child not in found:
                    found.add(child)
                    todo.append(child)
        found.update(pid for pid in self.extra if os.path.exists('/proc/%d' % pid))
        found -= self.exclude(frozenset(found)) if callable(self.exclude) else self.exclude
        found.add(self.own_pid)
        return found

    def threads(self, pid):
        """The thread ids of process ``pid`` that take part."""
        return {int(tid) for tid in os.listdir('/proc/%d/task' % pid)} - {self.own_tid}

    @staticmethod
    def kernel_threads():
        """The kernel's softirq threads, where this machine shows them (not inside a PID namespace)."""
        found = []
        for name in os.listdir('/proc'):
            if name.isdigit():
                try:
                    with open('/proc/%s/comm' % name) as f:
                        if f.read().startswith('ksoftirqd/'):
                            found.append(int(name))
                except OSError:
                    pass
        return found


def name_of(pid):
    """A process as a log line names it: a ROS node's name (its ``__name:=`` argument) or its program's, and its
    pid."""
    args = _strings('/proc/%d/cmdline' % pid)
    node = _argument(args, '__name:=')
    program = next((os.path.basename(a) for a in args[1:2] if not a.startswith('-')), None) if args else None
    return '%s (pid %d)' % (node or program or (os.path.basename(args[0]) if args else 'a process gone'), pid)


def node_name(pid):
    """The global name of the ROS node process ``pid`` was started as (``__name:=``, in the namespace of ``__ns:=``
    or else of its ``ROS_NAMESPACE``, as roslaunch starts nodes), read before it has told any master; None for a
    process started without ``__name:=`` (or gone)."""
    args = _strings('/proc/%d/cmdline' % pid)
    name = _argument(args, '__name:=')
    if not name:
        return None
    namespace = _argument(args, '__ns:=')
    if namespace is None:
        namespace = _argument(_strings('/proc/%d/environ' % pid), 'ROS_NAMESPACE=') or ''
    return '/' + '/'.join(part for part in (namespace + '/' + name).split('/') if part)


def _strings(path):
    """The NUL-separated strings of a /proc file (a process's arguments or environment); [] where it is gone."""
    try:
        with open(path, 'rb') as f:
            return [a.decode(errors='replace') for a in f.read().split(b'\0') if a]
    except OSError:
        return []


def _argument(strings, prefix):
    """The rest of the first of ``strings`` that starts with ``prefix``, or None."""
    return next((a[len(prefix):] for a in strings if a.startswith(prefix)), None)


def _ppid(pid):
    try:
        with open('/proc/%d/stat' % pid, 'rb') as f:
            return int(f.read().rsplit(b')', 1)[1].split()[1])
    except (OSError, ValueError, IndexError):
        return None
