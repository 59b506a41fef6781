#!/usr/bin/env python3
"""move_base through clutter, with the world's map given and without a map (issue 57): per
difficulty, how often the mbot gets through a strip of random obstacles to a goal 10 m away.

Worlds: tools/generate_clutter.py, levels wide, medium and narrow (the narrowest gap on the widest
way through 1.5x, 1.3x and 1.15x the mbot's 0.4 m width; 25-35% of the strip covered), seeds
1..SEEDS, written to bench/out/clutter/. Each world is driven twice: with the world's perfect map
(map:=true) and with costmaps from the laser alone (map:=false, as navigation benchmarks in clutter
are run), by launch/move_base_clutter.launch: the exploration tutorial's move_base YAMLs, perfect
localization, real_time_factor auto, one trial per process (bench/clutter_trial.py). Printed per
level and setting: reached within the limit, collisions, median and worst time against the ideal
(the shortest path for the robot's radius over max_vel_x, 0.3 m/s), recoveries run, distance
driven; every trial's line is kept in bench/out/clutter/trials.jsonl. Trials run JOBS at a time,
each on its own master: the simulation paces itself to move_base (real_time_factor auto), so a
busy machine slows a trial's wall time, not the robot's simulated one.

Environment: BENCH_CLUTTER_SEEDS (default 6: 18 worlds, 36 trials), BENCH_CLUTTER_LEVELS
(wide,medium,narrow), BENCH_CLUTTER_MAPS (true,false), BENCH_CLUTTER_LIMIT (100 simulated s, as
the issue's trials), BENCH_CLUTTER_JOBS (2), BENCH_CLUTTER_MAP_RESOLUTION (0.05 m/cell, the
world's map with the map given). Targets (issue 57): without a map >= 95% reached within 2.2x the
ideal time, 0 collisions, median <= 1.4x the ideal; with the map 100%, median <= 1.2x.
"""
import concurrent.futures
import json
import os
import statistics
import subprocess
import sys

import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(HERE, 'out', 'clutter')
MAX_VEL_X = 0.3  # [m/s] config/base_local_planner_params.yaml
PORT = 11421

sys.path.insert(0, os.path.join(ROOT, 'tools'))
import generate_clutter  # noqa: E402


def trial(world_yaml: str, with_map: bool, limit: float, k: int, map_resolution: float) -> dict:
    tag = '%s_%s' % (os.path.basename(world_yaml)[:-5], 'map' if with_map else 'nomap')
    out = subprocess.run([sys.executable, os.path.join(HERE, 'clutter_trial.py'), world_yaml,
                          '--map', 'true' if with_map else 'false', '--port', str(PORT + k % 50),
                          '--map-resolution', str(map_resolution), '--limit', str(limit),
                          '--log', os.path.join(OUT, tag + '.log')],
                         capture_output=True, text=True, timeout=20 * limit + 300)
    line = next((l for l in reversed(out.stdout.splitlines()) if l.startswith('{')), None)
    if line is None:
        return {'world': os.path.basename(world_yaml), 'map': with_map, 'outcome': 'error',
                'why': (out.stderr or out.stdout)[-300:]}
    return json.loads(line)


def summary(rows, ideal):
    """Figures of one level and setting."""
    n = len(rows)
    reached = [r for r in rows if r['outcome'] == 'reached']
    ratios = sorted(r['time_s'] / ideal[r['world']] for r in reached)
    within = [x for x in ratios if x <= 2.2]
    return {
        'trials': n,
        'reached': len(reached),
        'reached_within_2.2x': len(within),
        'collisions': sum(r.get('collisions', 0) for r in rows),
        'median_time_x_ideal': statistics.median(ratios) if ratios else None,
        'worst_time_x_ideal': max(ratios) if ratios else None,
        'recoveries': sum(r.get('recoveries', 0) for r in rows),
        'distance_m': statistics.median([r.get('distance_m') or 0.0 for r in rows]) if rows else 0.0,
    }


def main() -> int:
    seeds = int(os.environ.get('BENCH_CLUTTER_SEEDS', '6'))
    levels = os.environ.get('BENCH_CLUTTER_LEVELS', 'wide,medium,narrow').split(',')
    maps = [m == 'true' for m in os.environ.get('BENCH_CLUTTER_MAPS', 'true,false').split(',')]
    limit = float(os.environ.get('BENCH_CLUTTER_LIMIT', '100'))
    map_resolution = float(os.environ.get('BENCH_CLUTTER_MAP_RESOLUTION', '0.05'))
    if True in maps:
        print("  the world's map at %g m/cell" % map_resolution, flush=True)
    os.makedirs(OUT, exist_ok=True)
    worlds, ideal = [], {}
    for level in levels:
        for seed in range(1, seeds + 1):
            info = generate_clutter.write(level, seed, OUT)
            worlds.append((level, os.path.join(OUT, 'clutter_%s_%d.yaml' % (level, seed))))
            ideal[info['world']] = info['shortest_path_m'] / MAX_VEL_X
            print('  %s: %d obstacles, narrowest gap %.2f m, shortest path %.2f m (ideal %.1f s)'
                  % (info['world'], info['obstacles'], info['narrowest_gap_m'], info['shortest_path_m'],
                     ideal[info['world']]), flush=True)
    jobs = max(1, int(os.environ.get('BENCH_CLUTTER_JOBS', '2')))
    tasks = [(level, world_yaml, with_map) for level, world_yaml in worlds for with_map in maps]
    rows = []
    # The settings alternate in the task list, so the machine's noise falls on both.
    with open(os.path.join(OUT, 'trials.jsonl'), 'w') as log, concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        started = {}
        for k, (level, world_yaml, with_map) in enumerate(tasks):
            started[pool.submit(trial, world_yaml, with_map, limit, k, map_resolution)] = (level, with_map)
        for done in concurrent.futures.as_completed(started):
            level, with_map = started[done]
            r = done.result()
            r['level'] = level
            rows.append(r)
            log.write(json.dumps(r) + '\n')
            log.flush()
            print('  [%d/%d] %s %s: %s in %s s simulated (ideal %.1f s), %.1f m, %d collisions, %d recoveries%s '
                  '(%.0f s wall)' % (len(rows), len(tasks), r['world'], 'map' if with_map else 'no map', r['outcome'],
                                     r.get('time_s'), ideal.get(r['world'], float('nan')), r.get('distance_m') or 0.0,
                                     r.get('collisions', 0), r.get('recoveries', 0),
                                     ': ' + r['why'] if r.get('why') else '', r.get('wall_s') or 0.0),
                  flush=True)
    for with_map in maps:
        setting = 'map' if with_map else 'no map'
        for level in levels + ['all']:
            sel = [r for r in rows if r['map'] == with_map and (level == 'all' or r['level'] == level)]
            if not sel:
                continue
            s = summary(sel, ideal)
            name = '%s, %s' % (level, setting)
            target_share = '100%' if with_map else '>= 95%'
            print(json.dumps({'benchmark': 'clutter', 'metric': 'reached within 2.2x the ideal time: ' + name,
                              'value': round(100.0 * s['reached_within_2.2x'] / s['trials'], 1), 'unit': '%',
                              'target': target_share if level == 'all' else '',
                              'note': '%d of %d reached (%d within 2.2x), %d collisions, %d recoveries, median %.1f m '
                                      'driven' % (s['reached'], s['trials'], s['reached_within_2.2x'], s['collisions'],
                                                  s['recoveries'], s['distance_m'])}))
            if s['median_time_x_ideal'] is not None:
                print(json.dumps({'benchmark': 'clutter', 'metric': 'median time / ideal: ' + name,
                                  'value': round(s['median_time_x_ideal'], 2), 'unit': 'x',
                                  'target': ('<= 1.2' if with_map else '<= 1.4') if level == 'all' else '',
                                  'note': 'worst %.2fx of those reached' % s['worst_time_x_ideal']}))
    return 0


if __name__ == '__main__':
    sys.exit(main())
