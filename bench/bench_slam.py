#!/usr/bin/env python3
"""SLAM benchmark on the Radish logs (../shared/data/radish, see its SOURCES.md).

Runs the offline RBPF (the same C++ core as slam_gmapping) with 30 particles on ACES, FR079 and MIT
CSAIL; prints the relations error (Kümmerle et al.; translation [m], rotation [deg], mean and std)
and the CPU seconds of the SLAM calls per log (one core). Maps are written to bench/out/ as PGM and
PNG (MIT CSAIL has no relations: look at its map). Parameters other than the ROS defaults are
listed in PARAMS and printed.
"""
import json
import os
import sys

import numpy as np

from mbot_slam_navigation.maps.map_io import occupancy_to_image, save_map
from mbot_slam_navigation.slam.carmen import read_log
from mbot_slam_navigation.slam.offline import per_scan_poses, run
from mbot_slam_navigation.slam.relations import evaluate, read_relations

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.environ.get('RADISH_DIR', os.path.join(HERE, '..', '..', 'shared', 'data', 'radish'))
OUT = os.path.join(HERE, 'out')
# slam_gmapping's defaults throughout (30 particles, maxUrange 80 m, linearUpdate 1 m, ...).
PARAMS = {}
LOGS = [('aces', 'aces.clf.bz2', 'aces.relations', 0.06), ('fr079', 'fr079.clf.bz2', 'fr079.relations', 0.06),
        ('mit-csail', 'mit-csail.clf.bz2', None, None)]


def write_png(path, data):
    import cv2
    cv2.imwrite(path, occupancy_to_image(data))


def main():
    if not os.path.isdir(DATA):
        print('no Radish data at %s (set RADISH_DIR)' % DATA)
        return 1
    os.makedirs(OUT, exist_ok=True)
    print('parameters: slam_gmapping defaults%s' % (', except %s' % PARAMS if PARAMS else ''), flush=True)
    for name, log, rel, target in LOGS:
        scans = read_log(os.path.join(DATA, log))
        slam, cpu = run(scans, dict(PARAMS), progress=sys.stderr.isatty())
        poses = per_scan_poses(slam.best_trajectory(), scans)
        data, origin, res = slam.best_map()
        save_map(os.path.join(OUT, name), data, res, (origin[0], origin[1], 0.0))
        write_png(os.path.join(OUT, name + '.png'), data)
        duration = scans[-1].time - scans[0].time
        held, unshared = slam.map_memory()
        print(json.dumps(dict(benchmark='slam', metric='%s memory of the 30 particle maps' % name,
                              value=held / 2 ** 20, unit='MB', note='%.0f MB if no patch were shared' % (unshared / 2 ** 20))))
        print('%s: %d scans, %d filter updates, %.1f CPU s for %.0f s of log; map in %s'
              % (name, len(scans), slam.updates, cpu, duration, os.path.join(OUT, name + '.png')), flush=True)
        print(json.dumps(dict(benchmark='slam', metric='%s CPU time' % name, value=cpu, unit='s',
                              target='<= 25' if name == 'aces' else '', note='%.0fx faster than the log' % (duration / cpu))))
        if rel:
            e = evaluate(np.array([s.time for s in scans]), poses, read_relations(os.path.join(DATA, rel)))
            print(json.dumps(dict(benchmark='slam', metric='%s translation error' % name, value=e.trans_mean, unit='m',
                                  target='<= %.2f' % target, note='std %.3f, %d relations' % (e.trans_std, e.count))))
            print(json.dumps(dict(benchmark='slam', metric='%s rotation error' % name, value=e.rot_mean, unit='deg',
                                  note='std %.3f' % e.rot_std)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
