"""run_exploration (make demo's runner), with a stand-in for roslaunch on PATH: a script that
starts a "node" child, writes the report after a moment and runs until it is interrupted, as
roslaunch does. What is checked is the runner's own behaviour: it waits for the report, ends the
launch cleanly, reports the nodes' CPU, prints one outcome line and exits 0 only for complete."""
import os
import stat
import sys
import time

import pytest

from mbot_slam_navigation import exploration_run

FAKE_ROSLAUNCH = r'''#!/usr/bin/env python3
import json, os, signal, subprocess, sys, time
args = dict(a.split(':=', 1) for a in sys.argv[1:] if ':=' in a)
life = 1 if args.get('mode') == 'explorer_dies' else 60
# The "node" spins for 0.3 s of its own CPU time (not of wall time: on a loaded machine that gave
# it as little as 0.14 s) and says so in a file, then idles.
spun = os.path.join(args['report_dir'], 'spun')
node = subprocess.Popen([sys.executable, '-c', 'import time\nt=time.process_time()\nwhile time.process_time()-t<0.3: pass\n'
                         'open(%r, "w").close()\ntime.sleep(%d)' % (spun, life), '__name:=explore'])
def bye(*_):
    node.terminate(); node.wait()
    open(os.path.join(args['report_dir'], 'stopped'), 'w').write('SIGINT')
    sys.exit(0)
signal.signal(signal.SIGINT, bye)
if args.get('mode') == 'die':
    sys.exit(3)
time.sleep(1.0)
deadline = time.time() + 20.0  # the report comes after the node's spin, as a real explorer's after its work
while not os.path.exists(spun) and time.time() < deadline:
    time.sleep(0.05)
if args.get('mode') not in ('hang', 'explorer_dies'):
    tmp = os.path.join(args['report_dir'], '.r.tmp')
    json.dump({'outcome': args.get('outcome', 'complete'), 'exploration_time_s': 12.0, 'wall_time_s': 1.0,
               'collisions': 0, 'given_up': []}, open(tmp, 'w'))
    os.replace(tmp, os.path.join(args['report_dir'], 'report.json'))
time.sleep(60)
'''


@pytest.fixture
def fake_launch(tmp_path, monkeypatch):
    bin_dir = tmp_path / 'bin'
    bin_dir.mkdir()
    script = bin_dir / 'roslaunch'
    script.write_text(FAKE_ROSLAUNCH.replace('#!/usr/bin/env python3', '#!' + sys.executable))
    script.chmod(script.stat().st_mode | stat.S_IEXEC)
    monkeypatch.setenv('PATH', '%s:%s' % (bin_dir, os.environ['PATH']))
    report = tmp_path / 'report'
    report.mkdir()
    return report


def test_waits_for_the_report_then_stops_the_launch_cleanly(fake_launch):
    (fake_launch / 'report.json').write_text('{"outcome": "stale"}')  # an earlier run's: ignored
    t0 = time.monotonic()
    r = exploration_run.run(['pkg', 'x.launch', 'report_dir:=%s' % fake_launch], wall_timeout=30.0)
    assert r['outcome'] == 'complete'
    assert time.monotonic() - t0 < 20.0
    assert (fake_launch / 'stopped').read_text() == 'SIGINT'   # ended by SIGINT, as Ctrl-C ends roslaunch
    assert r['node_cpu_s']['explore'] >= 0.2                    # the child that spun 0.3 s


@pytest.mark.parametrize('outcome, status', [('complete', 0), ('timeout', 1), ('stuck', 1)])
def test_one_outcome_line_and_the_exit_status(fake_launch, capsys, outcome, status):
    with pytest.raises(SystemExit) as e:
        exploration_run.main(['--', 'pkg', 'x.launch', 'report_dir:=%s' % fake_launch, 'outcome:=%s' % outcome])
    assert e.value.code == status
    lines = [l for l in capsys.readouterr().out.splitlines() if l.startswith('exploration: ')]
    assert len(lines) == 1 and lines[0].startswith('exploration: %s after 12 s simulated' % outcome)


def test_no_report_ends_with_a_message_and_status_2(fake_launch, capsys):
    with pytest.raises(SystemExit) as e:
        exploration_run.main(['pkg', 'x.launch', 'report_dir:=%s' % fake_launch, 'mode:=die'])
    assert e.value.code == 2
    assert 'roslaunch ended (exit 3) before the explorer wrote' in capsys.readouterr().out
    with pytest.raises(SystemExit) as e:
        exploration_run.main(['--wall-timeout', '3', 'pkg', 'x.launch', 'report_dir:=%s' % fake_launch, 'mode:=hang'])
    assert e.value.code == 2
    assert 'no report after 3 s of wall time' in capsys.readouterr().out
    assert (fake_launch / 'stopped').exists()  # the hanging launch was stopped, not left running


def test_an_explorer_that_dies_without_a_report_ends_the_run_at_once(fake_launch, capsys):
    # the explorer died (an exception) and roslaunch ran on: not an hour's wait for the report
    t0 = time.monotonic()
    with pytest.raises(SystemExit) as e:
        exploration_run.main(['--wall-timeout', '120', 'pkg', 'x.launch', 'report_dir:=%s' % fake_launch,
                              'mode:=explorer_dies'])
    assert e.value.code == 2
    assert time.monotonic() - t0 < 30.0
    assert 'explore ended without writing' in capsys.readouterr().out
    assert (fake_launch / 'stopped').exists()


def test_report_dir_is_required():
    with pytest.raises(SystemExit, match='report_dir'):
        exploration_run.run(['pkg', 'x.launch'], wall_timeout=1.0)


def test_a_master_that_already_runs_a_simulation_is_not_joined(fake_launch, capsys):
    # Two benches on one port: roslaunch would join the first one's master, and the second
    # simulation would take over the first one's node names and publish a second /clock.
    import socket
    import subprocess
    rosgraph = pytest.importorskip('rosgraph.masterapi')
    with socket.socket() as s:
        s.bind(('localhost', 0))
        port = s.getsockname()[1]
    uri = 'http://localhost:%d' % port
    assert exploration_run.running_simulation(uri) is None  # nothing there: roslaunch starts its own
    master = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
    try:
        for _ in range(100):
            try:
                rosgraph.Master('/probe', master_uri=uri).getPid()
                break
            except OSError:
                time.sleep(0.1)
        assert exploration_run.running_simulation(uri) is None  # a bare master (a user's roscore): joined
        rosgraph.Master('/gazebo', master_uri=uri).registerPublisher('/clock', 'rosgraph_msgs/Clock',
                                                                     'http://localhost:1/')
        assert exploration_run.running_simulation(uri) == '/gazebo'
        r = exploration_run.run(['-p', str(port), 'pkg', 'x.launch', 'report_dir:=%s' % fake_launch],
                                wall_timeout=30.0)
        assert r is None
        assert 'already has a node /gazebo' in capsys.readouterr().out
        assert not (fake_launch / 'stopped').exists()  # roslaunch was never started
    finally:
        master.terminate()
        master.wait()
