#!/usr/bin/env python3
"""A team of robots on hosts of their own, on this one machine: a base host and one host per robot
as Linux network namespaces joined by a bridge (veth links, private addresses 10.211.0.0/24; nothing
is added to the machine's own namespace), one ROS master on the base, launch/base_station.launch
there, launch/robot.launch on each robot host with ROS_IP set to its address. Everything is torn
down at the end, also on a failure or Ctrl-C.

    tools/multi_host.py --robots 2 --report-dir report [--world FILE] [--spawn x,y[,yaw] ...]
        [--max-duration S] [--launch-arg name:=value ...] [--netem "delay 100ms loss 2%"] [--cut robot2:60:10]
        [--kill robot3:60]

--netem applies tc netem to every robot's link; --kill ROBOT:AT kills every process of ROBOT's
host (SIGKILL) AT seconds (wall) after the robots start, as a host that dies; --cut ROBOT:AT:FOR
takes ROBOT's link down AT seconds (wall) after the robots start, for FOR seconds. Prints the team's
one line and the bytes each robot's link carried (both directions, TCPROS and the master's XML-RPC)
per simulated and per wall second, and the message bytes of the robot's stack apart from the
simulator's streams (which stay on board a real robot); adds them to the team's report.json
(`link`), with the outages the base station heard (`outages`). Exit status 0 only for outcome
`complete`. Needs root (ip netns). `make demo ROBOTS=N HOSTS=separate` runs it.
"""
import argparse
import json
import os
import shlex
import signal
import subprocess
import sys
import time
from typing import Dict, List, Optional

SUBNET = '10.211.0.'
BASE_IP = SUBNET + '1'
MASTER_URI = 'http://%s:11311' % BASE_IP
SPAWNS = [(0.0, 0.0, 0.0), (2.3, -2.2, 0.0), (-4.0, -2.5, 0.0), (-1.0, 2.0, 0.0)]  # base_station.launch's


def run(*cmd: str, ns: Optional[str] = None, check: bool = True) -> str:
    full = (['ip', 'netns', 'exec', ns] if ns else []) + list(cmd)
    p = subprocess.run(full, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if check and p.returncode != 0:
        raise RuntimeError('%s: %s' % (' '.join(full), p.stderr.strip() or 'exit %d' % p.returncode))
    return p.stdout


class Hosts:
    """The namespaces and links of one run, named after this process so that runs do not collide."""

    def __init__(self, robots: int):
        tag = str(os.getpid())
        self.base = 'mbot-base-' + tag
        self.robots = ['mbot-r%d-%s' % (k, tag) for k in range(1, robots + 1)]
        self.links = [('mb%sb%d' % (tag[-6:], k), 'mb%sr%d' % (tag[-6:], k)) for k in range(1, robots + 1)]
        self.ips = [SUBNET + str(10 + k) for k in range(1, robots + 1)]
        self.made: List[str] = []

    def create(self) -> None:
        for ns in [self.base] + self.robots:
            run('ip', 'netns', 'add', ns)
            self.made.append(ns)
            run('ip', 'link', 'set', 'lo', 'up', ns=ns)
        run('ip', 'link', 'add', 'br0', 'type', 'bridge', ns=self.base)
        run('ip', 'addr', 'add', BASE_IP + '/24', 'dev', 'br0', ns=self.base)
        run('ip', 'link', 'set', 'br0', 'up', ns=self.base)
        for ns, (outer, inner), ip in zip(self.robots, self.links, self.ips):
            # created inside the base namespace, the robot's end moved into the robot's
            run('ip', 'link', 'add', outer, 'type', 'veth', 'peer', 'name', inner, ns=self.base)
            run('ip', 'link', 'set', inner, 'netns', ns, ns=self.base)
            run('ip', 'link', 'set', outer, 'master', 'br0', ns=self.base)
            run('ip', 'link', 'set', outer, 'up', ns=self.base)
            run('ip', 'addr', 'add', ip + '/24', 'dev', inner, ns=ns)
            run('ip', 'link', 'set', inner, 'up', ns=ns)

    def bytes(self, k: int) -> int:
        """Bytes through robot k's link so far, both directions (its end's counters)."""
        inner = self.links[k][1]
        rx = int(run('cat', '/sys/class/net/%s/statistics/rx_bytes' % inner, ns=self.robots[k]))
        tx = int(run('cat', '/sys/class/net/%s/statistics/tx_bytes' % inner, ns=self.robots[k]))
        return rx + tx

    def set_link(self, k: int, up: bool) -> None:
        run('ip', 'link', 'set', self.links[k][1], 'up' if up else 'down', ns=self.robots[k])

    def netem(self, k: int, spec: str) -> None:
        try:
            run('tc', 'qdisc', 'add', 'dev', self.links[k][1], 'root', 'netem', *shlex.split(spec), ns=self.robots[k])
        except RuntimeError as e:
            if 'qdisc kind is unknown' in str(e):
                raise RuntimeError('--netem: this kernel has no netem queueing discipline (sch_netem, %s); delay '
                                   'and loss cannot be added here' % os.uname().release) from None
            raise

    def kill_all(self, ns: str) -> int:
        """SIGKILL to every process of namespace `ns` (as a host that dies: roslaunch starts each node
        in a session of its own, so killing roslaunch's group leaves its nodes running); how many."""
        pids = [int(p) for p in run('ip', 'netns', 'pids', ns, check=False).split()]
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
        return len(pids)

    def remove(self) -> None:
        for ns in reversed(self.made):
            self.kill_all(ns)  # nothing outlives its host: a namespace deleted leaves its processes running
            run('ip', 'netns', 'delete', ns, check=False)  # its links go with it
        self.made = []


SIMULATOR = '/gazebo'  # empty_world.launch's simulator node: its streams stay on board a real robot


def topic_bytes(hosts: Hosts, k: int) -> Dict[str, Dict[str, int]]:
    """{peer node: {topic: message bytes}} between robot k's nodes and other hosts' (bus_traffic, run
    on the base)."""
    out = run(sys.executable, '-m', 'mbot_slam_navigation.bus_traffic', '--master', MASTER_URI,
              '--host', hosts.ips[k], '--by-peer', ns=hosts.base, check=False)
    try:
        return json.loads(out)
    except ValueError:
        return {}


def link_figures(link_bytes: int, by_peer: Dict[str, Dict[str, int]], sim: float, wall: float) -> dict:
    """A robot's link in the team's report: the interface's bytes (both ways, TCP/IP included) per
    simulated and wall second, and message bytes per topic; `stack_kB_per_s` counts the messages
    between the robot's stack and the base's nodes other than the simulator: what crosses the link
    of a real robot, whose sensors, odometry and clock are on board."""
    topics: Dict[str, int] = {}
    for by_topic in by_peer.values():
        for t, b in by_topic.items():
            topics[t] = topics.get(t, 0) + b
    stack = sum(b for peer, by_topic in by_peer.items() if peer != SIMULATOR for b in by_topic.values())
    per_s = (lambda b: round(b / 1000.0 / sim, 2)) if sim > 0 else (lambda b: None)
    return {
        'bytes': link_bytes,
        'link_kB_per_s': round(link_bytes / 1000.0 / sim, 1) if sim > 0 else None,
        'link_kB_per_wall_s': round(link_bytes / 1000.0 / wall, 1),
        'stack_kB_per_s': per_s(stack),
        'simulator_kB_per_s': per_s(sum(by_peer.get(SIMULATOR, {}).values())),
        # message bytes per topic over the robot's connections to other hosts (the nodes' counters)
        'topics_kB_per_s': {t: per_s(b) for t, b in sorted(topics.items(), key=lambda tb: -tb[1])
                            if sim > 0 and b > 0}}


def start(ns: str, ip: str, args: List[str], log: str) -> subprocess.Popen:
    """roslaunch in namespace `ns` as a host with address `ip`, in a process group of its own."""
    env = dict(os.environ, ROS_IP=ip, ROS_MASTER_URI=MASTER_URI)
    env.pop('ROS_HOSTNAME', None)
    out = open(log, 'w')
    return subprocess.Popen(['ip', 'netns', 'exec', ns, 'roslaunch'] + args, env=env, stdout=out,
                            stderr=subprocess.STDOUT, start_new_session=True)


def stop(procs: List[subprocess.Popen]) -> None:
    """Ctrl-C to every roslaunch, then SIGTERM and SIGKILL to what is left of their groups."""
    for sig, grace in ((signal.SIGINT, 30.0), (signal.SIGTERM, 10.0), (signal.SIGKILL, 5.0)):
        alive = [p for p in procs if p.poll() is None]
        if not alive:
            return
        for p in alive:
            try:
                os.killpg(p.pid, sig)
            except ProcessLookupError:
                pass
        end = time.monotonic() + grace
        while time.monotonic() < end and any(p.poll() is None for p in alive):
            time.sleep(0.2)


def _terminated(*_) -> None:
    raise KeyboardInterrupt  # SIGTERM tears down as Ctrl-C does


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--robots', type=int, default=2, choices=range(1, 5))
    ap.add_argument('--report-dir', required=True)
    ap.add_argument('--world', default='')
    ap.add_argument('--max-duration', type=float, default=1200.0, help='[s] simulated, per explorer')
    ap.add_argument('--timeout', type=float, default=3600.0, help='[s] wall, for the whole run')
    ap.add_argument('--launch-arg', action='append', default=[], help='name:=value for base_station.launch')
    ap.add_argument('--spawn', action='append', default=[],
                    help="x,y[,yaw]: a robot's start in the world, once per robot in order (default: the home's)")
    ap.add_argument('--netem', default='', help='tc netem on every robot link, e.g. "delay 100ms loss 2%%"')
    ap.add_argument('--bad-ros-ip', default='', metavar='ROBOT',
                    help='start robotK with ROS_IP=127.0.0.1 (a misconfigured host, to see it reported)')
    ap.add_argument('--cut', default='', help='ROBOT:AT:FOR: robotK link down AT s (wall) after the start, FOR s')
    ap.add_argument('--kill', default='', help="ROBOT:AT: robotK's host dies AT s (wall) after the start")
    a = ap.parse_args(argv)
    if os.geteuid() != 0:
        print('multi_host: network namespaces need root (ip netns); run as root', file=sys.stderr)
        return 2
    report_dir = os.path.abspath(a.report_dir)
    os.makedirs(report_dir, exist_ok=True)
    report = os.path.join(report_dir, 'report.json')
    if os.path.exists(report):
        os.replace(report, report + '.previous')
    cut = None
    kill = None
    if a.kill:
        name, at = a.kill.split(':')
        kill = (int(name.replace('robot', '')) - 1, float(at))
    if a.cut:
        name, at, length = a.cut.split(':')
        cut = (int(name.replace('robot', '')) - 1, float(at), float(length))
    world = ['world_name:=' + os.path.abspath(a.world)] if a.world else []
    spawns = list(SPAWNS)
    for k, text in enumerate(a.spawn[:4]):
        v = [float(t) for t in text.split(',')]
        spawns[k] = (v[0], v[1], v[2] if len(v) > 2 else 0.0)
    poses = ['%s%d:=%g' % (key, k + 1, v) for k in range(a.robots) for key, v in zip(('x', 'y', 'yaw'), spawns[k])]
    hosts = Hosts(a.robots)
    procs: List[subprocess.Popen] = []
    signal.signal(signal.SIGTERM, _terminated)
    try:
        hosts.create()
        for k in range(a.robots):
            if a.netem:
                hosts.netem(k, a.netem)
        print('multi_host: base %s (%s), robots %s' % (hosts.base, BASE_IP, ', '.join(
            '%s (%s)' % (ns, ip) for ns, ip in zip(hosts.robots, hosts.ips))), flush=True)
        procs.append(start(hosts.base, BASE_IP, ['mbot_slam_navigation', 'base_station.launch',
                                                 'robots:=%d' % a.robots, 'report_dir:=' + report_dir,
                                                 'max_duration:=%g' % a.max_duration] + world + poses + a.launch_arg,
                           os.path.join(report_dir, 'base_station.log')))
        for k in range(a.robots):
            x, y, yaw = spawns[k]
            name = 'robot%d' % (k + 1)
            procs.append(start(hosts.robots[k], '127.0.0.1' if a.bad_ros_ip == name else hosts.ips[k],
                               ['--wait', 'mbot_slam_navigation', 'robot.launch', 'ns:=' + name, 'x:=%g' % x,
                                'y:=%g' % y, 'yaw:=%g' % yaw, 'report_dir:=' + os.path.join(report_dir, name),
                                'max_duration:=%g' % a.max_duration] + world,
                               os.path.join(report_dir, name + '.log')))
        t0 = time.monotonic()
        start_bytes = [hosts.bytes(k) for k in range(a.robots)]
        cut_state = 'pending' if cut else None
        killed = None
        while not os.path.exists(report):
            now = time.monotonic() - t0
            if kill and now >= kill[1]:
                n = hosts.kill_all(hosts.robots[kill[0]])
                print('multi_host: robot%d host killed at %.0f s (%d processes)' % (kill[0] + 1, now, n), flush=True)
                killed = {'robot': 'robot%d' % (kill[0] + 1), 'at_wall_s': round(now, 1)}
                kill = None
            if cut_state == 'pending' and now >= cut[1]:
                hosts.set_link(cut[0], False)
                print('multi_host: robot%d link cut at %.0f s' % (cut[0] + 1, now), flush=True)
                cut_state = 'down'
            elif cut_state == 'down' and now >= cut[1] + cut[2]:
                hosts.set_link(cut[0], True)
                print('multi_host: robot%d link restored at %.0f s' % (cut[0] + 1, now), flush=True)
                cut_state = 'done'
            if procs[0].poll() is not None:
                print('multi_host: the base station ended (exit %s) before the team\'s report; see %s'
                      % (procs[0].returncode, os.path.join(report_dir, 'base_station.log')), file=sys.stderr)
                return 2
            if now > a.timeout:
                print('multi_host: no team report after %.0f s (wall)' % a.timeout, file=sys.stderr)
                return 2
            time.sleep(1.0)
        wall = time.monotonic() - t0
        link_bytes = [hosts.bytes(k) - start_bytes[k] for k in range(a.robots)]
        topics = [topic_bytes(hosts, k) for k in range(a.robots)]
        time.sleep(1.0)  # written atomically; read once it is whole
        with open(report) as f:
            figures = json.load(f)
        sim = float(figures.get('total_time_s') or 0.0)
        figures['hosts'] = 'separate'
        figures['link'] = {'robot%d' % (k + 1): link_figures(link_bytes[k], topics[k], sim, wall)
                           for k in range(a.robots)}
        if killed:
            figures['host_killed'] = killed
        if cut:
            figures['link_cut'] = {'robot': 'robot%d' % (cut[0] + 1), 'at_wall_s': cut[1], 'for_s': cut[2]}
        if a.netem:
            figures['netem'] = a.netem
        tmp = report + '.tmp'
        with open(tmp, 'w') as f:
            json.dump(figures, f, indent=2)
        os.replace(tmp, report)
        print('exploration: %s after %.0f s simulated (%.0f s wall), %.1f%% of the reachable free space, walls '
              '%.1f%% within 0.1 m, %d robots on hosts of their own, %d collisions'
              % (figures.get('outcome'), figures.get('exploration_time_s', 0), wall,
                 100 * float(figures.get('coverage_of_reachable_free') or 0),
                 100 * float(figures.get('walls_within_tolerance') or 0), a.robots, figures.get('collisions', 0)))
        for name, link in figures['link'].items():
            print('  %s link: %.1f kB per simulated s, %.1f kB per wall s (both ways); messages of the stack %.1f kB '
                  'per simulated s, of the simulator %.1f; most: %s'
                  % (name, link['link_kB_per_s'] or 0.0, link['link_kB_per_wall_s'], link['stack_kB_per_s'] or 0.0,
                     link['simulator_kB_per_s'] or 0.0,
                     ', '.join('%s %.1f' % tb for tb in list(link['topics_kB_per_s'].items())[:5])))
        for o in figures.get('outages', []):
            print('  outage: %s silent from %.1f s to %s (simulated, as the base station heard it)'
                  % (o['robot'], o['from_s'], 'the end' if o['to_s'] is None else '%.1f s' % o['to_s']))
        if figures.get('robots_lost'):
            print('  the team ended without %s (lost)' % ', '.join(figures['robots_lost']))
        return 0 if figures.get('outcome') == 'complete' else 1
    except KeyboardInterrupt:
        print('multi_host: interrupted; tearing down', file=sys.stderr)
        return 130
    except RuntimeError as e:
        print('multi_host: %s' % e, file=sys.stderr)
        return 2
    finally:
        stop(procs)
        hosts.remove()


if __name__ == '__main__':
    sys.exit(main())
