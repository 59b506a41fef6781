"""What the exploration rostests share: wait until the explorer says it has ended, then read its
report and keep a copy beside the test results (artifacts/<name>)."""
import json
import os
import shutil

import rospy
from std_msgs.msg import Bool

from rviz_screen import artifact_dir


def wait_for_report(artifact_name: str, first_timeout: float = 120.0, end_timeout: float = 1200.0,
                    node: str = '/explore') -> dict:
    """The report.json of `node` (the explorer, or explore_team), once its `complete` topic turned
    true (timeouts in wall seconds)."""
    msg = rospy.wait_for_message(node + '/complete', Bool, timeout=first_timeout)
    while not msg.data:
        msg = rospy.wait_for_message(node + '/complete', Bool, timeout=end_timeout)
    report_dir = rospy.get_param(node + '/report_dir')
    with open(os.path.join(report_dir, 'report.json')) as f:
        r = json.load(f)
    shutil.copytree(report_dir, os.path.join(artifact_dir(), artifact_name), dirs_exist_ok=True)
    rospy.loginfo('explore report: %s', r)
    r['report_dir'] = report_dir
    return r
