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


@dataclass
class Outage:
    """A robot the base station did not hear from: from its last word to its next [s, the team's
    clock from its start]; `until` None while it is still silent."""
    robot: str
    since: float
    until: Optional[float] = None

    def as_dict(self, origin: float = 0.0) -> dict:
        """For the team's report, times from `origin` [s]."""
        return {'robot': self.robot, 'from_s': round(self.since - origin, 1),
                'to_s': None if self.until is None else round(self.until - origin, 1),
                'silent_s': None if self.until is None else round(self.until - self.since, 1)}


class TeamWatch:
    """What the base station hears of each robot (its explorer's state, ~team_topic, said every
    second), ROS-free: a robot silent for more than `silence` [s] is in an outage (its link or its
    host is down) until it is heard again; one silent for `lost_after` [s] is lost, and the team
    does not wait for it once every other robot has ended. Times in seconds of the team's clock."""

    def __init__(self, names: Sequence[str], silence: float = 5.0, lost_after: float = 60.0):
        self.names = list(names)
        self.silence, self.lost_after = silence, lost_after
        self.heard = {}       # robot -> when last heard
        self.outages: List[Outage] = []
        self.open = {}        # robot -> its outage still going on

    def hear(self, robot: str, now: float) -> Optional[Outage]:
        """The robot said something at `now`; returns the outage it ends, if it was in one."""
        if robot not in self.names:
            return None
        self.heard[robot] = now
        ended = self.open.pop(robot, None)
        if ended is not None:
            ended.until = now
        return ended

    def check(self, now: float, ended: Sequence[str] = ()) -> List[Outage]:
        """The outages that begin by `now` (robots heard before, silent since for more than
        `silence`, and not `ended`: an explorer that has ended stops talking)."""
        begun = []
        # a copy: hear() runs in the subscriber's thread and may add a robot meanwhile
        for robot, last in list(self.heard.items()):
            if robot in ended or robot in self.open or now - last <= self.silence:
                continue
            outage = Outage(robot, last)
            self.open[robot] = outage
            self.outages.append(outage)
            begun.append(outage)
        return begun

    def lost(self, now: float, ended: Sequence[str] = ()) -> List[str]:
        """Robots not `ended` that have been silent for `lost_after` (heard once at least)."""
        return [r for r, o in sorted(self.open.items()) if r not in ended and now - o.since >= self.lost_after]

    def team_ends_without(self, now: float, ended: Sequence[str]) -> List[str]:
        """The lost robots, when every other robot has ended (the team ends without them), else []."""
        lost = self.lost(now, ended)
        if lost and all(n in ended or n in lost for n in self.names):
            return lost
        return []
