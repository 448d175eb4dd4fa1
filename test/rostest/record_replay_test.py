#!/usr/bin/env python3
"""record.launch bags every loop topic of a running demo, and the bag replays faithfully.

The robot drives in `wall`; record.launch runs as a separate roslaunch on the same master for a few
simulated seconds (through the slowdown) and is stopped with SIGINT, as a user would. The bag must
hold every listed topic. Its scans are then replayed (``rosbag play``, /scan remapped to
/replay/scan) into a second obstacle_detector: it must publish exactly (float32) the distances the
live detector published for those scans, in the same order.
"""
import glob
import math
import os
import signal
import subprocess
import sys
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from std_msgs.msg import Float32

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import harness  # noqa: E402

# record.launch's topics (images included, its default).
RECORDED_TOPICS = ('/cmd_vel', '/scan', '/camera/image_raw', '/camera/camera_info', '/odom', '/tf',
                   '/tf_static', '/obstacle_distance', '/red_detected')
MOVING_MPS = 0.1
# Simulated seconds of driving to record: from cruise into the slowdown and the stop in `wall`.
RECORD_S = 8.0
# Recording starts and ends mid-stream, so the bag's first and last few scans may have no
# recorded distance (or the other way round).
END_SLACK_MESSAGES = 3
# rosbag record subscribes to each topic on its own; under load the simulator can answer the /scan
# subscription a second or more after the detector answers /obstacle_distance's, so the live distances
# may begin well before the recorded scans. The offset is searched over the whole bag.
# The replayed distances must vary, or matching them against the live ones proves little.
MIN_DISTINCT_DISTANCES = 10

# Bounds that only catch hangs.
RECORD_START_WAIT_S = 60.0
RECORD_STOP_WAIT_S = 30.0
PLAY_LIMIT_S = 90.0
CONNECT_WAIT_S = harness.WAIT_FOR_TOPIC_S
# Time for the last replayed distance to arrive after rosbag play has exited.
REPLAY_SETTLE_S = 1.0
POLL_S = 0.05


def same_float(a, b):
    return a == b or (math.isnan(a) and math.isnan(b))


def wait_until(condition, timeout_s, what):
    deadline = time.monotonic() + timeout_s
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError('%s within %g s' % (what, timeout_s))
        time.sleep(POLL_S)


def best_alignment(replayed, live):
    """(offset, overlap) with ``replayed[i] == live[i + offset]`` over the whole overlap, the longest
    such overlap over every offset; (None, 0) when no offset matches."""
    best = (None, 0)
    for offset in range(-len(replayed) + 1, len(live)):
        pairs = [(value, live[i + offset]) for i, value in enumerate(replayed) if 0 <= i + offset < len(live)]
        if pairs and all(same_float(a, b) for a, b in pairs) and len(pairs) > best[1]:
            best = (offset, len(pairs))
    return best


def skipped_live(replayed, live):
    """Indices of ``live`` passed over when matching ``replayed`` in order (for failure messages)."""
    skipped, j = [], 0
    for value in replayed:
        while j < len(live) and not same_float(live[j], value):
            skipped.append(j)
            j += 1
        j += 1
    return skipped


class RecordReplay(unittest.TestCase):
    def setUp(self):
        self.record = None

    def tearDown(self):
        # A failed test must not leave the recorder running.
        if self.record is not None and self.record.poll() is None:
            os.killpg(self.record.pid, signal.SIGKILL)
            self.record.wait()

    def test_record_then_replay(self):
        rospy.init_node('record_replay_test')
        truth = harness.GroundTruth()
        replayed = []
        lock = threading.Lock()

        def on_replayed(msg):
            with lock:
                replayed.append(msg.data)

        replay_sub = rospy.Subscriber('/replay/obstacle_distance', Float32, on_replayed, queue_size=100)
        truth.wait(predicate=lambda m: m.twist.twist.linear.x > MOVING_MPS)

        out = harness.output_dir('record_replay')
        # A folder that does not exist yet: record.launch must create it.
        bag_dir = os.path.join(out, 'bags_%d' % os.getpid())
        self.assertFalse(os.path.exists(bag_dir))
        prefix = os.path.join(bag_dir, 'loop')
        earlier = set(glob.glob(prefix + '_*'))
        with open(os.path.join(out, 'record_launch.log'), 'w') as log:
            # Its own process group, so SIGINT reaches roslaunch and rosbag record as a Ctrl-C would.
            self.record = subprocess.Popen(['roslaunch', 'closed_loop', 'record.launch', 'bag_dir:=' + bag_dir,
                                            'bag_name:=loop'],
                                           stdout=log, stderr=subprocess.STDOUT, start_new_session=True)

        def new_files(pattern):
            return sorted(set(glob.glob(prefix + pattern)) - earlier)

        wait_until(lambda: new_files('_*.bag.active'), RECORD_START_WAIT_S, 'no bag being recorded')
        harness.sim_sleep(RECORD_S)
        os.killpg(self.record.pid, signal.SIGINT)
        self.record.wait(timeout=RECORD_STOP_WAIT_S)
        wait_until(lambda: new_files('_*.bag') and not new_files('_*.bag.active'), RECORD_STOP_WAIT_S,
                   'the bag was not closed')
        bags = new_files('_*.bag')
        self.assertEqual(len(bags), 1, bags)
        bag_path = bags[0]

        with rosbag.Bag(bag_path) as bag:
            counts = {topic: info.message_count
                      for topic, info in bag.get_type_and_topic_info().topics.items()}
            live = [msg.data for _, msg, _ in bag.read_messages(topics=['/obstacle_distance'])]
        for topic in RECORDED_TOPICS:
            self.assertGreater(counts.get(topic, 0), 0, '%s not in the bag (%s)' % (topic, counts))
        scan_count = counts['/scan']

        wait_until(lambda: replay_sub.get_num_connections() > 0, CONNECT_WAIT_S,
                   'the replay obstacle_detector did not connect')
        # --topics takes every following word, so it comes last.
        play = subprocess.run(['rosbag', 'play', '--quiet', '--wait-for-subscribers', bag_path,
                               '/scan:=/replay/scan', '--topics', '/scan'],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=PLAY_LIMIT_S)
        self.assertEqual(play.returncode, 0, play.stdout.decode(errors='replace'))
        time.sleep(REPLAY_SETTLE_S)
        with lock:
            replay = list(replayed)

        self.assertGreaterEqual(len(replay), scan_count - END_SLACK_MESSAGES,
                                '%d distances replayed for %d recorded scans' % (len(replay), scan_count))
        self.assertLessEqual(len(replay), scan_count)
        self.assertGreaterEqual(len(set(replay)), MIN_DISTINCT_DISTANCES,
                                'the recording hardly moved: %s' % sorted(set(replay)))
        offset, overlap = best_alignment(replay, live)
        if offset is None:
            self.fail('the replayed distances are no contiguous run of the live ones: live distances %s have no '
                      'replayed counterpart (a scan lost or one too many on one side)\nreplayed %s\nlive %s'
                      % (skipped_live(replay, live), replay, live))
        self.assertGreaterEqual(overlap, scan_count - 2 * END_SLACK_MESSAGES,
                                'only %d of %d replayed distances match live ones' % (overlap, len(replay)))


if __name__ == '__main__':
    rostest.rosrun('closed_loop', 'record_replay', RecordReplay)
