"""A team's explorers sharing the frontiers, ROS-free (explore's ~team_topic): a frontier whose
goal a teammate heads for is left to it, and one nearer to a teammate costs more."""
import math
from dataclasses import dataclass, replace
from typing import List, Optional, Sequence, Tuple

from mbot_slam_navigation.nav.frontiers import Frontier


@dataclass
class Teammate:
    """Another explorer of the team, as it last said (explore's ~team_topic)."""
    name: str
    position: Tuple[float, float]           # [m] global frame
    goal: Optional[Tuple[float, float]]     # its frontier goal, None without one


def share_out(frontiers: List[Frontier], mates: Sequence[Teammate], claim_radius: float = 2.0,
              potential_scale: float = 3.0) -> Tuple[List[Frontier], int]:
    """(this robot's frontiers, best first; how many are left to teammates) for a team exploring
    together.

    A frontier whose goal lies within claim_radius [m] of a teammate's goal is that teammate's. The
    others cost potential_scale times the metres by which this robot's path to them is longer than
    a teammate's straight-line distance: a robot leaves the frontiers nearer to the others, so the
    team spreads out. Two robots that chose the same place keep it for the one whose name sorts
    first (yields_goal)."""
    mine, claimed = [], 0
    for f in frontiers:
        if any(m.goal is not None and math.hypot(f.goal[0] - m.goal[0], f.goal[1] - m.goal[1]) < claim_radius
               for m in mates):
            claimed += 1
            continue
        nearest = min((math.hypot(f.goal[0] - m.position[0], f.goal[1] - m.position[1]) for m in mates),
                      default=math.inf)
        penalty = potential_scale * max(0.0, f.path_m - nearest)
        mine.append(replace(f, cost=f.cost + penalty) if penalty > 0 else f)
    mine.sort(key=lambda f: f.cost)
    return mine, claimed


def yields_goal(goal: Tuple[float, float], me: str, mates: Sequence[Teammate], claim_radius: float = 2.0) -> bool:
    """True if a teammate whose name sorts before `me` heads for a goal within claim_radius of ours."""
    return any(m.goal is not None and m.name < me and math.hypot(goal[0] - m.goal[0], goal[1] - m.goal[1]) < claim_radius
               for m in mates)
