"""Two robots on two hosts of their own and a base station (tools/multi_host.py: network namespaces
joined by a bridge, one master on the base, ROS_IP on every host) explore the home together; the
team's report gives each robot's link traffic (what its stack sends apart from the simulator's
streams), and nothing of the run is left behind. Needs root
(ip netns) and the built workspace; make test runs it after the unit tests."""
import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOOL = os.path.join(ROOT, 'tools', 'multi_host.py')


def namespaces():
    out = subprocess.run(['ip', 'netns', 'list'], stdout=subprocess.PIPE, text=True).stdout
    return [line.split()[0] for line in out.splitlines() if line.startswith('mbot-')]


@pytest.mark.skipif(os.geteuid() != 0, reason='network namespaces need root (ip netns)')
def test_two_robots_on_their_own_hosts_explore_the_home(tmp_path):
    before = namespaces()
    report_dir = tmp_path / 'team'
    p = subprocess.run([sys.executable, TOOL, '--robots', '2', '--report-dir', str(report_dir),
                        '--max-duration', '900', '--timeout', '900'],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1200)
    print(p.stdout)
    assert namespaces() == before, 'namespaces left behind'
    assert p.returncode == 0, p.stdout[-3000:]
    with open(report_dir / 'report.json') as f:
        r = json.load(f)
    assert r['outcome'] == 'complete'
    assert r['hosts'] == 'separate'
    assert r['walls_within_tolerance'] >= 0.99
    assert r['coverage_of_reachable_free'] >= 0.95
    assert r['collisions'] == 0
    for name in ('robot1', 'robot2'):
        link = r['link'][name]
        # each robot's stack talked to the base over its own link: the merged map, tf, the team
        assert link['bytes'] > 100000, link
        topics = link['topics_kB_per_s']
        # only its own transforms cross (its stack's tf is in its namespace), not every robot's /tf;
        # the merged map comes as updates between whole maps
        assert '/tf' not in topics and '/%s/tf' % name in topics, topics
        assert '/map_updates' in topics, topics
        assert 0 < link['stack_kB_per_s'] < link['link_kB_per_s'], link
        assert r['per_robot'][name]['outcome'] == 'complete'
