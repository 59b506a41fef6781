#!/usr/bin/env python3
"""Autonomous exploration of the home, end to end: launch/explore.launch (simulator, slam_gmapping,
move_base, explore) at 4x real time, RUNS times; each run's report (bench/out/explore_N/) gives the
figures, printed as the median over runs with every run listed. Targets (issue 8): complete within
600 s simulated, >= 97% of the reachable free space, every wall within 0.1 m, no collision.
Run inside the devel environment (make bench does that); about 3 min wall per run here.
"""
import json
import os
import shutil
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
RUNS = int(os.environ.get('BENCH_EXPLORE_RUNS', '3'))
PORT = 11398


def emit(metric, values, unit, target='', fmt='%.3g'):
    note = 'runs: ' + ', '.join(fmt % v for v in values)
    print(json.dumps({'benchmark': 'explore', 'metric': metric, 'value': statistics.median(values), 'unit': unit,
                      'target': target, 'note': note}), flush=True)


def one_run(k):
    out = os.path.join(HERE, 'out', 'explore_%d' % k)
    shutil.rmtree(out, ignore_errors=True)
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % PORT)
    start = time.time()
    log = open(os.path.join(HERE, 'out', 'explore_%d.log' % k), 'w')
    proc = subprocess.Popen(['roslaunch', '-p', str(PORT), 'mbot_slam_navigation', 'explore.launch',
                             'real_time_factor:=4.0', 'report_dir:=' + out, 'shutdown_when_done:=true'],
                            env=env, stdout=log, stderr=subprocess.STDOUT)
    try:
        proc.wait(timeout=1200)
    except subprocess.TimeoutExpired:
        proc.terminate()
        proc.wait()
    log.close()
    path = os.path.join(out, 'report.json')
    if not os.path.isfile(path):
        print('run %d: no report after %.0f s (log: %s)' % (k, time.time() - start, log.name), flush=True)
        return None
    with open(path) as f:
        r = json.load(f)
    print('run %d: complete after %.0f s simulated, %.0f s wall; coverage %.1f%%, walls %.1f%% within 0.1 m, '
          '%d goals (%d failed), %d collisions' % (k, r['exploration_time_s'], r['wall_time_s'],
                                                    100 * r['coverage_of_reachable_free'],
                                                    100 * r['walls_within_tolerance'], r['goals_sent'],
                                                    r['goals_failed'], r['collisions']), flush=True)
    return r


def main():
    os.makedirs(os.path.join(HERE, 'out'), exist_ok=True)
    reports = [r for r in (one_run(k) for k in range(1, RUNS + 1)) if r]
    if not reports:
        sys.exit(1)
    emit('time to completion (simulated)', [r['exploration_time_s'] for r in reports], 's', '<= 600', '%.0f')
    emit('wall time to completion at 4x', [r['wall_time_s'] for r in reports], 's', '', '%.0f')
    emit('reachable free space explored', [100 * r['coverage_of_reachable_free'] for r in reports], '%', '>= 97',
         '%.1f')
    emit('wall cells within 0.1 m of a true wall', [100 * r['walls_within_tolerance'] for r in reports], '%', '100',
         '%.2f')
    emit('largest wall-cell distance', [r['wall_distance_max_m'] for r in reports], 'm', '<= 0.1', '%.3f')
    emit('distance driven', [r['distance_m'] for r in reports], 'm', '', '%.1f')
    emit('goals sent', [r['goals_sent'] for r in reports], '', '', '%d')
    emit('goals failed', [r['goals_failed'] for r in reports], '', '', '%d')
    emit('collisions', [r['collisions'] for r in reports], '', '0', '%d')
    if len(reports) < RUNS:
        print('%d of %d runs gave no report' % (RUNS - len(reports), RUNS))
        sys.exit(1)


if __name__ == '__main__':
    main()
