"""record_bag: rosbag record of the loop, started without a shell and failing loudly (logic in closed_loop.recording)."""
import signal
import subprocess
import sys
import time

import rospy

from closed_loop import recording
from closed_loop.nodes.common import init_node, load_settings

#: How often the free space of the bag folder is checked while recording (s, wall clock).
ROOM_CHECK_PERIOD_S = 2.0
#: How long rosbag gets to close its bag after SIGINT before it is killed (s).
STOP_WAIT_S = 10.0


class RecordBag:
    """Runs ``rosbag record`` on the loop's topics into ``~bag_dir`` and exits non-zero if it cannot record.

    The folder is created if missing and checked before rosbag starts: writable, with at least
    ``~min_free_mb`` free. While recording, the free space is checked every few seconds (rosbag itself
    quietly stops writing on a full disk). Any of these failing, or rosbag exiting with an error, ends
    this node with a FATAL line naming the folder and status 1; ``record.launch`` marks it required, so
    the whole launch ends with it. ``~duration`` (s of wall time) stops the recording (the node stays up, idle). On
    shutdown rosbag gets SIGINT and closes its bag.

    Parameters: see :class:`closed_loop.recording.RecordSettings` (``~bag_dir``, ``~bag_name``,
    ``~images``, ``~compress``, ``~split_size_mb``, ``~max_splits``, ``~duration`` s, ``~min_free_mb``,
    ``~topics``).
    """

    def __init__(self):
        self.settings = s = load_settings(recording.RecordSettings)
        self.folder = recording.bag_folder(s)
        problem = recording.bag_dir_problem(s)
        if problem is not None:
            self.fail(problem)
        argv = recording.rosbag_argv(s)
        rospy.loginfo('recording %d topics into %s (%s_<date-time>.bag, split at %d MiB, keeping %s)',
                      len(recording.topics(s)), self.folder, s.bag_name, s.split_size_mb,
                      'all' if s.max_splits == 0 else 'the last %d' % s.max_splits)
        # An argv list: no shell sees the folder or the name. Its own session, so that a Ctrl-C meant for
        # roslaunch reaches rosbag only through this node, which stops it and waits for the bag.
        self.process = subprocess.Popen(argv, start_new_session=True)
        self.started = time.monotonic()
        self.stopped_on_purpose = False
        rospy.on_shutdown(self.stop)

    def fail(self, problem):
        rospy.logfatal('recording failed: %s', problem)
        sys.exit(1)

    def stop(self):
        """Stop rosbag (SIGINT, then SIGKILL after STOP_WAIT_S) so it closes its bag."""
        if self.process.poll() is None:
            self.stopped_on_purpose = True
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(STOP_WAIT_S)
            except subprocess.TimeoutExpired:
                self.process.kill()

    def run(self):
        s = self.settings
        while not rospy.is_shutdown():
            code = self.process.poll()
            if code is not None and not self.stopped_on_purpose:
                self.fail('rosbag record exited with status %d while recording into %s' % (code, self.folder))
            if code is None:
                problem = recording.room_problem(self.folder, s.min_free_mb)
                if problem is not None:
                    self.stop()
                    self.fail(problem)
                if s.duration > 0 and time.monotonic() - self.started >= s.duration:
                    rospy.loginfo('recorded for ~duration (%g s); stopping rosbag', s.duration)
                    self.stop()
            # The wall clock: simulated time may run faster than it, or stop with the simulator.
            time.sleep(ROOM_CHECK_PERIOD_S)


def main():
    init_node('record_bag')
    RecordBag().run()
