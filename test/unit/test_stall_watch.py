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


def test_a_loop_that_crawls_is_reported_each_stretch_and_one_that_keeps_pace_or_resets_is_not():
    clock = {'t': 0.0, 'step': 1.0}
    slow, stop = [], threading.Event()

    def loop():
        while not stop.is_set():
            clock['t'] += clock['step']
            time.sleep(0.01)
    thread = threading.Thread(target=loop)
    thread.start()
    # (1 a step of 10 ms: about 100x the wall time, and far over 0.05x however busy the machine; then at most 0.01x.)
    watch = StallWatch(lambda: clock['t'], lambda: False, lambda text: None, stall_s=0.3, check_s=0.05,
                       pace=(lambda: clock['t'], 0.05, lambda gone_on, wall_s: slow.append((gone_on, wall_s))))
    watch.start()
    try:
        time.sleep(1.0)
        assert slow == [], slow
        clock['step'] = 0.0001
        deadline = time.monotonic() + 60
        while len(slow) < 2 and time.monotonic() < deadline:
            time.sleep(0.05)
        clock['t'], clock['step'] = -100.0, 1.0      # a reset (a new episode), then pace kept: not a crawl
        time.sleep(1.0)
        assert len(slow) >= 2 and all(0 < gone_on < 0.05 * wall_s and wall_s >= 0.3 for gone_on, wall_s in slow), slow
    finally:
        stop.set()
        watch.stop()
        thread.join()
