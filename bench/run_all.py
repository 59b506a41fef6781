#!/usr/bin/env python3
"""Runs the benchmarks, prints one table of what they measured and writes docs/benchmarks.md.

    bench/run_all.py                  every bench/bench_*.py
    bench/run_all.py bench_grid ...   those only (the page keeps the others' last figures)
    bench/run_all.py --page           rewrite the page from the stored results, running nothing

Each benchmark prints result lines as JSON objects with keys: benchmark, metric, value, unit and
optionally target (a string such as ">= 5e6"), peer (the same figure of the ROS tool or another
peer, where one was measured) and note. Other output is passed through as progress. A benchmark
that ends well stores its figures with the date, the machine, its BENCH_* settings and its method
(the first paragraph of its docstring) in bench/results/<benchmark>.json; the page shows the
stored figures of every benchmark: the current ones only (the history is CHANGELOG.rst's).
Run inside the devel environment (make bench does that).
"""
import datetime
import glob
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS = os.path.join(HERE, 'results')
PAGE = os.path.join(os.path.dirname(HERE), 'docs', 'benchmarks.md')


def machine() -> str:
    """This machine in a few words: CPU model, cores, memory, OS."""
    model = ''
    try:
        with open('/proc/cpuinfo') as f:
            model = next((l.split(':', 1)[1].strip() for l in f if l.startswith('model name')), '')
    except OSError:
        pass
    mem = ''
    try:
        with open('/proc/meminfo') as f:
            kb = int(next(l.split()[1] for l in f if l.startswith('MemTotal')))
            mem = ', %.0f GiB' % (kb / 2 ** 20)
    except (OSError, StopIteration, ValueError):
        pass
    return '%s, %d cores%s, %s' % (model or platform.machine(), os.cpu_count() or 0, mem, platform.platform(terse=True))


def method_of(path: str) -> str:
    """The first paragraph of a benchmark's docstring, on one line."""
    import ast
    with open(path) as f:
        doc = ast.get_docstring(ast.parse(f.read())) or ''
    return ' '.join(doc.split('\n\n')[0].split())


def atomic_write(path: str, text: str) -> None:
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix='.' + os.path.basename(path) + '.', dir=os.path.dirname(path))
    with os.fdopen(fd, 'w') as f:
        f.write(text)
    os.replace(tmp, path)


def store(name: str, path: str, rows, wall: float) -> None:
    atomic_write(os.path.join(RESULTS, name + '.json'), json.dumps({
        'benchmark': name,
        'date': datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC'),
        'machine': machine(),
        'settings': {k: v for k, v in sorted(os.environ.items()) if k.startswith(('BENCH_', 'SLAM_'))},
        'method': method_of(path),
        'wall_s': round(wall, 1),
        'rows': rows,
    }, indent=1) + '\n')


def _value(v) -> str:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return str(v)
    if abs(v) >= 1000:
        return '{:,.0f}'.format(v)
    return '%.4g' % v


def write_page() -> None:
    lines = ['# Benchmarks', '',
             '<!-- Written by bench/run_all.py (make bench) from bench/results/*.json. DO NOT EDIT. -->', '',
             'The current figures of each benchmark, as `make bench` last measured them, with the date, the',
             'machine and the method. Run one with `bench/run_all.py bench_NAME` (inside the devel space);',
             'the page keeps the others. Earlier figures and how they moved: `CHANGELOG.rst`.', '']
    results = []
    for path in sorted(glob.glob(os.path.join(RESULTS, '*.json'))):
        with open(path) as f:
            results.append(json.load(f))
    measured = {r['benchmark'] for r in results}
    missing = sorted(os.path.basename(p)[:-3] for p in glob.glob(os.path.join(HERE, 'bench_*.py'))
                     if os.path.basename(p)[:-3] not in measured)
    if missing:
        lines += ['Not measured by `make bench` yet: %s.' % ', '.join('`%s`' % m for m in missing), '']
    for r in results:
        lines += ['## %s' % r['benchmark'], '', r['method'], '',
                  'Measured %s on %s, %.0f s of wall time%s.' % (
                      r['date'], r['machine'], r['wall_s'],
                      '; settings ' + ', '.join('%s=%s' % kv for kv in r['settings'].items()) if r['settings'] else ''),
                  '']
        peers = any('peer' in row for row in r['rows'])
        header = ['metric', 'value', 'unit', 'target'] + (['peer'] if peers else []) + ['note']
        # rows of several parts (a world and a load, a log and a backend): one table per part
        parts = []
        for row in r['rows']:
            if not parts or parts[-1][0] != row.get('benchmark', ''):
                parts.append((row.get('benchmark', ''), []))
            parts[-1][1].append(row)
        for part, rows in parts:
            if len(parts) > 1:
                lines += ['### %s' % part, '']
            lines += ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
            for row in rows:
                cells = [row.get('metric', ''), _value(row.get('value', '')), row.get('unit', ''), row.get('target', '')]
                cells += [_value(row['peer']) if 'peer' in row else ''] if peers else []
                cells += [row.get('note', '')]
                lines.append('| ' + ' | '.join(str(c).replace('|', '\\|') for c in cells) + ' |')
            lines.append('')
    atomic_write(PAGE, '\n'.join(lines).rstrip() + '\n')
    print('wrote %s' % os.path.relpath(PAGE))


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
    if only == ['--page']:
        write_page()
        return
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
        elif rows:
            store(name, path, rows, wall)
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
    write_page()
    if failed:
        print('\nbenchmarks that failed (their earlier figures stay on the page): %s' % ', '.join(failed))
        sys.exit(1)


if __name__ == '__main__':
    main()
