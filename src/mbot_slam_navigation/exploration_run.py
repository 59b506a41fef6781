"""Runs a whole exploration (roslaunch of launch/explore.launch or another launch file with an
explore node) until the explorer has written its report, then shuts the launch down cleanly and
prints one line with the outcome. Exit status 0 only for outcome `complete`; 2 if there is no
report (roslaunch ended first, or the wall-clock limit passed).

Why not `required="true"` on the explorer: roslaunch then ends with a "REQUIRED process has died"
banner, which reads as a crash at the end of every successful run.
"""
import argparse
import json
import os
import signal
import subprocess
import sys
import time
import xmlrpc.client
from typing import Dict, List, Optional

from mbot_slam_navigation.master_rpc import master_proxy


EXPLORERS = ('explore', 'explore_team')  # node names whose report run() waits for


def report_dir_of(launch_args: List[str]) -> Optional[str]:
    for a in launch_args:
        if a.startswith('report_dir:='):
            return os.path.abspath(a.split(':=', 1)[1])
    return None


def stop(proc: subprocess.Popen, grace_s: float = 30.0) -> int:
    """SIGINT (roslaunch's Ctrl-C), then SIGTERM and SIGKILL if it does not end in time."""
    for sig, wait in ((signal.SIGINT, grace_s), (signal.SIGTERM, 10.0), (signal.SIGKILL, 10.0)):
        if proc.poll() is not None:
            break
        proc.send_signal(sig)
        try:
            proc.wait(timeout=wait)
        except subprocess.TimeoutExpired:
            continue
    return proc.wait()


def _namespace_of(pid: str) -> str:
    """'robot1/' for a node roslaunch started in namespace /robot1 (its ROS_NAMESPACE), else ''."""
    try:
        with open('/proc/%s/environ' % pid, 'rb') as f:
            env = f.read().decode(errors='replace').split('\0')
    except OSError:
        return ''
    ns = next((e.split('=', 1)[1] for e in env if e.startswith('ROS_NAMESPACE=')), '')
    ns = ns.strip('/')
    return ns + '/' if ns else ''


def _launched(launch_pid: int):
    """(node name, pid, /proc stat fields) of each process that roslaunch `launch_pid` started and
    named with __name:=; the name has its namespace in front ('robot1/move_base') if it has one."""
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            with open('/proc/%s/stat' % entry) as f:
                stat = f.read()
            with open('/proc/%s/cmdline' % entry, 'rb') as f:
                args = f.read().decode(errors='replace').split('\0')
        except OSError:
            continue
        fields = stat[stat.rindex(')') + 2:].split()  # after "pid (comm) "
        if int(fields[1]) != launch_pid:
            continue
        name = next((a.split(':=', 1)[1] for a in args if a.startswith('__name:=')), None)
        if name:
            yield _namespace_of(entry) + name, int(entry), fields


def node_pids(launch_pid: int) -> Dict[str, int]:
    """The pid of each node that roslaunch `launch_pid` started, by node name (its __name:=)."""
    return {name: pid for name, pid, _ in _launched(launch_pid)}


def node_cpu_seconds(launch_pid: int) -> Dict[str, float]:
    """CPU seconds (user + system) used so far by each node that roslaunch `launch_pid` started,
    by node name (its __name:= argument), read from /proc."""
    tick = os.sysconf('SC_CLK_TCK')
    return {name: (int(fields[11]) + int(fields[12])) / tick for name, _, fields in _launched(launch_pid)}


def summary(r: dict, report_dir: str) -> str:
    if 'why' in r:
        return 'exploration: %s: %s; report in %s' % (r.get('outcome'), r['why'], report_dir)
    line = 'exploration: %s after %.0f s simulated (%.0f s wall)' % (r.get('outcome'), r.get('exploration_time_s', 0),
                                                                     r.get('wall_time_s', 0))
    if 'coverage_of_reachable_free' in r:
        line += ', %.1f%% of the reachable free space, walls %.1f%% within 0.1 m' % (
            100 * r['coverage_of_reachable_free'], 100 * r['walls_within_tolerance'])
    if r.get('per_robot'):
        line += ', %d robots (%s)' % (len(r['per_robot']), ', '.join(
            '%s %s, %.0f m' % (name, v.get('outcome'), v.get('distance_m') or 0.0) for name, v in sorted(r['per_robot'].items())))
    line += ', %d collisions, %d given up; report in %s' % (r.get('collisions', 0), len(r.get('given_up', [])),
                                                             report_dir)
    return line


def master_uri_of(launch: List[str], env=None) -> str:
    """The ROS master the launch will use: roslaunch's -p PORT, else ROS_MASTER_URI."""
    for flag, value in zip(launch, launch[1:]):
        if flag in ('-p', '--port'):
            return 'http://localhost:%s' % value
    return (env if env is not None else os.environ).get('ROS_MASTER_URI', 'http://localhost:11311')


def running_simulation(master_uri: str) -> Optional[str]:
    """The simulator or explorer node already registered with the master at master_uri, if any
    (None: no master there, or none of those nodes). roslaunch joins a master that runs already;
    a second simulation on it takes over the first one's node names and publishes a second
    /clock, and neither run means anything (two benches on one port did that)."""
    # A master URI on a host that does not answer must not hold the run: 5 s, then roslaunch's
    # own error says what is wrong.
    master = master_proxy(master_uri, 5.0)
    try:
        for node in ('/gazebo', '/explore'):
            code, _, _ = master.lookupNode('/run_exploration', node)
            if code == 1:
                return node
    except (OSError, xmlrpc.client.Error):
        return None  # no master there (or no ROS master: an HTTP error): roslaunch decides
    return None


def run(launch: List[str], wall_timeout: float, env=None, stdout=None) -> Optional[dict]:
    """Runs `roslaunch <launch...>` until report.json appears in its report_dir; the report or None."""
    report_dir = report_dir_of(launch)
    if report_dir is None:
        raise SystemExit('run_exploration: pass report_dir:=DIR among the roslaunch arguments')
    uri = master_uri_of(launch, env)
    other = running_simulation(uri)
    if other is not None:
        print('run_exploration: the ROS master at %s already has a node %s (another exploration or bench is '
              'running there); not starting a second simulation on it' % (uri, other), flush=True)
        return None
    report = os.path.join(report_dir, 'report.json')
    if os.path.exists(report):
        os.remove(report)  # a report from an earlier run must not end this one at once
    proc = subprocess.Popen(['roslaunch'] + launch, env=env, stdout=stdout, stderr=subprocess.STDOUT if stdout else None)
    # A SIGTERM to this process (a bench killed, a CI timeout) must not leave the launch running.
    previous = signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    t0 = time.monotonic()
    explorers: set = set()  # explorer nodes seen running
    gone_since = None
    try:
        while not os.path.exists(report):
            if proc.poll() is not None:
                print('run_exploration: roslaunch ended (exit %d) before the explorer wrote %s' % (proc.returncode,
                                                                                                  report), flush=True)
                return None
            # An explorer that died (not required="true": see above) leaves the launch running with
            # no one to write the report; do not wait out the wall-clock limit for it.
            running = {n for n in node_pids(proc.pid) if n.rsplit('/', 1)[-1] in EXPLORERS}
            explorers |= running
            if explorers and not running:
                gone_since = gone_since or time.monotonic()
                if time.monotonic() - gone_since > 5.0:
                    print('run_exploration: %s ended without writing %s (see its log above); stopping the launch'
                          % (', '.join(sorted(explorers)), report), flush=True)
                    return None
            if time.monotonic() - t0 > wall_timeout:
                print('run_exploration: no report after %.0f s of wall time; stopping the launch' % wall_timeout,
                      flush=True)
                return None
            time.sleep(1.0)
        time.sleep(1.0)  # the explorer's last lines
        with open(report) as f:
            r = json.load(f)
        r['node_cpu_s'] = node_cpu_seconds(proc.pid)  # the whole run, start-up and return included
        return r
    finally:
        stop(proc)
        signal.signal(signal.SIGTERM, previous)


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    p.add_argument('--wall-timeout', type=float, default=3600.0, help='[s] of wall time before giving up')
    p.add_argument('launch', nargs=argparse.REMAINDER, help='roslaunch arguments: PKG FILE.launch [arg:=value ...]')
    a = p.parse_args(argv)
    if a.launch[:1] == ['--']:
        a.launch = a.launch[1:]
    try:
        r = run(a.launch, a.wall_timeout)
    except KeyboardInterrupt:
        print('run_exploration: interrupted', flush=True)
        sys.exit(130)
    if r is None:
        sys.exit(2)
    print(summary(r, report_dir_of(a.launch)), flush=True)
    sys.exit(0 if r.get('outcome') == 'complete' else 1)
