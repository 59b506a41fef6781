"""gui:=true: a top-down OpenCV window of the world, the people, the robots' footprints and their laser rays."""
import math

import cv2
import numpy as np

from mbot_slam_navigation.sim.ground_truth import draw_solids
from mbot_slam_navigation.sim.sdf_world import World
from mbot_slam_navigation.sim.simulation import GROUND_CLEARANCE, Simulation


class TopDownViewer:
    """Shapes that a body up to BODY_HEIGHT meets are dark; higher ones (lintels, shelves) light grey:
    robots pass under them and lasers at the usual heights do not see them."""

    BODY_HEIGHT = 0.5  # [m]

    def __init__(self, world: World, pixels_per_m: float = 50.0, window: str = 'gazebo_sim'):
        b = world.bounds() or (-5.0, -5.0, 5.0, 5.0)
        self.lo = np.array(b[:2]) - 0.5
        self.scale = pixels_per_m
        size = ((np.array(b[2:]) + 0.5 - self.lo) * pixels_per_m).astype(int)
        self.window = window
        self.background = np.full((size[1], size[0], 3), 255, np.uint8)
        low = world.blocking(GROUND_CLEARANCE, self.BODY_HEIGHT)
        high = World(world.name, [s for s in world.shapes if not s.blocks(GROUND_CLEARANCE, self.BODY_HEIGHT)])
        for part, colour in ((high, (200, 200, 200)), (low, (60, 60, 60))):
            if part.shapes:
                mask = draw_solids(part, tuple(self.lo), (size[1], size[0]), 1.0 / pixels_per_m)[::-1]
                self.background[mask > 0] = colour

    def px(self, points):
        p = (np.asarray(points, float) - self.lo) * self.scale
        p[:, 1] = self.background.shape[0] - p[:, 1]  # image rows grow downwards, y grows north
        return p.astype(np.int32)

    def draw(self, sim: Simulation) -> None:
        img = self.background.copy()
        for robot in sim.robots.values():
            for laser in robot.lasers:
                ranges = sim.scan(robot, laser)
                x, y, yaw = robot.laser_pose(laser)
                s = laser.spec
                for i in range(0, len(ranges), max(1, len(ranges) // 90)):
                    r = ranges[i] if math.isfinite(ranges[i]) else s.range_max
                    a = yaw + s.angle_min + i * s.angle_increment
                    p = self.px([(x, y), (x + r * math.cos(a), y + r * math.sin(a))])
                    cv2.line(img, tuple(p[0]), tuple(p[1]), (80, 80, 255), 1)
            cv2.polylines(img, [self.px(robot.drive.footprint_in_world())], True, (200, 120, 0), 2)
        for person in sim.people.values():
            x, y, yaw = person.pose
            c = self.px([(x, y), (x + person.actor.radius * math.cos(yaw), y + person.actor.radius * math.sin(yaw))])
            cv2.circle(img, tuple(c[0]), int(person.actor.radius * self.scale), (40, 140, 230), -1)
            cv2.line(img, tuple(c[0]), tuple(c[1]), (0, 60, 120), 2)  # which way the person faces
        cv2.imshow(self.window, img)
        cv2.waitKey(1)
