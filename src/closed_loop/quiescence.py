"""When a graph's processes have done all that what they were given asks of them: the simulator's lockstep.

Free of ROS: it reads ``/proc``. A lockstepped simulator publishes what happens at one instant, then waits until
every process that takes part in the graph is *quiet*: each of its threads asleep, and none of them run while it
looked. Then every message sent has been read and every callback it started has returned, whatever the nodes
are written in and however they are threaded (a command sent from a scan's callback, from a timer woken by
``/clock``, or from a node that was itself woken by another node); only then does simulated time go on.

How it is seen: each thread's count of run time and time slices (``/proc/PID/task/TID/schedstat``), read twice,
and between the two readings its state (``.../stat``). The graph is quiet when no count changed between the
readings and no thread was running or waiting to run (a thread being woken on another CPU shows as running, though
no count of the machine's runnable tasks has it yet): then no participant ran while we looked, and none will until
something new reaches it. A message in flight on loopback is delivered, and its reader woken, before the sender's
write returns (or by the kernel's ``ksoftirqd`` threads, which are watched too where this machine shows them).

What takes part: the processes a root process (the launch that started the simulator) started, at any depth; the
ROS master (a node that asks it something, a parameter or even rospy's own check at every line it logs, waits
asleep for the answer: the master's threads are watched, and the new thread it starts for each request shows as a
change in its count of threads); not rosout, which only collects log lines; and the simulator's own threads but
the one that waits. They are looked up again every ``refresh_s`` of wall time (a node that starts later, a
respawned one). A node that waits on something outside all these (a server elsewhere) looks idle while it waits:
the simulator goes on without its answer. A busy process that has *computed* for ``timeout_s`` since the wait began
(CPU time: a node kept from the CPU by a busy machine is waited for, so the run does not turn on the load), or stayed
busy for :data:`BACKSTOP` times that of wall time (blocked on a disk, starved for good), is *missed*: the wait ends,
the instant counts as missed, and that process is not waited for again until it is seen quiet (a hung node costs
one timeout, not one per instant). A node that sleeps on something that never comes (a service
that does not answer) is quiet: it simply does not answer, the same way every time.

Pollers: some threads do not wait to be woken but look again on their own, every so often of wall time:
roscpp's timers and sleeps on simulated time check the clock every millisecond, and ``rospy.wait_for_message``
checks for its message every 10 ms. Asleep between two looks, such a thread seems done while what it was given
still waits for it. :meth:`Quiescence.find_pollers` finds them (threads that ran in a good share of the short bins
of a moment when nothing was sent), and ``wait(poll=...)`` is not over until each poller of the processes named
has looked again after the last thing any other thread did (then the graph is quiet as above).
"""
import os
import time

from closed_loop.participants import Participants, name_of  # noqa: F401  (Participants re-exported: who takes part)

#: States of a thread that is not working: asleep (S), stopped (T, t: SIGSTOP or a debugger), dead (Z, X), idle
#: kernel thread (I). Running or runnable (R) and in uninterruptible sleep (D: I/O it asked for) are busy.
QUIET_STATES = frozenset((b'S', b'T', b't', b'Z', b'X', b'I'))
#: Pollers are found over POLLERS_WINDOW_S of wall time, in bins of POLLERS_BIN_S: a thread that ran in at least
#: POLLERS_SHARE of the bins looks again every 16 ms or more often (roscpp's timers every 1 ms, wait_for_message every
#: 10 ms); rospy's own loops look every 0.3 to 0.5 s, roscpp's every 0.1 s, a recorder looking for new topics every
#: 50 ms: not pollers, and not waited for.
POLLERS_WINDOW_S, POLLERS_BIN_S, POLLERS_SHARE = 0.1, 0.005, 0.3
#: Pollers that ran in this share of the bins look every 1 or 2 ms: roscpp's timers and sleeps, watching the clock.
#: They are waited for after a /clock (``wait(poll=EVERY)``), not after each message (``wait(poll=pids)``): what
#: they watch is the clock, not the messages.
CLOCK_POLLERS_SHARE = 0.9
#: A poller not seen to look again for this long (wall s) is one no more (it had run for another reason while it
#: was watched, or what it waits for now wakes it): it is not waited for again.
POLLER_GIVE_UP_S = 0.1
#: A wait looks again at once (yielding the CPU) up to SPIN_LOOKS times within SPIN_S (wall s), then naps between
#: looks: NAP_S at first, then NAP_SHARE of how long it has waited so far, at most NAP_MAX_S. A node's answer takes
#: some tens of microseconds, and the spin finds it; a long wait (on a machine with more work than cores, where the
#: nodes wait for a CPU) looks a few dozen times, not thousands, each look a read of every thread's /proc files,
#: and leaves the CPU to the nodes it waits for. When the graph is seen quiet is the same either way: only later.
SPIN_LOOKS, SPIN_S, NAP_S, NAP_SHARE, NAP_MAX_S = 30, 0.005, 0.0002, 0.1, 0.01
#: ``wait(poll=EVERY)``: the pollers of every process.
EVERY = object()
#: A busy process is missed at the latest after this many times ``timeout_s`` of wall time (the module's doc); past
#: ``timeout_s`` of wall time, its CPU time is looked at every RECHECK_S (wall s).
BACKSTOP, RECHECK_S = 10, 0.1


def _open(path):
    try:
        return os.open(path, os.O_RDONLY)
    except OSError:
        return None


def _read(fd, size):
    """What an open /proc file says now (b'' once its thread is gone)."""
    try:
        return os.pread(fd, size, 0)
    except OSError:
        return b''


def _state(stat):
    """A thread's state letter from the start of its stat line (dead for one that is gone)."""
    if not stat:
        return b'X'
    close = stat.rfind(b')')
    return stat[close + 2:close + 3] if close >= 0 else b'R'     # (a name cut off by the read: not seen, busy)


class Quiescence:
    """``wait()`` until the participants are quiet, or ``timeout_s`` of wall time; the count of misses is kept.

    ``participants``: a :class:`Participants`; ``refresh_s``: how often (wall s) the set of processes is
    looked up again. Their threads are listed again whenever a process's count of threads changes. ``stopping``:
    a callable, true once the waiting is to end (the graph shuts down): a wait then ends at once, not missed."""

    def __init__(self, participants, timeout_s, refresh_s=0.5, clock=time.monotonic, stopping=lambda: False):
        self.participants = participants
        self.stopping = stopping
        self.timeout_s = timeout_s
        self.refresh_s = refresh_s
        self.clock = clock
        self.missed = 0
        self.excused = set()         # pids missed and not seen quiet since
        self.last_miss = None        # (pids busy, starved) of the last miss: starved by the wall-time backstop
        self._kernel = Participants.kernel_threads()
        self._processes = {}         # pid -> (its stat fd, its count of threads when listed)
        self._threads = {}           # (pid, tid) -> (stat fd, schedstat fd)
        self._keys, self._sched, self._stat = [], [], []
        self._refreshed = -float('inf')
        self._last = None            # the counts at the end of the last wait
        self.pollers = set()         # (pid, tid) of the threads that look again on their own
        self.clock_pollers = set()   # those of them that look every 1 or 2 ms (at the clock)

    def close(self):
        for fd in [fd for fds in self._threads.values() for fd in fds] + [fd for fd, _ in self._processes.values()]:
            os.close(fd)
        self._threads.clear()
        self._processes.clear()

    def restart(self):
        """A new episode (a kept graph's): nothing missed, no poller known, the participants looked up again now."""
        self.missed, self.excused, self.last_miss = 0, set(), None
        self.pollers, self.clock_pollers = set(), set()
        self._refreshed, self._last = -float('inf'), None

    def why_last_miss(self):
        """The last miss in words: which processes were busy, and by which rule they were missed."""
        if self.last_miss is None:
            return 'none'
        pids, starved = self.last_miss
        who = ', '.join(name_of(pid) for pid in pids) or 'a process gone'
        if starved:
            return '%s busy for %g s of wall time without computing %g s (kept from the CPU, or blocked)' % (
                who, BACKSTOP * self.timeout_s, self.timeout_s)
        return '%s computing for over %g s of CPU time' % (who, self.timeout_s)

    def find_pollers(self, window_s=POLLERS_WINDOW_S):
        """Look at the participants for ``window_s`` of wall time, while nothing is sent to them, in bins of
        :data:`POLLERS_BIN_S`, and keep as pollers the threads that ran in at least :data:`POLLERS_SHARE` of the
        bins (a thread that looks every 10 ms runs in about half of them; one busy with a burst of work that ends,
        or one that looks every 50 ms, in a few). Returns them, as (pid, tid)."""
        self._refresh_processes()
        self._list_threads()
        bins = max(2, int(round(window_s / POLLERS_BIN_S)))
        active = [0] * len(self._keys)
        before = _reads(self._sched, 64)
        for _ in range(bins):
            time.sleep(POLLERS_BIN_S)
            after = _reads(self._sched, 64)
            states = _reads(self._stat, 48)
            # (Runnable counts as looking: on a machine with more work than cores a poller waits for a CPU.)
            for i, (b, a, state) in enumerate(zip(before, after, states)):
                active[i] += b != a and a != b'' or _state(state) == b'R'
            before = after
        # The kernel's softirq threads carry the graph's loopback traffic and are watched for it, but they look at
        # nothing of their own: never pollers (on a loaded machine they run in most bins).
        ours = [(key, n) for key, n in zip(self._keys, active) if key[0] not in self._kernel]
        self.pollers = {key for key, n in ours if n >= POLLERS_SHARE * bins}
        self.clock_pollers = {key for key, n in ours if n >= CLOCK_POLLERS_SHARE * bins}
        self._last = None
        return self.pollers

    def wait(self, poll=None):
        """True once quiet; False when a busy process computed for ``timeout_s`` first, or stayed busy for BACKSTOP
        times that of wall time (a miss: the busy processes are excused).
        ``poll``: the pids whose pollers must look again, after the last thing any other thread did, before it is
        over (EVERY: every process's, after a clock; None: none; pids: after a message to them, their pollers but
        those that watch the clock)."""
        now = self.clock()
        if now - self._refreshed >= self.refresh_s:
            self._refresh_processes()
            self._refreshed = now
        deadline, backstop = now + self.timeout_s, now + BACKSTOP * self.timeout_s
        first = None                       # the counts when the threads were last listed in this wait
        excused = self.excused
        before = self._last
        check = True                       # whether the thread lists are to be checked
        waiting = {}                       # {index: (its count of runs when seen asleep, or None)} of the pollers
                                           # yet to look again
        # The pollers' counts are to be taken at the next reading: at first (one made wholly after what the caller
        # did, which a poller may find without being woken), and after anything ran.
        fresh = True
        looked = {}                        # {index: wall time} each poller was last seen to look
        looks = 0
        while True:
            if check and self._threads_changed():      # (a thread started or ended: list them again)
                self._list_threads()
                before, waiting, looked, fresh, first = None, {}, {}, True, None
            check = False
            if before is None or len(before) != len(self._sched):
                before = _reads(self._sched, 64)
                first = before
            elif first is None:
                first = before
            after = _reads(self._sched, 64)
            moved = self._moved(before, after)
            t = self.clock()
            for i in waiting:
                if after[i] != before[i] or i not in looked:
                    looked[i] = t
            if moved:
                # Something ran: every poller awaited is to look again after it, counted from the next reading, which
                # begins once this one has seen it (what ran may have finished only as this reading went by: a
                # poller read before it and run after it, but before it finished, saw none of it).
                fresh = True
            elif fresh:
                waiting = {i: self._asleep_mark(i) for i in self._pollers_of(poll, after)}
                fresh = False
            elif waiting:
                # A poller has looked again once it has been seen asleep since the reference and has run after that:
                # one that ran again without that may have been finishing a look begun before (preempted in it).
                for i, mark in list(waiting.items()):
                    if mark is None:
                        waiting[i] = self._asleep_mark(i)
                    elif _slices(after[i]) != mark:
                        del waiting[i]
                # A poller not seen to look for a while and asleep now looks no more (not a poller); one that is
                # runnable waits for a CPU (a loaded machine), and is waited for.
                gone = {i for i in waiting if t - looked.get(i, t) > POLLER_GIVE_UP_S
                        and _state(_read(self._stat[i], 48)) in QUIET_STATES}
                if gone:
                    self.pollers -= {self._keys[i] for i in gone}
                    waiting = {i: n for i, n in waiting.items() if i not in gone}
            if not moved and not fresh and not waiting:
                # Nothing ran between the two readings (but pollers, and the excused): are all asleep now, and still
                # nothing ran since?
                states = _reads(self._stat, 48)
                again = _reads(self._sched, 64)
                if not self._moved(after, again) and self._asleep(states):
                    if not self._threads_changed():
                        if excused:       # an excused process seen quiet is waited for again
                            excused -= {pid for pid in excused if self._asleep(states, only=pid)
                                        and not self._moved(after, again, only=pid)}
                        self._last = again
                        return True
                    check = True
                after = again
            if self.stopping():
                self._last = None
                return True
            if self.clock() > deadline:
                states = _reads(self._stat, 48)
                busy = self._busy(before, after, states)
                starved = self.clock() >= backstop
                used = self._computed(first, after, busy - excused)
                if not starved and max(used.values(), default=0.0) < self.timeout_s:
                    deadline = self.clock() + min(self.timeout_s, RECHECK_S)      # (kept from the CPU: wait on)
                else:
                    self.missed += 1
                    computed = [pid for pid, seconds in used.items() if seconds >= self.timeout_s]
                    self.last_miss = (tuple(sorted(computed if not starved and computed else busy - excused)), starved)
                    excused |= busy
                    self._last = None
                    return False
            before = after
            # Look again at once for a little while, then nap, longer the longer the wait (SPIN_LOOKS).
            looks += 1
            waited = self.clock() - now
            if looks < SPIN_LOOKS and waited < SPIN_S:
                os.sched_yield()
            else:
                time.sleep(min(NAP_MAX_S, max(NAP_S, NAP_SHARE * waited)))

    def _moved(self, before, after, only=None):
        """True if a thread ran between the two readings: but a poller (it runs every few ms anyway) and a thread of
        an excused process; ``only``: of process ``only`` (whatever it is)."""
        if before == after:
            return False
        if only is not None:
            return any(b != a and key[0] == only for key, b, a in zip(self._keys, before, after))
        pollers, excused = self.pollers, self.excused
        return any(b != a and key not in pollers and key[0] not in excused
                   for key, b, a in zip(self._keys, before, after))

    def _computed(self, first, counts, pids):
        """{pid: the CPU time (s) it has had between the readings ``first`` and ``counts``} of ``pids``."""
        if first is None or len(first) != len(counts):
            return {}
        used = {}
        for key, a, b in zip(self._keys, first, counts):
            if key[0] in pids and b:
                used[key[0]] = used.get(key[0], 0.0) + (_run_ns(b) - _run_ns(a)) * 1e-9
        return used

    def _asleep(self, states, only=None):
        """True if every thread (of process ``only``; but those of excused processes) is asleep in ``states``."""
        excused = self.excused
        return all(_state(stat) in QUIET_STATES for key, stat in zip(self._keys, states)
                   if (key[0] == only if only is not None else key[0] not in excused))

    def _asleep_mark(self, i):
        """Poller ``i``'s count of runs if it is asleep now (its state read before the count: a run after the count
        began after it was seen asleep), else None."""
        if _state(_read(self._stat[i], 48)) in QUIET_STATES:
            return _slices(_read(self._sched[i], 64))
        return None

    def _pollers_of(self, poll, counts):
        """{index: time slices in ``counts``} of the pollers to await: every poller (``poll`` EVERY), or the pollers
        of ``poll``'s processes but those that watch the clock."""
        if poll is None or not self.pollers or counts is None or len(counts) != len(self._keys):
            return {}
        return {i: _slices(counts[i]) for i, key in enumerate(self._keys) if key in self.pollers
                and key[0] not in self.excused and (poll is EVERY or key[0] in poll and key not in self.clock_pollers)}

    def _busy(self, before, after, states):
        """The pids that ran between the two readings, or are not asleep."""
        busy = set()
        for i, key in enumerate(self._keys):
            if before[i] != after[i] or _state(states[i]) not in QUIET_STATES:
                busy.add(key[0])
        return busy

    # -- which processes and threads ---------------------------------------------------------------------------
    def _refresh_processes(self):
        pids = self.participants.pids() | set(self._kernel)
        for pid in set(self._processes) - pids:
            os.close(self._processes.pop(pid)[0])
        for pid in pids - set(self._processes):
            fd = _open('/proc/%d/stat' % pid)
            if fd is not None:
                self._processes[pid] = (fd, -1)

    def _threads_changed(self):
        """True if a process's count of threads differs from when its threads were listed (or it is gone)."""
        for fd, listed in self._processes.values():
            stat = _read(fd, 512)
            if not stat or int(stat[stat.rindex(b')') + 2:].split()[17]) != listed:
                return True
        return False

    def _list_threads(self):
        wanted = set()
        for pid, (fd, _) in list(self._processes.items()):
            stat = _read(fd, 512)
            try:
                tids = self.participants.threads(pid) if pid not in self._kernel else {pid}
            except OSError:
                tids = None
            if not stat or tids is None:
                os.close(self._processes.pop(pid)[0])
                continue
            self._processes[pid] = (fd, int(stat[stat.rindex(b')') + 2:].split()[17]))
            wanted.update((pid, tid) for tid in tids)
        for key in wanted - set(self._threads):
            folder = '/proc/%d/task/%d/' % key
            fds = (_open(folder + 'stat'), _open(folder + 'schedstat'))
            if None in fds:
                for fd in fds:
                    if fd is not None:
                        os.close(fd)
                continue
            self._threads[key] = fds
        for key in set(self._threads) - wanted:
            for fd in self._threads.pop(key):
                os.close(fd)
        self._keys = list(self._threads)
        self._stat = [self._threads[key][0] for key in self._keys]
        self._sched = [self._threads[key][1] for key in self._keys]


def _run_ns(schedstat):
    """A thread's time on a CPU (ns) from its schedstat line (0 for one not there)."""
    fields = schedstat.split()
    return int(fields[0]) if fields else 0


def _slices(schedstat):
    """A thread's count of time slices (how many times it has run) from its schedstat line (0 once it is gone)."""
    fields = schedstat.split()
    return int(fields[2]) if len(fields) > 2 else 0


def _reads(fds, size):
    """What each open /proc file says now, in order (b'' for a thread that is gone)."""
    try:
        return [os.pread(fd, size, 0) for fd in fds]
    except OSError:
        return [_read(fd, size) for fd in fds]
