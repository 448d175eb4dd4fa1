"""One known source per safety input: who publishes a scan or a command, and whether to trust it.

ROS 1 lets any node publish on any topic. For a safety input (the scan a controller stops on, the
command a base obeys) a second publisher is either a mistake (a forgotten node, a bag played into a live
graph) or an attack, and in both cases the input can no longer be trusted: the robot must not pick one
publisher's messages and hope. :class:`SourceCheck` keeps, per input, which publishers (by caller id)
were heard from recently and which frame the messages are in, and says what is wrong in one sentence
that names the publishers. Free of ROS: the node hands it the caller id from the message's connection
header, the ``frame_id`` and the time.
"""
import math
import numbers

#: How long a publisher counts as present after its last message (s). Long enough to span a few
#: periods of a slow sensor (a 5 Hz LIDAR), short enough that a publisher that went away is forgotten
#: soon after its connection is.
DEFAULT_PRESENCE_S = 1.0


class SourceCheck:
    """Tracks the publishers of one input and judges each message.

    ``topic`` names the input in messages. ``expected_frame``: the ``frame_id`` its messages must carry
    (None: any frame). ``presence_s``: how long a publisher counts as present after its last message.
    """

    def __init__(self, topic, expected_frame=None, presence_s=DEFAULT_PRESENCE_S):
        if not (isinstance(presence_s, numbers.Real) and math.isfinite(presence_s) and presence_s > 0):
            raise ValueError('presence_s: expected a positive number of s, got %r' % (presence_s,))
        self.topic = topic
        self.expected_frame = expected_frame
        self.presence_s = presence_s
        self._last_heard = {}  # caller id -> time (s) of its last message

    def publishers(self, now_s, connected=()):
        """The caller ids heard from within ``presence_s`` before ``now_s``, plus ``connected``, sorted."""
        for name in [n for n, t in self._last_heard.items() if now_s - t > self.presence_s or now_s < t]:
            del self._last_heard[name]
        return sorted(set(self._last_heard) | {c for c in connected if c})

    def observe(self, callerid, frame_id, now_s, connected=()):
        """Record a message from ``callerid``; return why it must not be used, or None when it may.

        ``connected``: caller ids of the publishers the subscriber is connected to now, where known (a
        publisher can be connected before its first message). A message is refused while more than one
        publisher is present, and when its ``frame_id`` is not ``expected_frame``.
        """
        self._last_heard[callerid or '(unknown publisher)'] = now_s
        present = self.publishers(now_s, connected)
        if len(present) > 1:
            return ('%d publishers on %s (%s): a safety input must have one source; stopping until only '
                    'one remains' % (len(present), self.topic, ', '.join(present)))
        if self.expected_frame is not None and frame_id != self.expected_frame:
            return ('%s from %s is in frame %r, expected %r'
                    % (self.topic, callerid or '(unknown publisher)', frame_id, self.expected_frame))
        return None

    def conflict(self, now_s, connected=()):
        """The publishers present if there are several (for a periodic report), else None."""
        present = self.publishers(now_s, connected)
        return present if len(present) > 1 else None
