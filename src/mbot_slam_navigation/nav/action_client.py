"""actionlib's SimpleActionClient without the race in its send_goal (ros/actionlib#206, never fixed:
ROS 1's actionlib is archived). send_goal registers the goal before it stores the handle, so a
status that arrives in between is dropped with "Got a transition callback on a goal handle that
we're not tracking"; when the dropped transition is the last one (a goal the server aborts at
once), wait_for_result waits out its whole timeout. Here callbacks wait until send_goal is done.

wait_for_server counts its timeout in wall-clock seconds. actionlib's counts ROS time: under a
simulator running 20x real time, 60 s was 3 s of wall time, less than connecting to a server takes
on a loaded machine (random_navigation gave up on a running move_base in a rostest that way), and
while /clock stands still it waited for ever.

cancel_goal cancels only a goal that has not finished: actionlib's cancels a finished one too, its
goal handle leaves DONE, and the server's next status of it logs "Received comm state PREEMPTING
when in simple state DONE" (red, at the end of every exploration). Locks are taken in actionlib's
order (the goal's, then this client's), so that a cancel during a status update cannot deadlock.

With feedback=False the client does not subscribe to the server's feedback: move_base publishes
it at controller_frequency (10 Hz in the tutorials) and a client that never reads it (the
explorer) spends a share of its CPU deserializing it. feedback_cb is then never called."""
import threading
import time

import actionlib
import rospy
from actionlib.action_client import CommState


class SimpleActionClient(actionlib.SimpleActionClient):
    def __init__(self, ns, action_spec, feedback: bool = True):
        super().__init__(ns, action_spec)
        self._sending = threading.RLock()
        self._feedback = feedback
        if not feedback:
            self.action_client.feedback_sub.unregister()

    def wait_for_server(self, timeout=rospy.Duration()):
        """True once the server is connected; False after `timeout` [wall-clock s] (0: no limit)
        or at shutdown."""
        end = time.monotonic() + timeout.to_sec()
        while not rospy.is_shutdown():
            if self._server_connected():
                return True
            if timeout.to_sec() > 0.0 and time.monotonic() >= end:
                return False
            time.sleep(0.01)
        return False

    def _server_connected(self) -> bool:
        """actionlib's test of a started server: a status message came, and the goal and cancel
        publishers and the result and feedback subscribers (the feedback's only if subscribed) are
        connected to its sender."""
        ac = self.action_client
        status = ac.last_status_msg
        if not status:
            return False
        server = status._connection_header['callerid']
        return (ac.pub_goal.impl.has_connection(server) and ac.pub_cancel.impl.has_connection(server)
                and any(c.callerid_pub == server for c in ac.result_sub.impl.connections)
                and (not self._feedback or any(c.callerid_pub == server for c in ac.feedback_sub.impl.connections)))

    def send_goal(self, goal, done_cb=None, active_cb=None, feedback_cb=None):
        with self._sending:
            super().send_goal(goal, done_cb, active_cb, feedback_cb)

    def cancel_goal(self):
        with self._sending:
            gh = self.gh
        # Not under self._sending: the goal handle's cancel takes actionlib's lock of the goal and
        # hands the new state to _handle_transition, which takes self._sending; actionlib's status
        # thread takes the two in that order too, and holding ours here first deadlocked them.
        if gh and gh.get_comm_state() != CommState.DONE:
            gh.cancel()

    def _handle_transition(self, gh):
        with self._sending:
            super()._handle_transition(gh)

    def _handle_feedback(self, gh, feedback):
        with self._sending:
            super()._handle_feedback(gh, feedback)
