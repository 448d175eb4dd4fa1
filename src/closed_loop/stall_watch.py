"""A thread that says where a loop stands when it has stopped going on: the loop's thread's stack, once per stall,
so that a run that hangs shows where in its own log. Free of ROS."""
import sys
import threading
import traceback


class StallWatch:
    """Every ``check_s`` (wall s), ``progress()`` (any value that changes as the loop goes on) is compared with the
    last; where it has not changed for ``stall_s`` while ``idle()`` is false, ``report(text)`` is called once, with
    the stack of thread ``thread_id`` (default: the one that made the watch), until it changes again."""

    def __init__(self, progress, idle, report, stall_s, check_s=1.0, thread_id=None):
        self.progress, self.idle, self.report = progress, idle, report
        self.stall_s, self.check_s = stall_s, check_s
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
        while not self._stop.wait(self.check_s):
            now = self.progress()
            if now != last or self.idle():
                last, still, reported = now, 0.0, False
                continue
            still += self.check_s
            if still >= self.stall_s and not reported:
                reported = True
                frame = sys._current_frames().get(self.thread_id)
                where = ''.join(traceback.format_stack(frame)) if frame is not None else '(the thread is gone)\n'
                self.report('no progress for %g s of wall time; the loop stands at:\n%s' % (still, where.rstrip()))
