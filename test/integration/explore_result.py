"""What the exploration rostests share: wait until the explorer says it has ended, then read its
report and keep a copy beside the test results (artifacts/<name>)."""
import json
import os
import shutil
import threading
import time

import rospy
from std_msgs.msg import Bool

from mbot_slam_navigation.topic_watch import WatchedSubscriber

from rviz_screen import artifact_dir


def wait_for_report(artifact_name: str, first_timeout: float = 120.0, end_timeout: float = 1200.0,
                    node: str = '/explore') -> dict:
    """The report.json of `node` (the explorer, or explore_team), once its `complete` topic turned
    true (timeouts in wall seconds)."""
    # One subscription for the whole wait. rospy.wait_for_message in a loop subscribed afresh for
    # every message: the topic is latched, so each new subscription got the latched False at once
    # and subscribed again, thousands of times a run, and the explorer's publisher threads took
    # more CPU than its exploring (0.033-0.044 CPU s per simulated s in this rostest against
    # 0.014 in bench_explore.py). Watched (topic_watch), as the explorer's
    # own inputs are: rospy can lose a publisher that registers while the subscriber does.
    heard, done = threading.Event(), threading.Event()

    def on_complete(msg: Bool) -> None:
        heard.set()
        if msg.data:
            done.set()

    topic = node + '/complete'
    sub = WatchedSubscriber(topic, Bool, on_complete)
    try:
        for event, timeout, what in ((heard, first_timeout, 'no message'), (done, end_timeout, 'not true')):
            end = time.monotonic() + timeout
            checked = time.monotonic()
            while not event.wait(0.5):
                if time.monotonic() > checked + 5.0:
                    checked = time.monotonic()
                    sub.check()
                if rospy.is_shutdown():
                    raise rospy.ROSInterruptException('shut down while waiting for %s' % topic)
                if time.monotonic() > end:
                    raise rospy.ROSException('%s: %s within %.0f s (wall)' % (topic, what, timeout))
    finally:
        sub.unregister()
    report_dir = rospy.get_param(node + '/report_dir')
    with open(os.path.join(report_dir, 'report.json')) as f:
        r = json.load(f)
    shutil.copytree(report_dir, os.path.join(artifact_dir(), artifact_name), dirs_exist_ok=True)
    rospy.loginfo('explore report: %s', r)
    r['report_dir'] = report_dir
    return r
