"""A thread that says where a loop stands when it has stopped going on: the loop's thread's stack, once per stall,
so that a run that hangs shows where in its own log; and, given a measure of its progress, when it goes on far
slower than it should (a run that crawls looks like one that hangs from outside). Free of ROS."""
import sys
import threading
import time
import traceback


class StallWatch:
    """Every ``check_s`` (wall s), ``progress()`` (any value that changes as the loop goes on) is compared with the
    last; where it has not changed for ``stall_s`` while ``idle()`` is false, ``report(text)`` is called once, with
    the stack of thread ``thread_id`` (default: the one that made the watch), until it changes again."""

    def __init__(self, progress, idle, report, stall_s, check_s=1.0, thread_id=None, pace=None):
        """``pace``: (measure, least, report_slow): where ``measure()`` (a number, such as simulated time) has gone
        on by less than ``least`` times the wall time over a stretch of ``stall_s`` of wall time (not idle, and
        not back: a reset), ``report_slow(gone_on, wall_s)`` is called, once per such stretch."""
        self.progress, self.idle, self.report = progress, idle, report
        self.stall_s, self.check_s = stall_s, check_s
        self.pace = pace
        self.thread_id = threading.get_ident() if thread_id is None else thread_id
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name='stall-watch', daemon=True)

    def start(self):
        self._thread.start()
        return self

    def stop(self):
        self._stop.set()

    def _run(self):
        last, still, reported = self.progress(), 0.0, False
        stretch = [time.monotonic(), self._measure()]     # (when the pace's stretch began, the measure then)
        while not self._stop.wait(self.check_s):
            now = self.progress()
            self._pace(stretch)
            if now != last or self.idle():
                last, still, reported = now, 0.0, False
                continue
            still += self.check_s
            if still >= self.stall_s and not reported:
                reported = True
                frame = sys._current_frames().get(self.thread_id)
                where = ''.join(traceback.format_stack(frame)) if frame is not None else '(the thread is gone)\n'
                self.report('no progress for %g s of wall time; the loop stands at:\n%s' % (still, where.rstrip()))

    def _measure(self):
        return self.pace[0]() if self.pace else None

    def _pace(self, stretch):
        """At the end of the pace's stretch (``stall_s`` of wall time), report a slow one, and begin the next."""
        if self.pace is None:
            return
        measure, least, report_slow = self.pace
        if self.idle():
            stretch[:] = [time.monotonic(), measure()]
            return
        wall_s = time.monotonic() - stretch[0]
        if wall_s >= self.stall_s:
            gone_on = measure() - stretch[1]
            if 0.0 < gone_on < least * wall_s:      # (none: a stall, reported above; less than none: a reset)
                report_slow(gone_on, wall_s)
            stretch[:] = [time.monotonic(), measure()]
