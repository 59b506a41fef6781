"""batched_reads with a real master: a subscription read at most every `period` wakes about once
a period and loses nothing; one without a period in the same process is untouched; rospy's time
read that way keeps up with /clock and ends at its last value."""
import subprocess
import sys

import pytest

pytest.importorskip('rospy')
rosgraph = pytest.importorskip('rosgraph.masterapi')

PUBLISHER = '''
import time
import rospy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64
rospy.init_node('burst', disable_signals=True)
pubs = [rospy.Publisher(t, Float64, queue_size=None) for t in ('/batched', '/plain')]
clock = rospy.Publisher('/clock', Clock, queue_size=None)
start = time.monotonic()
while any(p.get_num_connections() == 0 for p in pubs) or clock.get_num_connections() == 0:
    time.sleep(0.01)
    if time.monotonic() - start > 30.0:
        raise SystemExit('no subscriber')
time.sleep(1.0)  # both subscriptions set up their read period meanwhile
for k in range(2000):  # 2 s at 1 kHz: the value is the wall time it was sent at
    for p in pubs:
        p.publish(Float64(time.time()))
    clock.publish(Clock(rospy.Time(100 + k // 1000, (k % 1000) * 1000000)))
    time.sleep(0.001)
print('sent', flush=True)
time.sleep(5.0)
'''

SUBSCRIBER = '''
import time
import rospy
from std_msgs.msg import Float64
from mbot_slam_navigation.batched_reads import clock_at_most_every, read_at_most_every
rospy.init_node('reader', disable_signals=True)
got = {'/batched': [], '/plain': []}
subs = [rospy.Subscriber(t, Float64, lambda m, t=t: got[t].append((time.time(), m.data)), queue_size=None)
        for t in got]
read_at_most_every(subs[0], 0.05)
print('clock', clock_at_most_every(0.05), flush=True)
times = []
start = time.monotonic()
while time.monotonic() - start < 25.0 and len(got['/plain']) < 2000:
    times.append(rospy.Time.now())
    time.sleep(0.002)
time.sleep(0.5)
times.append(rospy.Time.now())
for t, rx in got.items():
    lag = max(r - s for r, s in rx) if rx else -1
    wakes = 1 + sum(1 for a, b in zip(rx, rx[1:]) if b[0] - a[0] > 0.0005)
    print(t, len(rx), wakes, '%.3f' % lag, flush=True)
print('back', sum(1 for a, b in zip(times, times[1:]) if b < a), flush=True)
print('last', times[-1].to_nsec(), flush=True)
'''


def test_a_batched_subscription_wakes_once_a_period_and_keeps_every_message(ros_master):
    env = ros_master
    procs = []
    try:
        master_api = rosgraph.Master('/probe', master_uri=env['ROS_MASTER_URI'])
        master_api.setParam('/use_sim_time', True)
        procs.append(subprocess.Popen([sys.executable, '-c', PUBLISHER], env=env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL))
        out = subprocess.run([sys.executable, '-c', SUBSCRIBER], env=env, capture_output=True, text=True,
                             timeout=90).stdout
        lines = dict(line.split(' ', 1) for line in out.splitlines() if ' ' in line)
        assert lines.get('clock') == 'True', out
        n, wakes, lag = lines['/batched'].split()
        # every message, in about 2 s / 0.05 s wake-ups (not 2000), each at most a period (and the
        # machine's scheduling) late
        assert int(n) == 2000, out
        assert int(wakes) <= 80, out
        assert float(lag) < 0.05 + 0.5, out
        n, wakes, _ = lines['/plain'].split()
        assert int(n) == 2000 and int(wakes) > 200, out  # the same process's other subscription: untouched
        assert lines['back'] == '0', out  # time never went back
        assert int(lines['last']) == 101999000000, out  # and ended at the last /clock message
    finally:
        for p in procs:
            p.terminate()
            p.wait()
