"""Fixtures shared by the pytests: a real ROS master on a free port, for tests that run rospy
nodes as subprocesses."""
import os
import socket
import subprocess
import time

import pytest


@pytest.fixture
def ros_master(tmp_path):
    """The environment (ROS_MASTER_URI, ROS_HOME) of a rosmaster started for this test on a free
    port, up and answering (within 10 s); terminated afterwards."""
    rosgraph = pytest.importorskip('rosgraph.masterapi')
    with socket.socket() as s:
        s.bind(('localhost', 0))
        port = s.getsockname()[1]
    env = dict(os.environ, ROS_MASTER_URI='http://localhost:%d' % port, ROS_HOME=str(tmp_path))
    master = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, env=env)
    try:
        for _ in range(100):
            try:
                rosgraph.Master('/probe', master_uri=env['ROS_MASTER_URI']).getPid()
                break
            except OSError:
                time.sleep(0.1)
        else:
            pytest.fail('rosmaster on port %d did not answer within 10 s' % port)
        yield env
    finally:
        master.terminate()
        master.wait()
