"""The real rviz on a virtual display (Xvfb), as a user sees it: screenshots (ImageMagick's import),
clicks and keys (xdotool), and what a screenshot of urdf/navigation.rviz shows.

navigation.rviz looks straight down (TopDownOrtho) at (VIEW_X, VIEW_Y) in the map frame with
VIEW_SCALE pixels per metre, so a map point's pixel follows from the centre of the render area,
which is found by its background colour.
"""
import os
import subprocess
import sys
import time
from typing import Optional, Tuple

import cv2
import numpy as np

VIEW_X, VIEW_Y, VIEW_SCALE = -1.5, -1.2, 40.0  # urdf/navigation.rviz: Views/Current
BACKGROUND = 48                                # Background Color: 48; 48; 48


def artifact_dir() -> str:
    """Where a rostest keeps pictures and maps for people to look at: beside its result file
    (rostest passes --gtest_output=xml:FILE), else $ROS_HOME/test_artifacts."""
    for a in sys.argv:
        if a.startswith('--gtest_output=xml:'):
            d = os.path.join(os.path.dirname(a.split(':', 1)[1]), 'artifacts')
            break
    else:
        d = os.path.join(os.environ.get('ROS_HOME', os.path.expanduser('~/.ros')), 'test_artifacts')
    os.makedirs(d, exist_ok=True)
    return d


class RosoutFile:
    """Every node's /rosout lines of at least `level` (rosgraph_msgs/Log: 2 INFO, 4 WARN) appended to
    `path` as they come, with the ROS time, so that a failed run in CI leaves what move_base, amcl
    and slam_gmapping said beside the test's result (rostest keeps output="screen" nodes' lines only
    in its own stdout)."""

    def __init__(self, path: str, level: int = 2):
        import rospy
        from rosgraph_msgs.msg import Log
        self.level = level
        self.file = open(path, 'w', buffering=1)
        self.sub = rospy.Subscriber('/rosout', Log, self.on_log, queue_size=500)

    def on_log(self, msg) -> None:
        if msg.level >= self.level and not self.file.closed:
            self.file.write('[%d] [%.2f] %s: %s\n' % (msg.level, msg.header.stamp.to_sec(), msg.name, msg.msg))

    def close(self) -> None:
        self.sub.unregister()
        self.file.close()


class RvizScreen:
    def __init__(self, config: str, log_path: str, size=(1400, 1000)):
        self.xvfb = subprocess.Popen(['Xvfb', '-displayfd', '1', '-screen', '0', '%dx%dx24' % size, '-nolisten', 'tcp'],
                                     stdout=subprocess.PIPE)
        self.display = ':' + self.xvfb.stdout.readline().decode().strip()
        self.env = dict(os.environ, DISPLAY=self.display)
        self.log = open(log_path, 'w')
        self.rviz = subprocess.Popen(['rosrun', 'rviz', 'rviz', '-d', config], env=self.env, stdout=self.log,
                                     stderr=subprocess.STDOUT)

    def alive(self) -> bool:
        return self.rviz.poll() is None

    def shot(self, path: str) -> np.ndarray:
        subprocess.run(['import', '-display', self.display, '-window', 'root', path], check=True, timeout=30)
        img = cv2.imread(path)
        assert img is not None, 'no screenshot in %s' % path
        return img

    def xdotool(self, *args) -> None:
        subprocess.run(['xdotool'] + [str(a) for a in args], env=self.env, check=True, timeout=30)

    def close(self) -> None:
        for p in (self.rviz, self.xvfb):
            if p.poll() is None:
                p.terminate()
                try:
                    p.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    p.kill()
        self.log.close()


def render_area(img: np.ndarray) -> Optional[Tuple[int, int, int, int]]:
    """(x0, y0, x1, y1) of rviz's 3D view: the largest region of background colour, or None."""
    bg = np.all(np.abs(img.astype(np.int16) - BACKGROUND) <= 2, axis=2).astype(np.uint8)
    n, _, stats, _ = cv2.connectedComponentsWithStats(bg, connectivity=4)
    if n < 2:
        return None
    i = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    x, y, w, h, area = stats[i]
    if area < 10000:
        return None
    return int(x), int(y), int(x + w), int(y + h)


def to_pixel(area, wx: float, wy: float) -> Tuple[int, int]:
    """Screen pixel (column, row) of the map point (wx, wy) [m]."""
    cx, cy = (area[0] + area[2]) / 2.0, (area[1] + area[3]) / 2.0
    return int(round(cx + (wx - VIEW_X) * VIEW_SCALE)), int(round(cy - (wy - VIEW_Y) * VIEW_SCALE))


def crop(img: np.ndarray, area) -> np.ndarray:
    return img[area[1]:area[3], area[0]:area[2]].astype(np.int16)


def map_free_pixels(img: np.ndarray, area) -> int:
    """Pixels drawn as free map cells: white at the Map display's alpha 0.8 over the background."""
    v = crop(img, area)
    b, g, r = v[..., 0], v[..., 1], v[..., 2]
    return int(np.count_nonzero((np.abs(r - 214) <= 12) & (np.abs(g - r) <= 6) & (np.abs(b - r) <= 6)))


def laser_pixels(img: np.ndarray, area) -> int:
    """Pixels of the LaserScan display (flat red squares; nothing else is drawn pure red)."""
    v = crop(img, area)
    return int(np.count_nonzero((v[..., 2] > 200) & (v[..., 1] < 60) & (v[..., 0] < 60)))


def robot_pixels(img: np.ndarray, area, wx: float, wy: float, radius_m: float = 0.25) -> int:
    """Pixels of the mbot's blue base within radius_m of the map point (wx, wy)."""
    u, v = to_pixel(area, wx, wy)
    r = int(round(radius_m * VIEW_SCALE))
    patch = img[max(v - r, 0):v + r + 1, max(u - r, 0):u + r + 1].astype(np.int16)
    return int(np.count_nonzero((patch[..., 0] > 120) & (patch[..., 1] < 50) & (patch[..., 2] < 50)))


def wait_for(predicate, timeout: float, period: float = 2.0):
    """Calls predicate() until it returns something true or timeout [s, wall] passes; returns the last value."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value or time.monotonic() > deadline:
            return value
        time.sleep(period)
