"""nav/action_client.SimpleActionClient with a real master: cancel_goal while actionlib's status
thread hands the goal a new state must not hang (the explorer stood for good after a link came
back with a burst of status messages)."""
import subprocess
import sys
import textwrap

import pytest

pytest.importorskip('rospy')

SCRIPT = textwrap.dedent('''
    import threading, time
    import rospy
    from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
    from mbot_slam_navigation.nav.action_client import SimpleActionClient

    rospy.init_node('cancel_during_status', anonymous=True)
    c = SimpleActionClient('move_base', MoveBaseAction)
    c.send_goal(MoveBaseGoal())
    gh = c.gh
    csm = gh.comm_state_machine
    holding = threading.Event()

    def status_thread():
        # as actionlib's CommStateMachine.update_status: its lock held while the transition is
        # handed to the client
        with csm.mutex:
            holding.set()
            time.sleep(0.3)
            c._handle_transition(gh)

    t = threading.Thread(target=status_thread, daemon=True)
    t.start()
    holding.wait(5.0)
    canceller = threading.Thread(target=c.cancel_goal, daemon=True)
    canceller.start()
    t.join(5.0)
    canceller.join(5.0)
    print('hung' if t.is_alive() or canceller.is_alive() else 'done', flush=True)
''')


def test_cancel_goal_during_a_status_update_does_not_hang(ros_master):
    p = subprocess.run([sys.executable, '-c', SCRIPT], env=ros_master, stdout=subprocess.PIPE,
                       stderr=subprocess.STDOUT, text=True, timeout=60)
    assert p.stdout.strip().endswith('done'), p.stdout[-2000:]
