"""topic_watch.WatchedSubscriber: a subscription with fewer connections than the master lists
publishers, at two checks in a row, is made again; otherwise it is left alone."""

import pytest

pytest.importorskip('rospy')
from mbot_slam_navigation.topic_watch import WatchedSubscriber  # noqa: E402


class FakeSub:
    """What rospy.Subscriber offers that WatchedSubscriber uses."""
    made = []

    def __init__(self, connections):
        self.resolved_name = '/robot2/explore/complete'
        self.connections = connections
        self.unregistered = False
        FakeSub.made.append(self)

    def get_num_connections(self):
        return self.connections

    def unregister(self):
        self.unregistered = True


def watched(publishers, connections_of_each):
    FakeSub.made = []
    conns = iter(connections_of_each)
    counts = iter(publishers)
    return WatchedSubscriber('/robot2/explore/complete', None, None, publishers_of=lambda topic: next(counts),
                             subscribe=lambda: FakeSub(next(conns)))


def test_a_lost_publisher_is_connected_by_subscribing_again():
    # the master lists robot2's explorer; rospy never connected (0); the fresh subscription does (1)
    w = watched([1, 1, 1, 1], [0, 1])
    assert not w.check()  # one period for a connection being made
    assert w.check()
    assert FakeSub.made[0].unregistered and not FakeSub.made[1].unregistered
    assert w.sub is FakeSub.made[1] and w.resubscribed == 1
    assert not w.check() and not w.check()  # connected now: left alone
    assert len(FakeSub.made) == 2


def test_a_connected_subscription_or_a_topic_without_publishers_is_left_alone():
    w = watched([1, 1, 1, 0, 0, 0], [1])
    assert not any(w.check() for _ in range(6))
    assert len(FakeSub.made) == 1 and not FakeSub.made[0].unregistered


def test_a_master_that_does_not_answer_proves_nothing():
    w = watched([-1, 1, -1, 1, -1], [0])
    assert not any(w.check() for _ in range(5))  # never two checks in a row with a publisher unconnected
    assert len(FakeSub.made) == 1


PUBLISHER = '''
import rospy
from std_msgs.msg import Bool
rospy.init_node('ender', disable_signals=True)
pub = rospy.Publisher('/ender/complete', Bool, queue_size=1, latch=True)
pub.publish(Bool(True))
rospy.sleep(60.0)
'''

SUBSCRIBER = '''
import time
import rospy
from std_msgs.msg import Bool
from mbot_slam_navigation.topic_watch import WatchedSubscriber
rospy.init_node('waiter', disable_signals=True)
got = []
w = WatchedSubscriber('/ender/complete', Bool, lambda m: got.append(m.data))
def wait(n):
    t = time.monotonic()
    while len(got) < n and time.monotonic() - t < 20.0:
        time.sleep(0.05)
wait(1)
print('first', len(got), w.check(), flush=True)
# The state rospy's race leaves: the master lists the publisher, the subscription has no connection.
for c in list(w.sub.impl.connections):
    w.sub.impl.remove_connection(c)
    c.close()
print('lost', w.sub.get_num_connections(), flush=True)
checks = [w.check(), w.check()]
wait(2)
print('again', checks, len(got), got, w.sub.get_num_connections(), flush=True)
'''


def test_with_a_real_master_a_lost_latched_connection_comes_back(ros_master):
    import subprocess
    import sys
    import time
    env = ros_master
    procs = []
    try:
        procs.append(subprocess.Popen([sys.executable, '-c', PUBLISHER], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL))
        time.sleep(1.0)
        out = subprocess.run([sys.executable, '-c', SUBSCRIBER], env=env, capture_output=True, text=True,
                             timeout=90).stdout
        lines = dict(line.split(' ', 1) for line in out.splitlines() if ' ' in line)
        assert lines.get('first') == '1 False', out  # connected: nothing to do
        assert lines.get('lost') == '0', out
        assert lines.get('again') == '[False, True] 2 [True, True] 1', out  # subscribed again, latched True again
    finally:
        for p in procs:
            p.terminate()
            p.wait()


def test_a_master_that_does_not_answer_is_given_up_on_within_the_timeout(monkeypatch):
    # A listening socket that never answers: the count comes back -1 within MASTER_TIMEOUT, not never.
    import socket
    import threading
    from mbot_slam_navigation import topic_watch
    with socket.socket() as s:
        s.bind(('localhost', 0))
        s.listen(1)
        monkeypatch.setattr(topic_watch.rosgraph, 'get_master_uri', lambda: 'http://localhost:%d' % s.getsockname()[1])
        monkeypatch.setattr(topic_watch, 'MASTER_TIMEOUT', 0.5)
        result = []
        asker = threading.Thread(target=lambda: result.append(topic_watch.master_publisher_count('/x')), daemon=True)
        asker.start()
        asker.join(5.0)  # a broken timeout fails the test here instead of hanging it
        assert result == [-1]
