#!/usr/bin/env python3
"""The CPU a rospy node pays in a simulated run before it does anything of its own: rospy's /clock
subscription (under /use_sim_time every rospy node has one; the simulator publishes 100 Hz of
simulated time) and, with --tf, a /tf subscription as the explorer's (LazyTransformBuffer: raw
messages queued, nothing deserialized). bench_explore.py runs one of each beside every exploration,
so that the explorer's CPU per simulated second can be read against what any rospy node there pays.

Usage: rospy_floor.py OUT.json [--tf]. Waits (up to --wait wall s) for the master and /use_sim_time,
then for the simulated clock to start; from then on rewrites OUT.json every 2 wall s with
{"sim_s", "cpu_s", "cpu_s_per_sim_s"} until it is terminated.
"""
import argparse
import json
import os
import sys
import tempfile
import time

import rosgraph


def write_atomically(path, data):
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(os.path.abspath(path)), prefix='.floor')
    with os.fdopen(fd, 'w') as f:
        json.dump(data, f)
    os.replace(tmp, path)


def wait_for(what, test, deadline):
    while not test():
        if time.monotonic() > deadline:
            sys.exit('rospy_floor: no %s at %s after waiting; giving up' % (what, rosgraph.get_master_uri()))
        time.sleep(0.2)


def sim_time_set():
    try:
        return rosgraph.Master('/rospy_floor').hasParam('/use_sim_time')
    except Exception:  # the master is not up yet (socket errors, or an HTTP error from another server)
        return False


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('out')
    ap.add_argument('--tf', action='store_true', help='also subscribe to /tf as the explorer does')
    ap.add_argument('--wait', type=float, default=300.0, help='[wall s] for the master and the clock')
    args = ap.parse_args(argv)
    deadline = time.monotonic() + args.wait
    wait_for('ROS master with /use_sim_time', sim_time_set, deadline)  # read by init_node
    import rospy
    rospy.init_node('rospy_floor_tf' if args.tf else 'rospy_floor', anonymous=True, disable_signals=True)
    if args.tf:
        from mbot_slam_navigation.lazy_tf import LazyTransformBuffer
        buffer = LazyTransformBuffer()  # noqa: F841 (subscribes; never looked up, as nothing asks it)
    wait_for('simulated clock', lambda: not rospy.Time.now().is_zero(), deadline)
    sim0, cpu0 = rospy.Time.now().to_sec(), time.process_time()
    while True:
        time.sleep(2.0)
        sim, cpu = rospy.Time.now().to_sec() - sim0, time.process_time() - cpu0
        if sim > 0:
            write_atomically(args.out, {'sim_s': sim, 'cpu_s': cpu, 'cpu_s_per_sim_s': cpu / sim})


if __name__ == '__main__':
    main()
