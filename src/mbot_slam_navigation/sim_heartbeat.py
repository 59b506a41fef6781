"""The heartbeat that lets the simulator's real_time_factor:=auto keep pace with this node.

A node that consumes simulated time calls `beat(stamp)` with the stamp of the newest input it has
fully processed; the simulator slows down while that stamp falls behind its clock and speeds up
while every node keeps up (sim/pacing.py). Published as std_msgs/Header on /sim_heartbeat (stamp,
frame_id = the node's name) only when /use_sim_time is set: on real time there is nothing to pace.
"""
import rospy
from std_msgs.msg import Header

TOPIC = '/sim_heartbeat'


class Heartbeat:
    def __init__(self, name: str = ''):
        self.name = name or rospy.get_name()
        self.pub = rospy.Publisher(TOPIC, Header, queue_size=10) if rospy.get_param('/use_sim_time', False) else None

    def beat(self, stamp: rospy.Time) -> None:
        if self.pub is not None and not stamp.is_zero():
            self.pub.publish(Header(stamp=stamp, frame_id=self.name))
