"""What the explorer decides between planning cycles, ROS-free: which goal to keep or change
(ExploreState: hysteresis, blacklisting of failed goals, places given up), how long the robot has
stood still (MotionWatch) and the longest stretch without new explored area (Plateau). Times are
seconds of ROS time, positions metres in the map frame."""
import math
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Tuple, Union

import numpy as np

from mbot_slam_navigation.nav.frontiers import CURRENT_RADIUS, Frontier, GivenUp

ELIGIBLE, WAITING = 'eligible', 'waiting'  # ExploreState.screener's verdicts (or a GivenUp)


@dataclass
class Blacklisted:
    """A place not to send the robot to: a goal reached (for good), or goals that failed on one
    frontier (until `until`, for good after max_tries)."""
    goals: List[Tuple[float, float]]  # [m] the goals sent there (map frame)
    until: float                      # [s] when it may be tried again
    tries: int                        # how many times a goal here failed
    cells: Optional[np.ndarray] = None  # (N, 2) [m] the frontier's cells then (None: its frontier vanished)
    size_m: float = 0.0
    why: str = ''                     # the last failure's reason
    reached: bool = False             # the robot got to the goal (not a failure)
    _box: Tuple = field(default=(0, None, None), repr=False, compare=False)  # (len(cells), lo, hi) cached

    def box(self) -> Tuple[np.ndarray, np.ndarray]:
        """(lower, upper) corners [m] of its cells' bounding box (cells grow by concatenation only)."""
        if self._box[0] != len(self.cells):
            self._box = (len(self.cells), self.cells.min(axis=0), self.cells.max(axis=0))
        return self._box[1], self._box[2]


def _near_fraction(a: np.ndarray, b: np.ndarray, distance: float) -> float:
    """Fraction of the points of a within `distance` [m] of some point of b."""
    if len(a) == 0 or len(b) == 0:
        return 0.0
    # most pairs lie far apart (a frontier and a place blacklisted across the floor): their boxes tell
    if np.any(a.min(axis=0) > b.max(axis=0) + distance) or np.any(b.min(axis=0) > a.max(axis=0) + distance):
        return 0.0
    step = max(1, len(b) // 400)  # a subsample of b is enough at cell spacing; bounds the cost
    bb = b[::step]
    near = np.zeros(len(a), bool)
    for i in range(0, len(a), 512):
        chunk = a[i:i + 512]
        d2 = (chunk[:, None, 0] - bb[None, :, 0]) ** 2 + (chunk[:, None, 1] - bb[None, :, 1]) ** 2
        near[i:i + 512] = d2.min(axis=1) <= (distance + step * 0.05) ** 2
    return float(near.mean())


@dataclass
class ExploreState:
    """What the explorer decides between planning cycles. Times are seconds of ROS time."""
    progress_timeout: float = 30.0    # [s] without moving progress_distance: the goal is given up
    progress_distance: float = 0.2    # [m]
    blacklist_timeout: float = 60.0   # [s] before a failed goal may be tried again
    max_tries: int = 2                # failures after which a place stays blacklisted
    blacklist_radius: float = 0.6     # [m] around a failed or visited goal
    same_frontier_overlap: float = 0.5  # fraction of cells within 0.3 m that makes two frontiers one
    hysteresis: float = 1.0           # [cost] a new frontier must beat the current goal's by this
    settle_time: float = 10.0         # [s] at most to wait for a map made after a goal was reached
    max_goals_per_place: int = 5      # new goals within blacklist_radius of one place before it is given up
    switch_back_after: float = 60.0   # [s] before a goal left for a better one may beat the current goal
    goal: Optional[Frontier] = None
    progress_at: Tuple[float, float] = (math.nan, math.nan)
    progress_time: float = 0.0
    blacklist: List[Blacklisted] = field(default_factory=list)
    goals_chosen: int = 0             # new goals (a goal that moved with its frontier is not new)
    places: List[List[float]] = field(default_factory=list)  # [x, y, new goals sent there]
    why: str = ''                     # why choose() last chose a new goal (for the log)
    left: List[Tuple[float, float, float]] = field(default_factory=list)  # [x, y, when] goals left for better ones

    def avoid(self, now: float) -> List[Tuple[float, float]]:
        """Places whose frontier cells do not count now (rank_frontiers' avoid): goals reached, and
        goals that failed while blacklisted (for good after max_tries)."""
        return [g for b in self.blacklist if b.reached or b.until > now or b.tries >= self.max_tries for g in b.goals]

    def avoid_for_good(self) -> List[Tuple[float, float]]:
        """Places whose frontier cells never count again: goals that failed max_tries times. Cells
        near a goal reached are left out only while other frontiers remain (so that the robot does
        not turn back to a place it has been, where the map flickers); when nothing else is left,
        they are what there is to explore (a room seen only from its door whose frontier came back
        when the map was corrected). max_goals_per_place bounds the trips there."""
        return [g for b in self.blacklist if not b.reached and b.tries >= self.max_tries for g in b.goals]

    def avoid_goals(self, now: float) -> List[Tuple[float, float]]:
        """Goals that may not be sent now (rank_frontiers' avoid_goals): those that failed, while
        blacklisted, and those the robot stood at with its frontier still there. From where the robot
        stood, it saw that frontier as it is; the same spot shows nothing more, so the frontier's next
        goal lies at least blacklist_radius away (measured: the home's kitchen, a shadow beside its
        door seen from the doorway, got its goal in the doorway five times and was given up, 66%
        mapped)."""
        return [g for b in self.blacklist if b.cells is not None
                and (b.reached or b.until > now or b.tries >= self.max_tries) for g in b.goals]

    def _same_place(self, b: Blacklisted, f: Frontier, near_goal: Optional[bool] = None) -> bool:
        """`near_goal`: whether f's goal lies within blacklist_radius of one of b's goals, if the
        caller knows (screen works it out for all places at once)."""
        if b.cells is None:
            return False
        # A goal near a failed one is the same place; near a reached one it may see more: there
        # only the same cells make the same frontier.
        if near_goal is None:
            near_goal = any(math.hypot(f.goal[0] - x, f.goal[1] - y) < self.blacklist_radius for x, y in b.goals)
        if not b.reached and near_goal:
            return True
        return (_near_fraction(f.cells, b.cells, 0.3) >= self.same_frontier_overlap or
                _near_fraction(b.cells, f.cells, 0.3) >= self.same_frontier_overlap)

    def screen(self, now: float, frontiers: List[Frontier],
               map_time: float = math.inf) -> Tuple[List[Frontier], int, List[GivenUp]]:
        """(frontiers that may be sent now, how many wait, those given up for good): screener's
        judgement of each."""
        judge = self.screener(now, map_time)
        eligible, waiting, given_up = [], 0, []
        for f in frontiers:
            verdict = judge(f)
            if verdict is ELIGIBLE:
                eligible.append(f)
            elif verdict is WAITING:
                waiting += 1
            else:
                given_up.append(verdict)
        return eligible, waiting, given_up

    def screener(self, now: float, map_time: float = math.inf) -> Callable[[Frontier], Union[str, GivenUp]]:
        """A judge of frontiers by the failures recorded: ELIGIBLE (may be sent now), WAITING, or
        given up for good (a GivenUp, with why). A frontier that is the place of a failed goal (its
        goal near that goal, or most of its cells near the failed frontier's cells, however it has
        grown or shrunk since) waits blacklist_timeout, and is given up after max_tries failures. A
        frontier still there at a goal reached is given up only on a map made after the robot got
        there (map_time [s], the stamp of the map the frontiers come from); until then it waits,
        settle_time at most."""
        places = np.array(self.places, float).reshape(-1, 3)  # [x, y, new goals sent there]
        failures = [b for b in self.blacklist if b.cells is not None]
        # Which places can be f's at all, for all places at once (a building's exploration records
        # hundreds): the cells' boxes within 0.3 m of each other, or a goal within blacklist_radius.
        if failures:
            boxes = [b.box() for b in failures]
            lo, hi = np.array([bx[0] for bx in boxes]), np.array([bx[1] for bx in boxes])
            goals = np.array([g for b in failures for g in b.goals], float).reshape(-1, 2)
            owner = np.repeat(np.arange(len(failures)), [len(b.goals) for b in failures])

        def judge(f: Frontier) -> Union[str, GivenUp]:
            sent = int(np.sum(places[np.hypot(places[:, 0] - f.goal[0], places[:, 1] - f.goal[1])
                                     < self.blacklist_radius, 2]))
            if sent >= self.max_goals_per_place:
                # Chosen again and again and never explored (two frontiers pulling the robot to and
                # fro): a bound on goals per place is what makes every exploration end.
                x, y = f.cells.mean(axis=0)
                return GivenUp(float(x), float(y), f.size_m, 'sent %d times and never explored' % sent)
            matches = []
            if failures:
                flo, fhi = f.cells.min(axis=0), f.cells.max(axis=0)
                overlap = ~(np.any(flo > hi + 0.3, axis=1) | np.any(lo > fhi + 0.3, axis=1))
                near_goal = np.zeros(len(failures), bool)
                near_goal[owner[np.hypot(goals[:, 0] - f.goal[0], goals[:, 1] - f.goal[1]) < self.blacklist_radius]] = True
                matches = [failures[i] for i in np.flatnonzero(overlap | near_goal)
                           if self._same_place(failures[i], f, bool(near_goal[i]))]
            # with no newer map within settle_time (SLAM publishes none while the robot stands
            # still), it is judged on the map there is
            unsettled = [b for b in matches if b.reached and map_time <= b.until and now - b.until < self.settle_time]
            exhausted = [b for b in matches if b.tries >= self.max_tries and b not in unsettled]
            if exhausted:
                x, y = f.cells.mean(axis=0)
                b = exhausted[0]
                return GivenUp(float(x), float(y), f.size_m, b.why if b.reached else
                               '%d goals failed (last: %s)' % (b.tries, b.why))
            if unsettled or any(b.until > now and not b.reached for b in matches):
                return WAITING
            return ELIGIBLE

        return judge

    def choose(self, now: float, frontiers: List[Frontier], robot: Tuple[float, float]) -> Optional[Frontier]:
        """The frontier to head for (a goal to send), or None to keep the current goal; with no
        frontiers the current goal's place counts as visited and there is no goal."""
        self.why = 'no goal before'
        if not frontiers:
            self.reached(now)
            return None
        best = frontiers[0]
        if self.goal is not None:
            # The frontier being explored, if still there: the one with cells nearest the goal sent
            # (its cells and goal shift as the map grows; matching on cells keeps the robot from
            # flipping between two frontiers whose goals move).
            gx, gy = self.goal.goal
            near = [(float(np.min(np.hypot(f.cells[:, 0] - gx, f.cells[:, 1] - gy))), i) for i, f in enumerate(frontiers)]
            d, i = min(near)
            current = [frontiers[i]] if d < CURRENT_RADIUS else []
            if not current:
                # Its frontier is gone (mapped on the way, or below min_frontier_size now): the place
                # counts as visited, so that a frontier flickering there does not pull the robot back.
                self.why = 'the frontier of (%.2f, %.2f) is gone' % (gx, gy)
                self.reached(now)
            else:
                self.why = 'cost %.1f against %.1f for (%.2f, %.2f)' % (best.cost, current[0].cost, gx, gy)
            # A goal left for a better one does not take the robot back from the current one for
            # switch_back_after: as the map grows, the costs of two frontiers can take turns
            # (measured: the home's kitchen and hall swapped 4 times in 30 s, and the robot reached
            # neither for 88 s).
            self.left = [g for g in self.left if now - g[2] < self.switch_back_after]
            left_before = any(math.hypot(best.goal[0] - x, best.goal[1] - y) < self.blacklist_radius
                              for x, y, _ in self.left)
            if current and (best.cost > current[0].cost - self.hysteresis or left_before):
                if math.hypot(current[0].goal[0] - self.goal.goal[0], current[0].goal[1] - self.goal.goal[1]) < 0.25:
                    return None
                # The same frontier, but its goal moved (the map grew, or an obstacle appeared near
                # the old goal): follow it without counting a new goal.
                self.goal = current[0]
                return current[0]
            if current:
                self.left.append((gx, gy, now))
        if self.goal is not None and math.hypot(best.goal[0] - self.goal.goal[0], best.goal[1] - self.goal.goal[1]) < 0.25:
            # Another frontier whose goal is the one being driven to (two groups of cells that one
            # cell serves): not a new goal, and not one more goal sent to that place.
            self.goal = best
            return None
        self.goal = best
        self.goals_chosen += 1
        for p in self.places:
            if math.hypot(p[0] - best.goal[0], p[1] - best.goal[1]) < self.blacklist_radius:
                p[2] += 1
                break
        else:
            self.places.append([best.goal[0], best.goal[1], 1])
        self.progress_at, self.progress_time = robot, now
        return best

    def stuck(self, now: float, robot: Tuple[float, float]) -> bool:
        """True when the robot has not moved progress_distance within progress_timeout while a goal
        is active; the goal is then blacklisted and dropped."""
        if self.goal is None:
            return False
        if math.hypot(robot[0] - self.progress_at[0], robot[1] - self.progress_at[1]) >= self.progress_distance:
            self.progress_at, self.progress_time = robot, now
            return False
        if now - self.progress_time > self.progress_timeout:
            self.fail(now, 'no progress for %.0f s' % self.progress_timeout)
            return True
        return False

    def fail(self, now: float, why: str = '') -> None:
        """The current goal failed (aborted by move_base, or no progress): blacklist its place and
        its frontier."""
        if self.goal is None:
            return
        f = self.goal
        for b in self.blacklist:
            if b.cells is not None and not b.reached and self._same_place(b, f):
                b.tries += 1
                b.until = now + self.blacklist_timeout
                b.goals.append(f.goal)
                b.cells = np.concatenate([b.cells, f.cells])
                b.size_m, b.why = f.size_m, why
                break
        else:
            self.blacklist.append(Blacklisted([f.goal], now + self.blacklist_timeout, 1, f.cells.copy(), f.size_m, why))
        self.goal = None

    def reached(self, now: float, arrived: bool = False, seen_radius: float = 1.5) -> None:
        """The goal's place is not sent again: its frontier vanished on the way, or (arrived) the
        robot got there. Frontier cells within seen_radius [m] of a goal the robot stood at, and
        still there, cannot be seen from the floor (the gap behind a bathtub, under furniture): a
        frontier made mostly of those, reached max_tries times, is given up, not chased goal after
        goal along its cells (once is not enough: at a doorway a step more may show the room). A
        long frontier of which the robot saw one end (a hall beyond laser range) is not."""
        if self.goal is not None:
            cells = None
            if arrived:
                c = self.goal.cells
                near = np.hypot(c[:, 0] - self.goal.goal[0], c[:, 1] - self.goal.goal[1]) <= seen_radius
                cells = c[near].copy() if near.any() else None
            for b in self.blacklist:
                if cells is not None and b.reached and self._same_place(b, self.goal):
                    b.tries += 1
                    b.until = now
                    b.goals.append(self.goal.goal)
                    b.cells = np.concatenate([b.cells, cells])
                    break
            else:
                self.blacklist.append(Blacklisted([self.goal.goal], now, 1 if cells is not None else self.max_tries,
                                                  cells, self.goal.size_m, 'reached %d times and still there: not '
                                                  'visible from the floor' % self.max_tries if arrived else '',
                                                  reached=True))
        self.goal = None


@dataclass
class MotionWatch:
    """How long the robot has stood still (moved less than `distance` [m]), whatever its goals."""
    distance: float = 0.2
    anchor: Optional[Tuple[float, float]] = None
    since: float = 0.0

    def update(self, now: float, robot: Tuple[float, float]) -> None:
        if self.anchor is None or math.hypot(robot[0] - self.anchor[0], robot[1] - self.anchor[1]) >= self.distance:
            self.reset(now, robot)

    def reset(self, now: float, robot: Tuple[float, float]) -> None:
        self.anchor, self.since = robot, now

    def still_for(self, now: float) -> float:
        return now - self.since if self.anchor is not None else 0.0


@dataclass
class Plateau:
    """The longest stretch [s] without new explored area while reachable frontiers remained."""
    growth: float = 0.5         # [m^2] of new known area that ends a plateau
    longest: float = 0.0        # [s]
    longest_at: float = 0.0     # [s] when that stretch began
    _mark: Optional[Tuple[float, float]] = None  # (time, known area) at the last growth

    def pause(self, seconds: float) -> None:
        """The exploration was paused for `seconds`: not a stretch without progress."""
        if self._mark is not None:
            self._mark = (self._mark[0] + seconds, self._mark[1])

    def update(self, now: float, known_m2: float, frontiers_left: bool) -> None:
        if not frontiers_left:
            self._mark = None
            return
        if self._mark is None or known_m2 >= self._mark[1] + self.growth:
            self._mark = (now, known_m2)
            return
        if now - self._mark[0] > self.longest:
            self.longest, self.longest_at = now - self._mark[0], self._mark[0]
