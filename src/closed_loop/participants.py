"""Which processes take part in a lockstepped graph (``closed_loop.quiescence``): a root process's descendants, the
master beside them, and the simulator's own threads but the one that waits. Free of ROS: it reads ``/proc``."""
import os
import threading


class Participants:
    """The processes that take part: ``root_pid``'s descendants and ``extra`` pids but ``exclude`` ones (a set, or
    a callable that gives one, asked at each look-up), and the calling process (``own_pid``) but its calling thread
    (``own_tid``)."""

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
        found -= self.exclude() if callable(self.exclude) else self.exclude
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
    try:
        with open('/proc/%d/cmdline' % pid, 'rb') as f:
            args = [a.decode(errors='replace') for a in f.read().split(b'\0') if a]
    except OSError:
        args = []
    node = next((a[len('__name:='):] for a in args if a.startswith('__name:=')), None)
    program = next((os.path.basename(a) for a in args[1:2] if not a.startswith('-')), None) if args else None
    return '%s (pid %d)' % (node or program or (os.path.basename(args[0]) if args else 'a process gone'), pid)


def _ppid(pid):
    try:
        with open('/proc/%d/stat' % pid, 'rb') as f:
            return int(f.read().rsplit(b')', 1)[1].split()[1])
    except (OSError, ValueError, IndexError):
        return None
