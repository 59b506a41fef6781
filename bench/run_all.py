#!/usr/bin/env python3
"""Runs every bench/bench_*.py and prints one table of what they measured.

Each benchmark prints result lines as JSON objects with keys: benchmark, metric, value, unit and
optionally target (a string such as ">= 5e6") and note. Other output is passed through as progress.
Run inside the devel environment (make bench does that).
"""
import glob
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))


def run(path):
    rows = []
    start = time.time()
    proc = subprocess.Popen([sys.executable, path], stdout=subprocess.PIPE, text=True)
    for line in proc.stdout:
        line = line.strip()
        if line.startswith('{'):
            try:
                rows.append(json.loads(line))
                continue
            except json.JSONDecodeError:
                pass
        print('  ' + line, flush=True)
    rc = proc.wait()
    return rows, rc, time.time() - start


def main():
    only = sys.argv[1:]
    all_rows, failed = [], []
    for path in sorted(glob.glob(os.path.join(HERE, 'bench_*.py'))):
        name = os.path.basename(path)[:-3]
        if only and name not in only:
            continue
        print('== %s' % name, flush=True)
        rows, rc, wall = run(path)
        print('   (%.1f s wall)' % wall)
        if rc != 0:
            failed.append(name)
        all_rows.extend(rows)
    header = ('benchmark', 'metric', 'value', 'unit', 'target', 'note')
    table = [header] + [(r.get('benchmark', ''), r.get('metric', ''), '%.4g' % r['value']
                         if isinstance(r.get('value'), (int, float)) else str(r.get('value')),
                         r.get('unit', ''), r.get('target', ''), r.get('note', '')) for r in all_rows]
    widths = [max(len(str(row[i])) for row in table) for i in range(len(header))]
    print()
    for k, row in enumerate(table):
        print(' | '.join(str(c).ljust(w) for c, w in zip(row, widths)).rstrip())
        if k == 0:
            print('-+-'.join('-' * w for w in widths))
    if failed:
        print('\nbenchmarks that failed: %s' % ', '.join(failed))
        sys.exit(1)


if __name__ == '__main__':
    main()
