#!/usr/bin/env python3
"""Several robots exploring together (issue 20) against one: in each world, launch/explore.launch
(one robot) and launch/multi_explore.launch robots:=N, run by run_exploration until the report,
RUNS times each, interleaved (one of each in turn, so the machine's noise falls on both alike).
Prints per world and team size: completions, median exploration time and its ratio to one robot's,
coverage and walls of the (merged) map, collisions, each robot's distance; from the first team run,
what one robot's stack costs (CPU seconds per simulated second of its slam_gmapping, move_base and
explore) and the bandwidth of its topics (/robotN/robot/laser/scan, /robotN/map, /tf, /map), so a
user can size a fleet. Reports are kept in bench/out/team_<world>_<n>_<k>/.

Environment: BENCH_TEAM_WORLDS (home; or large), BENCH_TEAM_RUNS (3), BENCH_TEAM_ROBOTS (2: the team
sizes besides 1). Targets: home with 2 robots <= 0.6x one robot's time (median), the large floor with
3 robots <= 0.45x, coverage >= 97%, walls >= 99% within 0.1 m, 0 collisions. Run inside the devel environment (make bench does that).
"""
import json
import os
import shutil
import statistics
import subprocess
import sys
import threading

from mbot_slam_navigation.exploration_run import run

from bench_explore import emit as emit_for  # bench/ is on sys.path when a script in it runs

HERE = os.path.dirname(os.path.abspath(__file__))
PKG = os.path.abspath(os.path.join(HERE, '..'))
PORT = 11397
# world: (file, spawn arguments of the team beyond multi_explore.launch's defaults, which suit the home)
WORLDS = {'home': ('mbot_sim_gazebo_navigation.world', []),
          'large': ('large.world', ['x2:=1.0', 'y2:=0.8', 'x3:=-1.0', 'y3:=-0.8', 'x4:=1.0', 'y4:=-0.8'])}
BANDWIDTH = r'''
import json, sys, time
import rospy
rospy.init_node('bench_bandwidth', anonymous=True)
topics = sys.argv[2:]
count = {t: [0, 0] for t in topics}
def on(msg, t):
    count[t][0] += 1
    count[t][1] += len(msg._buff)
for t in topics:
    rospy.Subscriber(t, rospy.AnyMsg, on, callback_args=t, queue_size=100)
time.sleep(2.0)  # connections
for t in topics:
    count[t] = [0, 0]
t0, s0 = time.monotonic(), rospy.Time.now().to_sec()
time.sleep(float(sys.argv[1]))
wall, sim = time.monotonic() - t0, rospy.Time.now().to_sec() - s0
print(json.dumps({t: {'msgs_per_sim_s': n / sim, 'bytes_per_sim_s': b / sim, 'bytes_per_wall_s': b / wall}
                  for t, (n, b) in count.items()}))
'''


def bandwidth(env, topics, out, delay=25.0, seconds=30.0):
    """In a thread: after `delay` s, the bytes per second on `topics` over `seconds` (into `out`)."""
    def measure():
        threading.Event().wait(delay)
        try:
            p = subprocess.run([sys.executable, '-c', BANDWIDTH, str(seconds)] + topics, env=env, capture_output=True,
                               text=True, timeout=seconds + 60)
            out.update(json.loads(p.stdout.strip().splitlines()[-1]))
        except (subprocess.TimeoutExpired, ValueError, IndexError) as e:
            out['error'] = str(e)
    t = threading.Thread(target=measure, daemon=True)
    t.start()
    return t


def one_run(world, n, k, log_dir, measure=False):
    out = os.path.join(HERE, 'out', 'team_%s_%d_%d' % (world, n, k))
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % PORT)
    launch = ['explore.launch'] if n == 1 else ['multi_explore.launch', 'robots:=%d' % n] + WORLDS[world][1]
    traffic = {}
    thread = bandwidth(env, ['/robot1/robot/laser/scan', '/robot1/map', '/tf', '/map'], traffic) if measure else None
    with open(os.path.join(log_dir, 'team_%s_%d_%d.log' % (world, n, k)), 'w') as log:
        r = run(['-p', str(PORT), 'mbot_slam_navigation'] + launch +
                ['world_name:=' + os.path.join(PKG, 'worlds', WORLDS[world][0]), 'report_dir:=' + out,
                 'max_duration:=%d' % (1500 if world == 'home' else 4000)], wall_timeout=3600.0, env=env, stdout=log)
    if thread is not None:
        thread.join(timeout=120.0)
    if r is None:
        print('%s, %d robot(s), run %d: no report' % (world, n, k), flush=True)
        return None
    r['traffic'] = traffic
    distances = {name: v['distance_m'] for name, v in r.get('per_robot', {}).items()} or {'robot': r['distance_m']}
    print('%s, %d robot(s), run %d: %s after %.0f s simulated (%.0f s wall); coverage %.1f%%, walls %.1f%%, '
          '%d collisions; distances %s' % (world, n, k, r['outcome'], r['exploration_time_s'], r['wall_time_s'],
                                           100 * r.get('coverage_of_reachable_free', 0),
                                           100 * r.get('walls_within_tolerance', 0), r['collisions'], distances),
          flush=True)
    return r


def emit(world, n, metric, values, unit, target='', fmt='%.3g'):
    """bench_explore's line, with the team size where it has the load."""
    emit_for(world, 'team of %d' % n, metric, values, unit, target, fmt)


def main():
    worlds = os.environ.get('BENCH_TEAM_WORLDS', 'home').split(',')
    runs = int(os.environ.get('BENCH_TEAM_RUNS', '3'))
    sizes = [1] + [int(n) for n in os.environ.get('BENCH_TEAM_ROBOTS', '2').split(',')]
    log_dir = os.path.join(HERE, 'out')
    os.makedirs(log_dir, exist_ok=True)
    failed = False
    for world in worlds:
        reports = {n: [] for n in sizes}
        for k in range(1, runs + 1):
            for n in sizes:
                reports[n].append(one_run(world, n, k, log_dir, measure=(k == 1 and n > 1)))
        one = [r['exploration_time_s'] for r in reports[1] if r and r['outcome'] == 'complete']
        for n in sizes:
            done = [r for r in reports[n] if r]
            complete = [r for r in done if r['outcome'] == 'complete']
            failed |= len(complete) < runs
            emit(world, n, 'runs complete', [len(complete)], 'of %d' % runs, '= all', '%d')
            if not complete:
                continue
            times = [r['exploration_time_s'] for r in complete]
            emit(world, n, 'exploration time (simulated), median', times, 's', '', '%.0f')
            if n > 1 and one:
                emit(world, n, 'exploration time against one robot (medians)',
                     [statistics.median(times) / statistics.median(one)], 'x',
                     {('home', 2): '<= 0.6', ('large', 3): '<= 0.45'}.get((world, n), ''), '%.2f')
            emit(world, n, 'wall time', [r['wall_time_s'] for r in complete], 's', '', '%.0f')
            emit(world, n, 'reachable free space explored', [100 * r.get('coverage_of_reachable_free', 0)
                                                             for r in complete], '%', '>= 97', '%.1f')
            emit(world, n, 'walls within 0.1 m', [100 * r.get('walls_within_tolerance', 0) for r in complete], '%',
                 '>= 99', '%.1f')
            emit(world, n, 'collisions', [r['collisions'] for r in done], '', '0', '%d')
            if n > 1:
                for r in complete:
                    shares = sorted(v['distance_m'] for v in r['per_robot'].values())
                    r['_share'] = shares[0] / max(sum(shares), 1e-9)
                emit(world, n, 'shortest robot path, share of the team\'s distance', [r['_share'] for r in complete],
                     '', '', '%.2f')
                for node in ('slam_gmapping', 'move_base', 'explore'):
                    per_s = [r['node_cpu_s']['robot1/' + node] / r['total_time_s'] for r in complete
                             if 'robot1/' + node in r.get('node_cpu_s', {})]
                    if per_s:
                        emit(world, n, 'one robot\'s %s CPU per simulated second' % node, per_s, 'CPU s', '', '%.3f')
                for r in done:
                    for topic, t in sorted(r.get('traffic', {}).items()):
                        if isinstance(t, dict):
                            emit(world, n, 'bandwidth %s' % topic, [t['bytes_per_sim_s'] / 1000.0], 'kB per simulated s',
                                 '', '%.1f')
    sys.exit(1 if failed else 0)


if __name__ == '__main__':
    main()
