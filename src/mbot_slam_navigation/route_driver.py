"""Drives a robot through a list of waypoints by steering on a pose it is given (a ground-truth
pose in the simulator): a stand-in for move_base in demos and tests of the layers below it.

Poses are (x [m], y [m], yaw [rad]) in the waypoints' frame; commands are (v [m/s], w [rad/s]).
"""
import math
from typing import Optional, Sequence, Tuple

from mbot_slam_navigation.transforms import normalize_angle

# Through the simulated home (world frame, m): the living room, the study and back, the dining room
# and the kitchen and back; every leg is a straight line clear of walls and furniture, with doors
# crossed at their centres.
HOME_TOUR = [(-1.0, -1.0), (-2.0, -2.8), (-4.2, -3.2), (-4.6, -1.5), (-3.0, -0.3), (-1.15, 0.3), (-1.15, 2.0),
             (-1.15, 0.3), (0.5, -0.3), (0.7, -2.4), (2.3, -2.4), (2.9, -3.1), (3.05, -4.6), (2.9, -3.1),
             (2.3, -2.4), (0.7, -2.4), (0.0, -0.5)]
# Around the living room twice.
LIVING_ROOM_LOOPS = [(-1.0, -1.0), (-2.0, -2.8), (-4.2, -3.2), (-4.6, -1.5), (-3.0, -0.3), (0.0, -0.3),
                     (0.3, -2.5), (-1.0, -3.2), (-2.0, -2.8), (-4.2, -3.2), (-4.6, -1.5), (-3.0, -0.3),
                     (0.0, -0.5)]


class RouteDriver:
    def __init__(self, waypoints: Sequence[Tuple[float, float]], speed: float = 0.3, turn_gain: float = 2.0,
                 max_turn: float = 0.8, reach: float = 0.15):
        self.waypoints = list(waypoints)
        self.speed, self.turn_gain, self.max_turn, self.reach = speed, turn_gain, max_turn, reach
        self.index = 0

    @property
    def done(self) -> bool:
        return self.index >= len(self.waypoints)

    def command(self, pose: Sequence[float]) -> Optional[Tuple[float, float]]:
        """The command for the robot at `pose`, or None when the last waypoint is reached. Turns in
        place while the heading is off by more than 0.4 rad, so legs stay straight."""
        while not self.done:
            wx, wy = self.waypoints[self.index]
            if math.hypot(wx - pose[0], wy - pose[1]) >= self.reach:
                break
            self.index += 1
        if self.done:
            return None
        wx, wy = self.waypoints[self.index]
        bearing = math.atan2(wy - pose[1], wx - pose[0])
        err = normalize_angle(bearing - pose[2])
        w = max(-self.max_turn, min(self.max_turn, self.turn_gain * err))
        return (self.speed if abs(err) < 0.4 else 0.0), w
