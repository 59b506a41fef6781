"""A rospy subscription that connects afresh when the master lists a publisher it never connected to.

rospy can lose a publisher that registers while the subscriber registers. Its RegManager queues
the master's publisherUpdate (which lists the new publisher) and registerSubscriber's answer
(which does not yet) in the order they arrive, takes the newest entry as the truth and drops the
others for the topic; when the stale answer comes last, the new publisher is never connected and
nothing asks again. Seen in the two-robot rostest: explore_team, started by the same roslaunch as
the explorers, never connected to /robot2/explore/complete, a latched topic published once, and
waited out its 1440 s timeout though robot2 had ended at 164 s.

`WatchedSubscriber.check()`, called now and then (every few seconds of wall time), asks the master
how many publishers the topic has; if the subscription has fewer connections at two checks in a
row (a connection being made is given one period), it unregisters and subscribes again: a fresh
registerSubscriber answer lists every publisher, and a latched message comes again.
"""
from typing import Callable, Optional

import rosgraph
import rospy

from mbot_slam_navigation.master_rpc import master_proxy

MASTER_TIMEOUT = 3.0  # [s, wall] for the master's answer


def master_publisher_count(topic: str) -> int:
    """Publishers of `topic` (resolved) that the master lists, or -1 when the master does not answer
    within MASTER_TIMEOUT."""
    try:
        code, _, (publishers, _, _) = master_proxy(rosgraph.get_master_uri(), MASTER_TIMEOUT).getSystemState(
            rospy.get_name())
    except Exception:  # the master gone, busy or not a master: nothing to conclude this time
        return -1
    if code != 1:
        return -1
    return next((len(nodes) for name, nodes in publishers if name == topic), 0)


class WatchedSubscriber:
    def __init__(self, topic: str, data_class, callback, callback_args=None,
                 publishers_of: Callable[[str], int] = master_publisher_count,
                 subscribe: Optional[Callable] = None, **kwargs):
        self._make = subscribe or (lambda: rospy.Subscriber(topic, data_class, callback, callback_args=callback_args,
                                                            **kwargs))
        self._publishers_of = publishers_of
        self.sub = self._make()
        self.topic = self.sub.resolved_name
        self.strikes = 0
        self.resubscribed = 0

    def check(self) -> bool:
        """Subscribes again if the topic has had more publishers than connections at two checks in
        a row; True when it did."""
        publishers = self._publishers_of(self.topic)
        if publishers < 0 or self.sub.get_num_connections() >= publishers:
            self.strikes = 0
            return False
        self.strikes += 1
        if self.strikes < 2:
            return False
        (rospy.logwarn if self.resubscribed == 0 else rospy.logdebug)(
            '%s: %s has %d publisher(s) but %d connection(s) (rospy lost one that registered as we did); '
            'subscribing again', rospy.get_name(), self.topic, publishers, self.sub.get_num_connections())
        self.sub.unregister()
        self.sub = self._make()
        self.strikes = 0
        self.resubscribed += 1
        return True

    def unregister(self) -> None:
        self.sub.unregister()
