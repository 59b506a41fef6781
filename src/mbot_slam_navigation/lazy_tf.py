"""LazyTransformBuffer: a tf2_ros.Buffer that reads /tf only when a lookup needs it.

A rospy node that wants the robot's pose a few times a second (explore, random_navigation) pays,
with tf2_ros.TransformListener, for deserializing every /tf message and inserting it into its
buffer, in Python, on arrival: in the simulated home that is 87 messages a simulated second
(the simulator 50, the URDF's odometry rate; SLAM 27; robot_state_publisher 10), and it was the
explorer's largest cost after the /clock thread (1.7 of 5.6 CPU s of a home exploration). Even raw, the subscription adds half as much again to what an idle
rospy node pays for /clock (0.0039 on 0.0074 CPU s per simulated s; bench/rospy_floor.py).

This buffer subscribes to /tf as rospy.AnyMsg, so a message arrives as its raw bytes and is only
queued. Messages are queued per stream (the publishing node and the child frame of the message's
first transform), keeping the `keep` newest of each stream; a lookup (can_transform_core /
lookup_transform_core and their _full variants, which Buffer's lookup_transform, can_transform and
transform go through) first deserializes what is queued into the tf2 buffer. What is dropped is
only the older part of a burst between two lookups, so lookups of the latest transform
(rospy.Time(0)) answer as a TransformListener's buffer would; a lookup at a past time interpolates
between the samples kept, which are `keep` per stream per lookup interval. /tf_static is read as a
TransformListener reads it. Like TransformListener, the buffer is cleared when ROS time jumps back
(a simulation reset, a bag played again). With a `read_period`, /tf is read in batches at most
that often (batched_reads): a lookup then sees what arrived up to that much wall time before.
"""
import collections
import struct
import threading
from typing import Deque, Dict, Tuple

import rospy
import tf2_ros
from tf2_msgs.msg import TFMessage

from mbot_slam_navigation.batched_reads import read_at_most_every

_U32 = struct.Struct('<I')


def first_child_frame(raw: bytes) -> bytes:
    """The child_frame_id of the first transform of a serialized tf2_msgs/TFMessage (b'' if it has
    none; b'?' if the bytes are too short to be one). Reads 3 lengths, deserializes nothing."""
    try:
        if _U32.unpack_from(raw, 0)[0] == 0:
            return b''
        # transforms[0].header: seq (4 bytes), stamp (8), frame_id (length + bytes); then child_frame_id
        frame_len = _U32.unpack_from(raw, 16)[0]
        at = 20 + frame_len
        child_len = _U32.unpack_from(raw, at)[0]
        return bytes(raw[at + 4:at + 4 + child_len])
    except struct.error:
        return b'?'


class LazyTransformBuffer(tf2_ros.Buffer):
    """A tf2_ros.Buffer and its listener in one; see the module's doc. `keep` [messages] per stream
    between two lookups; `subscribe` False leaves /tf and /tf_static to the caller (tests feed
    on_tf); `read_period` [wall s]: /tf is read at most this often (0: as it comes)."""

    def __init__(self, cache_time: rospy.Duration = None, keep: int = 3, subscribe: bool = True,
                 read_period: float = 0.0):
        super().__init__(cache_time, debug=subscribe)  # debug: the ~tf2_frames service, as Buffer() has
        self.keep = max(1, int(keep))
        self._lock = threading.Lock()
        self._pending: Dict[Tuple[str, bytes], Deque[bytes]] = {}
        self._last_update = rospy.Time.now() if subscribe else rospy.Time(0)
        self.received = 0  # /tf messages arrived
        self.inserted = 0  # of them deserialized into the buffer
        self._subs = []
        if subscribe:
            self._subs = [rospy.Subscriber('/tf', rospy.AnyMsg, self.on_tf, queue_size=None),
                          rospy.Subscriber('/tf_static', TFMessage, self.on_tf_static, queue_size=None)]
            if read_period > 0.0:
                read_at_most_every(self._subs[0], read_period)

    def unregister(self) -> None:
        for s in self._subs:
            s.unregister()
        self._subs = []

    def on_tf(self, msg: rospy.AnyMsg) -> None:
        """Queues one raw /tf message; nothing else runs per message."""
        who = msg._connection_header.get('callerid', 'default_authority')
        key = (who, first_child_frame(msg._buff))
        with self._lock:
            q = self._pending.get(key)
            if q is None:
                q = self._pending[key] = collections.deque(maxlen=self.keep)
            q.append(msg._buff)
            self.received += 1

    def on_tf_static(self, msg: TFMessage) -> None:
        self._ingest()
        who = msg._connection_header.get('callerid', 'default_authority')
        for t in msg.transforms:
            self.set_transform_static(t, who)

    def _ingest(self) -> None:
        """Deserializes what is queued into the buffer, clearing it first if ROS time jumped back."""
        with self._lock:
            pending, self._pending = self._pending, {}
            now = rospy.Time.now()
            if now < self._last_update:
                rospy.logwarn('Detected jump back in time of %fs. Clearing TF buffer.'
                              % (self._last_update - now).to_sec())
                self.clear()
            self._last_update = now
            for (who, _), q in pending.items():
                for raw in q:
                    m = TFMessage()
                    try:
                        m.deserialize(raw)
                    except Exception as e:  # genpy raises DeserializationError or struct.error
                        rospy.logwarn_throttle(10.0, 'a /tf message from %s could not be read (%s); skipped'
                                               % (who, e))
                        continue
                    for t in m.transforms:
                        self.set_transform(t, who)
                    self.inserted += 1

    def can_transform_core(self, *args):
        self._ingest()
        return super().can_transform_core(*args)

    def can_transform_full_core(self, *args):
        self._ingest()
        return super().can_transform_full_core(*args)

    def lookup_transform_core(self, *args):
        self._ingest()
        return super().lookup_transform_core(*args)

    def lookup_transform_full_core(self, *args):
        self._ingest()
        return super().lookup_transform_full_core(*args)
