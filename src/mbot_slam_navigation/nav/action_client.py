"""actionlib's SimpleActionClient without the race in its send_goal (ros/actionlib#206, never fixed:
ROS 1's actionlib is archived). send_goal registers the goal before it stores the handle, so a
status that arrives in between is dropped with "Got a transition callback on a goal handle that
we're not tracking"; when the dropped transition is the last one (a goal the server aborts at
once), wait_for_result waits out its whole timeout. Here callbacks wait until send_goal is done."""
import threading

import actionlib


class SimpleActionClient(actionlib.SimpleActionClient):
    def __init__(self, ns, action_spec):
        super().__init__(ns, action_spec)
        self._sending = threading.RLock()

    def send_goal(self, goal, done_cb=None, active_cb=None, feedback_cb=None):
        with self._sending:
            super().send_goal(goal, done_cb, active_cb, feedback_cb)

    def _handle_transition(self, gh):
        with self._sending:
            super()._handle_transition(gh)

    def _handle_feedback(self, gh, feedback):
        with self._sending:
            super()._handle_feedback(gh, feedback)
