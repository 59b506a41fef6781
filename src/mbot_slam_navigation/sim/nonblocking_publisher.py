"""A rospy publisher whose publish() never waits for a subscriber, and never yields the thread.

rospy offers two kinds of publisher and neither fits a simulator that publishes /clock, odometry,
tf and scans hundreds of times per wall second:
- queue_size=N: each message goes through a per-subscriber queue and writer thread; the
  time.sleep(0) after every message costs about 80 us here, most of the simulator's time;
- queue_size=None: the message is written with socket.sendall() in the calling thread, which
  blocks for as long as one subscriber does not read (stopped, swapped out, or just slow). One
  SIGSTOPped subscriber froze the whole simulation that way.

This one writes in the calling thread but with MSG_DONTWAIT: what the kernel's socket buffer takes
is sent; the rest of a message that did not fit waits in a one-message backlog per subscriber,
written first on the next publish (so the TCPROS stream never carries a torn message); while a
backlog remains, new messages to that subscriber are dropped, as a full roscpp queue drops them.
A subscriber that died is removed as rospy removes it. Publishing to the others goes on at full
rate meanwhile.

It relies on rospy's _PublisherImpl calling `add_connection(c)` with a transport that has a
`socket`, `write_data`, `close` and `endpoint_id` (rospy 1.15/1.16, Debian bookworm's); the
rostest sim_never_blocks exercises it with a stopped subscriber.
"""
import errno
import socket
import warnings

import rospy
from rospy.exceptions import TransportTerminated


class NonBlockingConnection:
    """Wraps one TCPROS publisher-side transport (rospy.impl.tcpros_base.TCPROSTransport)."""

    def __init__(self, transport):
        self._transport = transport
        self._backlog = b''
        self.dropped = 0  # messages not sent to this subscriber because it did not read

    def __getattr__(self, name):
        # Everything but write_data is the transport's (endpoint_id, close, done, stats, ...).
        return getattr(self._transport, name)

    def _send(self, data) -> int:
        """Bytes the kernel took without waiting; raises TransportTerminated if the peer is gone."""
        t = self._transport
        if t.done or t.socket is None:
            raise TransportTerminated('connection closed')
        try:
            return t.socket.send(data, socket.MSG_DONTWAIT)
        except (BlockingIOError, InterruptedError):
            return 0
        except OSError as e:
            if e.errno in (errno.EAGAIN, errno.EWOULDBLOCK, errno.EINTR):
                return 0
            t.close()
            raise TransportTerminated('%s: %s' % (t.endpoint_id, e)) from None

    def write_data(self, data) -> None:
        if self._backlog:
            n = self._send(self._backlog)
            self._backlog = self._backlog[n:]
            if self._backlog:
                self.dropped += 1
                return
        n = self._send(data)
        if n < len(data):
            self._backlog = bytes(data[n:])
        t = self._transport
        t.stat_bytes += n
        t.stat_num_msg += 1


def nonblocking_publisher(topic: str, msg_type, latch: bool = False) -> rospy.Publisher:
    """rospy.Publisher on `topic` whose connections are NonBlockingConnections (see the module)."""
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')  # rospy warns when queue_size is None: it is wrapped below
        pub = rospy.Publisher(topic, msg_type, queue_size=None, latch=latch)
    impl = pub.impl
    if not getattr(impl, '_mbot_nonblocking', False):
        add = impl.add_connection
        impl.add_connection = lambda c: add(NonBlockingConnection(c))
        impl._mbot_nonblocking = True
    return pub

