"""closed_loop.stall_watch: a loop that stops going on is reported once, with where its thread stands; one that
goes on, or is idle, is not."""
import threading
import time

from closed_loop.stall_watch import StallWatch


def stuck_here(release):
    release.wait(10)


def test_a_loop_that_stands_is_reported_once_with_its_stack_and_not_while_it_goes_on_or_idles():
    reports, state = [], {'step': 0, 'idle': False}
    release, ready = threading.Event(), threading.Event()

    def loop():
        ready.set()
        while state['step'] < 5:          # goes on for a while, then stands in stuck_here
            state['step'] += 1
            time.sleep(0.05)
        stuck_here(release)
    thread = threading.Thread(target=loop)
    thread.start()
    ready.wait(5)
    watch = StallWatch(lambda: state['step'], lambda: state['idle'], reports.append, stall_s=0.3, check_s=0.05,
                       thread_id=thread.ident).start()
    try:
        # (Waited for up to a generous bound, not a fixed time: the test runs beside others on a busy machine.)
        deadline = time.monotonic() + 60
        while not reports and time.monotonic() < deadline:
            time.sleep(0.05)
        time.sleep(0.6)                       # (standing on: not reported again)
        assert len(reports) == 1, reports
        assert reports[0].startswith('no progress for 0.3') and 'in stuck_here' in reports[0], reports[0]
        state['idle'] = True                  # (paused: standing is what it should do)
        state['step'] += 1
        time.sleep(0.6)
        assert len(reports) == 1, reports
    finally:
        watch.stop()
        release.set()
        thread.join()
