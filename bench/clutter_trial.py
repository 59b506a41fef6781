#!/usr/bin/env python3
"""One trial of bench_clutter.py: launch/move_base_clutter.launch in one clutter world on its own
ROS master, one move_base goal from the world's start to its goal, and what happened, printed as
one JSON line.

    clutter_trial.py WORLD.yaml --map {true,false} --port PORT [--limit S] [--log FILE]

WORLD.yaml is tools/generate_clutter.py's description beside WORLD.world. The trial ends when
move_base finishes the goal or after --limit simulated seconds (the goal is then cancelled).
Printed: outcome (reached, aborted, timeout, error), simulated time from the goal to its end,
distance driven (ground truth), collisions (the simulator's contacts), recovery behaviours run,
move_base's last abort text, the simulated seconds move_base commanded forward, turning on the
spot, backing and standing still (where the time goes), and the wall time.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

import yaml

from mbot_slam_navigation.exploration_run import stop

RECOVERY_TEXT = 'running recovery behaviour'


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('world_yaml')
    ap.add_argument('--map', choices=('true', 'false'), default='false')
    ap.add_argument('--map-resolution', type=float, default=0.05, help="[m/cell] the world's map with --map true")
    ap.add_argument('--port', type=int, required=True)
    ap.add_argument('--limit', type=float, default=100.0, help='[s] simulated time allowed for the goal')
    ap.add_argument('--log', default=os.devnull, help="roslaunch's output")
    a = ap.parse_args(argv)
    with open(a.world_yaml) as f:
        info = yaml.safe_load(f)
    world = os.path.join(os.path.dirname(os.path.abspath(a.world_yaml)), info['world'])
    uri = 'http://localhost:%d' % a.port
    os.environ['ROS_MASTER_URI'] = uri
    wall0 = time.monotonic()
    with open(a.log, 'w') as log:
        launch = subprocess.Popen(['roslaunch', '-p', str(a.port), '--screen', 'mbot_slam_navigation',
                                   'move_base_clutter.launch', 'world_name:=' + world, 'map:=' + a.map,
                                   'map_resolution:=%g' % a.map_resolution],
                                  stdout=log, stderr=subprocess.STDOUT, env=dict(os.environ, ROS_MASTER_URI=uri))
    result = {'world': info['world'], 'level': info['level'], 'seed': info['seed'], 'map': a.map == 'true',
              'outcome': 'error', 'time_s': None, 'distance_m': 0.0, 'collisions': 0, 'recoveries': 0, 'why': ''}
    try:
        result.update(drive(info, a.limit))
    except Exception as e:  # noqa: BLE001 (the trial's error is its result)
        result['why'] = '%s: %s' % (type(e).__name__, e)
    finally:
        stop(launch, grace_s=15.0)
    result['wall_s'] = round(time.monotonic() - wall0, 1)
    print(json.dumps(result), flush=True)
    return 0


def drive(info, limit):
    import rosgraph
    deadline = time.monotonic() + 60.0
    while not rosgraph.Master('/clutter_trial').is_online():
        if time.monotonic() > deadline:
            raise RuntimeError('no ROS master within 60 s')
        time.sleep(0.2)
    import rospy
    from actionlib_msgs.msg import GoalStatus
    from move_base_msgs.msg import MoveBaseAction, MoveBaseGoal
    from geometry_msgs.msg import Twist
    from nav_msgs.msg import Odometry
    from rosgraph_msgs.msg import Log

    from mbot_slam_navigation.msg import Contact
    from mbot_slam_navigation.nav.action_client import SimpleActionClient

    rospy.init_node('clutter_trial', disable_signals=True)
    state = {'last': None, 'distance': 0.0, 'collisions': 0, 'recoveries': 0, 'recovery_names': [],
             'cmd': None, 'cmd_time': None, 'shares': {'forward': 0.0, 'turning': 0.0, 'backing': 0.0, 'stopped': 0.0}}

    def on_cmd(msg):
        # what move_base commanded, by simulated time: where the time goes
        now = rospy.Time.now().to_sec()
        if state['cmd'] is not None and state['cmd_time'] is not None and now > state['cmd_time']:
            vx, wz = state['cmd']
            kind = 'forward' if vx > 0.02 else 'backing' if vx < -0.02 else 'turning' if abs(wz) > 0.02 else 'stopped'
            state['shares'][kind] += min(now - state['cmd_time'], 1.0)
        state['cmd'], state['cmd_time'] = (msg.linear.x, msg.angular.z), now

    def on_truth(msg):
        p = (msg.pose.pose.position.x, msg.pose.pose.position.y)
        if state['last'] is not None:
            state['distance'] += math.hypot(p[0] - state['last'][0], p[1] - state['last'][1])
        state['last'] = p

    def on_contact(msg):
        if msg.robot_at_fault:
            state['collisions'] += 1

    def on_log(msg):
        if msg.name == '/move_base' and RECOVERY_TEXT in msg.msg:
            state['recoveries'] += 1
            state['recovery_names'].append(msg.msg.rsplit(' ', 1)[-1])

    rospy.Subscriber('/base_pose_ground_truth', Odometry, on_truth, queue_size=50)
    rospy.Subscriber('/gazebo/contacts', Contact, on_contact, queue_size=20)
    rospy.Subscriber('/rosout_agg', Log, on_log, queue_size=100)
    rospy.Subscriber('/cmd_vel', Twist, on_cmd, queue_size=50)
    client = SimpleActionClient('move_base', MoveBaseAction, feedback=False)
    if not client.wait_for_server(rospy.Duration(120.0)):
        raise RuntimeError('move_base did not start within 120 s of wall time')
    wait_until = time.monotonic() + 30.0
    while state['last'] is None and time.monotonic() < wait_until:
        time.sleep(0.05)
    goal = MoveBaseGoal()
    goal.target_pose.header.frame_id = 'map'
    goal.target_pose.header.stamp = rospy.Time.now()
    goal.target_pose.pose.position.x, goal.target_pose.pose.position.y = info['goal']['x'], info['goal']['y']
    goal.target_pose.pose.orientation.w = 1.0
    start_distance = state['distance']
    client.send_goal(goal)
    t0 = rospy.Time.now().to_sec()
    wall_limit = time.monotonic() + 20.0 * limit + 60.0  # the simulation may be slow, not stopped
    outcome = 'timeout'
    while time.monotonic() < wall_limit:
        now = rospy.Time.now().to_sec()
        done = client.get_state() in (GoalStatus.SUCCEEDED, GoalStatus.ABORTED, GoalStatus.REJECTED)
        if done:
            outcome = 'reached' if client.get_state() == GoalStatus.SUCCEEDED else 'aborted'
            break
        if now - t0 > limit:
            break
        time.sleep(0.05)
    elapsed = rospy.Time.now().to_sec() - t0
    why = client.get_goal_status_text() if outcome == 'aborted' else ''
    if outcome == 'timeout':
        client.cancel_goal()
    end = state['last']
    return {'outcome': outcome, 'time_s': round(elapsed, 2), 'distance_m': round(state['distance'] - start_distance, 2),
            'collisions': state['collisions'], 'recoveries': state['recoveries'],
            'recovery_names': state['recovery_names'], 'why': why,
            'command_s': {k: round(v, 1) for k, v in state['shares'].items()},
            'left_m': round(math.hypot(end[0] - info['goal']['x'], end[1] - info['goal']['y']), 2) if end else None}


if __name__ == '__main__':
    sys.exit(main())
