"""A pose estimate against the simulator's ground truth at the same simulated time: the truth
(/base_pose_ground_truth) and the estimates (e.g. /amcl_pose) are kept by stamp."""
import bisect
import math
import threading

import rospy
from geometry_msgs.msg import PoseWithCovarianceStamped
from nav_msgs.msg import Odometry

from mbot_slam_navigation.ros_msgs import pose_from_msg
from mbot_slam_navigation.transforms import normalize_angle


class PoseTrack:
    def __init__(self, estimate_topic='/amcl_pose'):
        self.lock = threading.Lock()
        self.truth_t, self.truth = [], []
        self.estimates = []  # (stamp [s], (x, y, yaw))
        rospy.Subscriber('/base_pose_ground_truth', Odometry, self.on_truth, queue_size=100)
        rospy.Subscriber(estimate_topic, PoseWithCovarianceStamped, self.on_estimate, queue_size=10)

    def on_truth(self, msg):
        with self.lock:
            self.truth_t.append(msg.header.stamp.to_sec())
            self.truth.append(pose_from_msg(msg.pose.pose))

    def on_estimate(self, msg):
        with self.lock:
            self.estimates.append((msg.header.stamp.to_sec(), pose_from_msg(msg.pose.pose)))

    def truth_at(self, t):
        """(stamp, (x, y, yaw)) of the ground truth nearest to time t [s]."""
        with self.lock:
            i = bisect.bisect_left(self.truth_t, t)
            candidates = [j for j in (i - 1, i) if 0 <= j < len(self.truth_t)]
            j = min(candidates, key=lambda k: abs(self.truth_t[k] - t))
            return self.truth_t[j], self.truth[j]

    def errors_since(self, t0):
        """(stamp, position error [m], yaw error [rad]) of every estimate stamped after t0 that has
        ground truth within 0.05 s."""
        with self.lock:
            estimates = [e for e in self.estimates if e[0] > t0]
        out = []
        for t, (x, y, yaw) in estimates:
            tt, (gx, gy, gyaw) = self.truth_at(t)
            if abs(tt - t) < 0.05:
                out.append((t, math.hypot(x - gx, y - gy), abs(normalize_angle(yaw - gyaw))))
        return out
