"""Getting a stuck robot out, ROS-free: the explorer's last resort when move_base's recoveries cannot
turn or back the robot (its costmap has it boxed in). The robot drove in, so its own recent path
is a way out: it drives straight back to a point of that path, forwards or backwards, whichever
faces the point, and checks its laser (the truth) rather than the costmap.

Poses are (x, y, yaw) [m, rad] in the map frame; scan points (x, y) [m] in the robot's base frame.
"""
import math
from typing import Optional, Sequence, Tuple

import numpy as np


def backtrack_target(path: Sequence[Tuple[float, float]], robot: Tuple[float, float],
                     distance: float) -> Optional[Tuple[float, float]]:
    """The point of the driven path (oldest first), walking back from its end, that is first
    `distance` [m] from the robot in a straight line; None if the path never gets that far."""
    for x, y in reversed(list(path)):
        if math.hypot(x - robot[0], y - robot[1]) >= distance:
            return float(x), float(y)
    return None


def escape_command(pose: Tuple[float, float, float], target: Tuple[float, float], points: np.ndarray,
                   radius: float, speed: float, arrive: float = 0.1, clearance: float = 0.02,
                   lookahead: float = 0.1, turn_in_place: float = 0.6) -> Tuple[Optional[Tuple[float, float]], str]:
    """((v [m/s], w [rad/s]), '') to drive for target, or (None, 'arrived') / (None, why blocked).

    The robot is about a disc of `radius` (the mbot; its wheels stand out a few millimetres): it
    turns in place until forwards or backwards (whichever needs less turning) faces the target within
    turn_in_place [rad], then drives, steering towards it. Turning is blocked when a laser point lies
    within radius + clearance of its centre (a wheel would sweep it). Driving is blocked when a laser
    point lies within radius + clearance of where it would be after `lookahead` metres and nearer to
    that than it is now: moving away from what is already close (the wall it was wedged against) is
    allowed."""
    dx, dy = target[0] - pose[0], target[1] - pose[1]
    if math.hypot(dx, dy) < arrive:
        return None, 'arrived'
    c, s = math.cos(pose[2]), math.sin(pose[2])
    tx, ty = c * dx + s * dy, -s * dx + c * dy  # target in the base frame
    direction = 1.0 if tx >= 0 else -1.0
    error = math.atan2(ty * direction, tx * direction)  # heading error of the travel direction
    w = max(-0.5, min(0.5, 1.5 * error))  # turns the travel direction (backwards too) towards it
    pts = np.asarray(points, float).reshape(-1, 2)
    if abs(error) > turn_in_place:
        if len(pts) and np.any(np.hypot(pts[:, 0], pts[:, 1]) < radius + clearance):
            return None, 'the laser sees an obstacle beside the robot: turning on the spot would touch it'
        return (0.0, 0.5 if error > 0 else -0.5), ''
    v = direction * speed * max(0.3, math.cos(error))
    if len(pts):
        d_now = np.hypot(pts[:, 0], pts[:, 1])
        d_new = np.hypot(pts[:, 0] - direction * lookahead, pts[:, 1])
        if np.any((d_new < radius + clearance) & (d_new < d_now - 1e-3)):
            return None, 'the laser sees an obstacle %s the robot' % ('in front of' if direction > 0 else 'behind')
    return (v, w), ''
