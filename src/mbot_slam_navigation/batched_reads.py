"""A rospy subscription that reads its connections at most every `period` seconds of wall time.

rospy gives each publisher connection a thread that blocks on its socket and wakes for every
message that arrives. What the wake-up costs does not depend on the message: in the explorer,
with the simulation at about 6x real time, the /clock thread (100 messages a
simulated second, 600 a wall second) was 34% of the node's CPU and the /tf threads (87 a simulated
second) 24%, while the explorer wants the time and the robot's pose a few times a second. Moving
them to a roscpp node in the same process did not help: its threads took more than the rospy
ones did (its per-message cost, in wake-ups and system calls, is of the same order).

read_at_most_every(subscriber, period) makes each connection thread of the subscription sleep
`period` [wall s] after it has handed what it read to the callbacks. What arrives meanwhile
waits in the socket and is read in one go; rospy then deserializes only the newest `queue_size`
messages of the batch (all of them without a queue_size) and calls the callbacks for each, as
before. So a burst costs one wake-up, a message waits at most `period` of wall time longer
than before, and nothing is lost that rospy would not drop anyway. A stream slower than
1/period [Hz of wall time] is not touched: the gain grows with the simulation's speed, where it
is needed (the explorer's 0.02 s halves the /clock wake-ups at real time, and cuts them by 12x at
6x).

rospy has no option for this. The one place that runs once per batch is
_SubscriberImpl.receive_callback, which every TCPROS connection thread calls with the batch it
read; install() wraps it, once per process, so that a subscription that has a read period (an
attribute of its rospy topic implementation) sleeps there. Subscriptions without one behave
exactly as before. A connection thread holds the method it was started with: connections made
before install() (rospy's /clock, made in init_node) are not batched until made again.
"""
import threading
import time

import rospy
from rosgraph_msgs.msg import Clock
from rospy.impl import simtime
from rospy.topics import _SubscriberImpl

_ATTR = '_mbot_read_period'  # [wall s] on a rospy _SubscriberImpl
_installed = False
_lock = threading.Lock()


def install() -> None:
    """Wraps rospy's _SubscriberImpl.receive_callback (idempotent; see the module's doc)."""
    global _installed
    with _lock:
        if _installed:
            return
        original = _SubscriberImpl.receive_callback

        def receive_callback(self, msgs, connection):
            original(self, msgs, connection)
            period = getattr(self, _ATTR, 0.0)
            if period > 0.0 and not rospy.is_shutdown():
                time.sleep(period)

        receive_callback.__doc__ = original.__doc__
        _SubscriberImpl.receive_callback = receive_callback
        _installed = True


def read_at_most_every(subscriber: rospy.Subscriber, period: float) -> None:
    """Makes every connection of `subscriber`'s topic in this process (rospy shares one per topic)
    read at most every `period` [s, wall time; 0: as rospy does]."""
    if not period >= 0.0:
        raise ValueError('read period must be >= 0 s (got %r)' % period)
    install()
    setattr(subscriber.impl, _ATTR, float(period))


def clock_at_most_every(period: float) -> bool:
    """The same for rospy's own /clock subscription (under /use_sim_time; after rospy.init_node):
    rospy.Time.now() then moves on at most every `period` of wall time, and lags /clock by up to
    that. False, changing nothing, when rospy reads no /clock.

    rospy made that subscription in init_node, and its connection thread holds the
    receive_callback of that time; so it is made again, with rospy's own callback and queue size:
    unsubscribed first (rospy shares a topic's connections while any subscription to it is left),
    then subscribed (for a few milliseconds no new time comes; it never goes back)."""
    old = simtime._clock_sub
    if old is None or old.impl is None:
        return False
    install()
    topic = old.resolved_name
    old.unregister()
    simtime._clock_sub = rospy.Subscriber(topic, Clock, simtime._set_rostime_clock_wrapper, queue_size=1)
    read_at_most_every(simtime._clock_sub, period)
    return True
