"""gui:=true: a top-down OpenCV window of the world, the people, the robots' footprints and their laser rays."""
import math

import cv2
import numpy as np

from mbot_slam_navigation.sim.simulation import Simulation


class TopDownViewer:
    def __init__(self, world, pixels_per_m: float = 50.0, window: str = 'gazebo_sim'):
        b = world.bounds() or (-5.0, -5.0, 5.0, 5.0)
        self.lo = np.array(b[:2]) - 0.5
        self.scale = pixels_per_m
        size = ((np.array(b[2:]) + 0.5 - self.lo) * pixels_per_m).astype(int)
        self.window = window
        self.background = np.full((size[1], size[0], 3), 255, np.uint8)
        for s in world.shapes:
            if s.kind == 'box':
                c, si = math.cos(s.yaw), math.sin(s.yaw)
                corners = [(s.x + c * a * s.size_x / 2 - si * b_ * s.size_y / 2,
                            s.y + si * a * s.size_x / 2 + c * b_ * s.size_y / 2)
                           for a, b_ in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
                cv2.fillPoly(self.background, [self.px(corners)], (60, 60, 60))
            else:
                cv2.circle(self.background, tuple(self.px([(s.x, s.y)])[0]), int(s.radius * self.scale), (60, 60, 60), -1)

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
