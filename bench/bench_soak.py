#!/usr/bin/env python3
"""The soak (issue 19): the exploration tutorial left running with people walking through the home.

As a user runs it: `roslaunch robot_gazebo_navigation.launch` (simulator with
worlds/mbot_home_people.world, slam_gmapping) and `roslaunch robot_gazebo_navigation_move.launch`
(move_base), then `rosrun random_navigation.py` with a goal limit. Both launches respawn their nodes
(respawn_slam, respawn_move_base), so a death shows as a restart and the run goes on; the report
counts both. Prints progress every minute of wall time and at the end:
- success per point (random_navigation's own summary);
- collisions: with walls and furniture, into people (the robot's fault), and people walking into
  the robot (counted apart: not the robot's fault);
- each node's resident memory over simulated time (bench/out/soak/memory.png) and its growth after
  the first 10 simulated minutes; restarts and deaths; whether every node still answers at the end
  (an XML-RPC getPid, as `rosnode ping` does).
Writes bench/out/soak/report.json and the launches' logs beside it.

Environment: BENCH_SOAK_GOALS (100), BENCH_SOAK_RTF (auto), BENCH_SOAK_SEED (1),
BENCH_SOAK_WALL_LIMIT (7200 s). Targets: success >= 98%, 0 collisions with walls or furniture, 0
collisions the robot drives into, memory growth of every node < 10% after the first 10 minutes, 0
node deaths. Run inside the devel environment (make bench does that).
"""
import json
import math
import os
import re
import signal
import socket
import subprocess
import sys
import time
import xmlrpc.client
from collections import defaultdict

HERE = os.path.dirname(os.path.abspath(__file__))
PKG = os.path.abspath(os.path.join(HERE, '..'))
PORT = 11396
os.environ['ROS_MASTER_URI'] = 'http://localhost:%d' % PORT

import rosgraph  # noqa: E402  (after ROS_MASTER_URI is set for this process)
import rospy  # noqa: E402
from geometry_msgs.msg import TransformStamped  # noqa: E402

from mbot_slam_navigation.exploration_run import node_cpu_seconds, node_pids, stop  # noqa: E402
from mbot_slam_navigation.explore_report import draw_curves  # noqa: E402
from mbot_slam_navigation.msg import Contact  # noqa: E402

GOALS = int(os.environ.get('BENCH_SOAK_GOALS', '100'))
RTF = os.environ.get('BENCH_SOAK_RTF', 'auto')
SEED = int(os.environ.get('BENCH_SOAK_SEED', '1'))
WALL_LIMIT = float(os.environ.get('BENCH_SOAK_WALL_LIMIT', '7200'))
WARM_UP = 600.0  # [s simulated] memory growth is measured after this


def rss_mb(pid):
    try:
        with open('/proc/%d/status' % pid) as f:
            for line in f:
                if line.startswith('VmRSS:'):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        return None
    return None


def ping(node_name, master):
    """True if the node answers getPid over XML-RPC within 5 s (rosnode ping)."""
    try:
        proxy = xmlrpc.client.ServerProxy(master.lookupNode(node_name))
        socket.setdefaulttimeout(5.0)  # this process's only XML-RPC calls from here on are pings
        code, _, _ = proxy.getPid('/bench_soak')
        return code == 1
    except Exception:  # noqa: BLE001  (any failure is "does not answer")
        return False


def parse_summary(text):
    """random_navigation's summary: (goals, succeeded, {point: (reached, sent, failed states)})."""
    m = re.search(r'Random navigation summary: (\d+) goals, (\d+) succeeded', text)
    if not m:
        return None
    points = {}
    for p in re.finditer(r'^\s+(p\d+)\s+(?:\([^)]*\))?\s*(\d+)/(\d+)(?:\s+failed: (.*))?$', text, re.M):
        points[p.group(1)] = (int(p.group(2)), int(p.group(3)), (p.group(4) or '').strip())
    return int(m.group(1)), int(m.group(2)), points


def memory_picture(samples, path):
    draw_curves({name: [(t / 60.0, m) for t, m in pts] for name, pts in sorted(samples.items())},
                'resident memory [MB] against simulated time [min]', path, size=(900, 450), marker_x=WARM_UP / 60.0)


def _terminated(signum, _frame):
    raise SystemExit('bench_soak: stopped by signal %d' % signum)


def main():
    # SIGTERM (kill, a CI timeout) ends Python without its finally blocks: the launches and their
    # nodes would be left running and join the next soak's master on the same port.
    signal.signal(signal.SIGTERM, _terminated)
    out = os.path.join(HERE, 'out', 'soak')
    os.makedirs(out, exist_ok=True)
    env = dict(os.environ)
    logs = {k: open(os.path.join(out, k + '.log'), 'w') for k in ('sim_slam', 'move_base', 'random_navigation')}
    world = os.path.join(PKG, 'worlds', 'mbot_home_people.world')
    launches = [subprocess.Popen(['roslaunch', '-p', str(PORT), 'mbot_slam_navigation', 'robot_gazebo_navigation.launch',
                                  'gui:=false', 'rviz:=false', 'real_time_factor:=' + RTF, 'world_name:=' + world,
                                  'respawn_slam:=true'], env=env, stdout=logs['sim_slam'], stderr=subprocess.STDOUT)]
    nav = None
    try:
        t0 = time.monotonic()
        while not rosgraph.Master('/bench_soak').is_online():
            if time.monotonic() - t0 > 60.0:
                raise SystemExit('bench_soak: no ROS master on port %d after 60 s; see %s' % (PORT, out))
            time.sleep(0.5)
        launches.append(subprocess.Popen(['roslaunch', 'mbot_slam_navigation', 'robot_gazebo_navigation_move.launch',
                                          'respawn_move_base:=true'], env=env, stdout=logs['move_base'],
                                         stderr=subprocess.STDOUT))
        rospy.init_node('bench_soak', disable_signals=True)
        contacts = []
        rospy.Subscriber('/gazebo/contacts', Contact, contacts.append)
        # How far SLAM moved the robot's pose at once (loop closures): a jump larger than the
        # costmaps' clearing reach leaves old marks on the robot.
        corrections = []
        rospy.Subscriber('/slam_gmapping/correction', TransformStamped,
                         lambda m: corrections.append((m.header.stamp.to_sec(), math.hypot(
                             m.transform.translation.x, m.transform.translation.y))))
        nav = subprocess.Popen(['rosrun', 'mbot_slam_navigation', 'random_navigation.py', '_max_goals:=%d' % GOALS,
                                '_seed:=%d' % SEED], env=env, stdout=logs['random_navigation'], stderr=subprocess.STDOUT)
        samples = defaultdict(list)   # node -> [(sim s, MB)]
        pids = {}                     # node -> last pid seen
        restarts = defaultdict(int)
        gone = set()
        wall0, last_progress = time.monotonic(), 0.0
        print('soak: %d goals of random_navigation.py in %s, real_time_factor %s; logs in %s'
              % (GOALS, os.path.basename(world), RTF, out), flush=True)
        while nav.poll() is None and time.monotonic() - wall0 < WALL_LIMIT:
            time.sleep(5.0)
            sim = rospy.get_time()
            now = {}
            for launch in launches:
                now.update(node_pids(launch.pid))
            for name, pid in now.items():
                if name in pids and pids[name] != pid:
                    restarts[name] += 1
                    print('soak: %s restarted (pid %d -> %d) at %.0f s simulated' % (name, pids[name], pid, sim),
                          flush=True)
                pids[name] = pid
                gone.discard(name)
                mb = rss_mb(pid)
                if mb is not None:
                    samples[name].append((sim, mb))
            for name in set(pids) - set(now) - gone:
                gone.add(name)
                print('soak: %s is not running at %.0f s simulated' % (name, sim), flush=True)
            if time.monotonic() - last_progress >= 60.0:
                last_progress = time.monotonic()
                with open(logs['random_navigation'].name) as f:
                    text = f.read()
                done = re.findall(r'Success so far: (\d+)/(\d+)', text)
                s, g = done[-1] if done else (0, 0)
                print('soak: %s/%d goals, %s succeeded; %.0f s simulated in %.0f s wall (%.1fx); %d contacts'
                      % (g, GOALS, s, sim, time.monotonic() - wall0, sim / max(time.monotonic() - wall0, 1e-9),
                         len(contacts)), flush=True)
        finished = nav.poll() is not None
        sim_end, wall_end = rospy.get_time(), time.monotonic() - wall0
        master = rosgraph.Master('/bench_soak')
        answered = {name: ping('/' + name, master) for name in sorted(pids)}
        cpu = {}
        for launch in launches:
            cpu.update(node_cpu_seconds(launch.pid))
    finally:
        if nav is not None:
            stop(nav, 10.0)
        for launch in reversed(launches):
            stop(launch)
        for f in logs.values():
            f.close()

    with open(logs['random_navigation'].name) as f:
        summary = parse_summary(f.read())
    growth = {}
    for name, pts in samples.items():
        base = next((m for t, m in pts if t >= WARM_UP), None)
        if base:
            growth[name] = {'at_10_min_mb': round(base, 1), 'end_mb': round(pts[-1][1], 1),
                            'max_mb': round(max(m for _, m in pts), 1),
                            'growth': round((pts[-1][1] - base) / base, 3)}
    kinds = defaultdict(int)
    for c in contacts:
        kinds['world' if c.other_kind in ('', 'world') else
              c.other_kind + (' (robot at fault)' if c.robot_at_fault else ' (walked into the robot)')] += 1
    report = {
        'finished': finished, 'goals_asked': GOALS, 'simulated_s': round(sim_end, 1), 'wall_s': round(wall_end, 1),
        'summary': None if summary is None else {'goals': summary[0], 'succeeded': summary[1],
                                                 'points': {k: list(v) for k, v in summary[2].items()}},
        'contacts': dict(kinds), 'memory': growth, 'restarts': dict(restarts), 'not_running_at_end': sorted(gone),
        'answered_at_end': answered,
        'slam_corrections': {'count': len(corrections), 'above_0.3_m': sum(1 for _, d in corrections if d > 0.3),
                             'largest_m': round(max((d for _, d in corrections), default=0.0), 3),
                             'largest_at_s': round(max(corrections, key=lambda c: c[1])[0], 1) if corrections else None},
        'cpu_s_per_simulated_s': {k: round(v / max(sim_end, 1e-9), 4) for k, v in cpu.items()},
    }
    tmp = os.path.join(out, 'report.json.tmp')
    with open(tmp, 'w') as f:
        json.dump(report, f, indent=1)
    os.replace(tmp, os.path.join(out, 'report.json'))
    if samples:
        memory_picture(samples, os.path.join(out, 'memory.png'))

    print('\nsoak: %s after %.0f s simulated, %.0f s wall (%.1fx)' % (
        'finished' if finished else 'STOPPED at the wall-clock limit', sim_end, wall_end, sim_end / max(wall_end, 1e-9)))
    if summary:
        print('  goals %d, succeeded %d (%.1f%%; target >= 98%%)' % (summary[0], summary[1],
                                                                  100.0 * summary[1] / max(summary[0], 1)))
        for k, (reached, sent, failed) in sorted(summary[2].items()):
            print('    %s %d/%d%s' % (k, reached, sent, '  failed: ' + failed if failed else ''))
    else:
        print('  random_navigation printed no summary (see %s)' % logs['random_navigation'].name)
    print('  contacts: %s (targets: 0 world, 0 person (robot at fault))' % (dict(kinds) or 'none'))
    sc = report['slam_corrections']
    print('  slam_gmapping corrections of the map frame above 0.1 m: %d, %d above 0.3 m, largest %.2f m (at %s s)'
          % (sc['count'], sc['above_0.3_m'], sc['largest_m'], sc['largest_at_s']))
    for name, g in sorted(growth.items()):
        print('  memory %-24s %6.1f MB at 10 min -> %6.1f MB at the end (%+.1f%%; max %.1f)'
              % (name, g['at_10_min_mb'], g['end_mb'], 100 * g['growth'], g['max_mb']))
    print('  restarts: %s; not running at the end: %s; answering at the end: %d/%d'
          % (dict(restarts) or 'none', sorted(gone) or 'none', sum(answered.values()), len(answered)))
    print('  CPU s per simulated s: %s' % ', '.join('%s %.3f' % kv for kv in sorted(report['cpu_s_per_simulated_s'].items())))
    print('  report %s, memory picture %s' % (os.path.join(out, 'report.json'), os.path.join(out, 'memory.png')))
    emit = lambda metric, value, unit, target='', note='': print(json.dumps(  # noqa: E731  (run_all.py's rows)
        {'benchmark': 'soak', 'metric': metric, 'value': value, 'unit': unit, 'target': target, 'note': note}), flush=True)
    if summary:
        emit('goals reached, home with people', 100.0 * summary[1] / max(summary[0], 1), '%', '>= 98',
             '%d of %d goals, %.0f s simulated' % (summary[1], summary[0], sim_end))
    emit('collisions with walls or furniture', kinds.get('world', 0), '', '0')
    emit('collisions the robot drove into a person', kinds.get('person (robot at fault)', 0), '', '0',
         '%d people walked into the robot' % kinds.get('person (walked into the robot)', 0))
    if growth:
        worst = max(growth, key=lambda k: growth[k]['growth'])
        emit('memory growth after 10 min, worst node', 100.0 * growth[worst]['growth'], '%', '< 10', worst)
    emit('node restarts', sum(restarts.values()), '', '0', 'not running at the end: %s' % (sorted(gone) or 'none'))
    return 0 if finished else 1


if __name__ == '__main__':
    sys.exit(main())
