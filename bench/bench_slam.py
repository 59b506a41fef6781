#!/usr/bin/env python3
"""SLAM benchmark on the Radish logs (../shared/data/radish, see its SOURCES.md).

Runs both backends of slam_gmapping on ACES, FR079 and MIT CSAIL with the node's defaults: the
particle filter (`rbpf`, 30 particles, the "before") and the pose graph (`graph`, the default, the
"after"). Prints the relations error (Kümmerle et al.; translation [m], rotation [deg], mean and
std) and the CPU seconds of the SLAM calls per log: the process's CPU time, on one core (the graph
runs its optimizer inline here, the rbpf matches its particles on one thread, `threads` 1, as
gmapping does; the node's default is 2). Maps are written to bench/out/ as PGM and PNG; the
graph's PNG also shows its trajectory (blue) and loop closures (green), so MIT CSAIL, which has
no relations, can be judged by eye. SLAM_BACKENDS=graph (or rbpf) runs one backend only.
"""
import json
import os
import sys

import numpy as np

from mbot_slam_navigation.maps.map_io import occupancy_to_image, save_map
from mbot_slam_navigation.slam.carmen import read_log
from mbot_slam_navigation.slam.offline import estimated_poses, run
from mbot_slam_navigation.slam.relations import evaluate, read_relations

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.environ.get('RADISH_DIR', os.path.join(HERE, '..', '..', 'shared', 'data', 'radish'))
OUT = os.path.join(HERE, 'out')
# Targets: the issues' (rbpf: issue 4, graph: issue 9); the speed target is the graph's.
LOGS = [('aces', 'aces.clf.bz2', 'aces.relations', {'rbpf': 0.06, 'graph': 0.04}),
        ('fr079', 'fr079.clf.bz2', 'fr079.relations', {'rbpf': 0.06, 'graph': 0.05}),
        ('mit-csail', 'mit-csail.clf.bz2', None, None)]
MIN_SPEEDUP = 30.0


def write_png(path, data, origin=None, res=None, slam=None):
    import cv2
    img = cv2.cvtColor(occupancy_to_image(data), cv2.COLOR_GRAY2BGR)
    if slam is not None and hasattr(slam, 'closures'):
        traj = slam.trajectory()
        h = img.shape[0]

        def px(p):  # map rows start at the lowest y; image rows at the top
            return int((p[0] - origin[0]) / res), h - 1 - int((p[1] - origin[1]) / res)
        for a, b in zip(traj[:-1], traj[1:]):
            cv2.line(img, px(a[1:3]), px(b[1:3]), (200, 120, 0), 1)
        for i, j in slam.closures():
            cv2.line(img, px(traj[i, 1:3]), px(traj[j, 1:3]), (0, 170, 0), 1)
    cv2.imwrite(path, img)


def emit(**fields):
    print(json.dumps(dict(benchmark='slam', **fields)), flush=True)


def main():
    if not os.path.isdir(DATA):
        print('no Radish data at %s (set RADISH_DIR)' % DATA)
        return 1
    os.makedirs(OUT, exist_ok=True)
    backends = os.environ.get('SLAM_BACKENDS', 'rbpf,graph').split(',')
    print('parameters: slam_gmapping defaults (rbpf: 30 particles; graph: graph_slam.h)', flush=True)
    for name, log, rel, targets in LOGS:
        scans = read_log(os.path.join(DATA, log))
        duration = scans[-1].time - scans[0].time
        for backend in backends:
            slam, cpu = run(scans, {'threads': 1} if backend == 'rbpf' else {}, progress=sys.stderr.isatty(), backend=backend)
            poses = estimated_poses(slam, scans)
            data, origin, res = slam.occupancy()
            base = os.path.join(OUT, '%s-%s' % (name, backend))
            save_map(base, data, res, (origin[0], origin[1], 0.0))
            write_png(base + '.png', data, origin, res, slam)
            extra = ''
            if backend == 'rbpf':
                held, unshared = slam.map_memory()
                emit(metric='%s rbpf memory of the 30 particle maps' % name, value=held / 2 ** 20, unit='MB',
                     note='%.0f MB if no patch were shared' % (unshared / 2 ** 20))
            else:
                st = slam.stats()
                extra = ', %d loop closures (%d ambiguous and %d inconsistent rejected), %d optimizations' % (
                    st['loop_closures'], st['loop_rejected_ambiguous'], st['loop_rejected_inconsistent'],
                    st['optimizations'])
            print('%s %s: %d scans, %d map updates, %.1f CPU s for %.0f s of log%s; map in %s.png'
                  % (name, backend, len(scans), slam.updates, cpu, duration, extra, base), flush=True)
            emit(metric='%s %s CPU time' % (name, backend), value=cpu, unit='s',
                 target='>= %.0fx faster than the log' % MIN_SPEEDUP if backend == 'graph' else '',
                 note='%.0fx faster than the log' % (duration / cpu))
            if rel:
                e = evaluate(np.array([s.time for s in scans]), poses, read_relations(os.path.join(DATA, rel)))
                emit(metric='%s %s translation error' % (name, backend), value=e.trans_mean, unit='m',
                     target='<= %.2f' % targets[backend], note='std %.3f, %d relations' % (e.trans_std, e.count))
                emit(metric='%s %s rotation error' % (name, backend), value=e.rot_mean, unit='deg',
                     note='std %.3f' % e.rot_std)
    return 0


if __name__ == '__main__':
    sys.exit(main())
