"""How fast simulated time runs against the wall clock: a fixed real-time factor, or `auto`, which
runs as fast as the nodes that consume simulated time keep up, and no faster. ROS-free.

The nodes that matter (slam_gmapping, move_base, amcl) publish a heartbeat (std_msgs/Header on
/sim_heartbeat): `stamp` is the simulated time of the newest input they have fully processed,
`frame_id` the node's name. On arrival the simulator's clock is ahead of that stamp by the node's
lag [simulated s]: its queue, its processing time and the transport, all in simulated seconds,
which is what a node's transform_tolerance and expected_update_rate are checked against.

Every `adjust_period` wall seconds the worst lag over the period (among nodes heard from within
`forget_after` wall seconds, so that a stopped or dead node does not hold the simulation still)
sets the factor: above `max_lag` it falls in proportion (at most halved), below half of it the
factor rises by `increase` per period, up to `max_rtf`; with no heartbeat at all it rises to the
maximum. A factor of inf means "as fast as the simulator goes" (no sleeping).

The factor follows the lag over a quarter of a wall second, which at 12x is three simulated
seconds: a node starved of the CPU for 30 ms of wall time (the scheduler on a busy two-core
machine) falls 0.4 simulated s behind before any factor could react, and move_base would find its
transform older than transform_tolerance. So under auto the simulator also waits for a node that is
late: each node's heartbeats come every `interval` simulated seconds (measured), and the clock does
not pass the node's last stamp + interval + max_lag until its next heartbeat has come, for at most
`max_hold` wall seconds (a node that changed its rhythm or stopped is then passed by, until it
beats again).

Free-running (real_time_factor 0) stays free while nobody reports a lag; once a node is more than
`free_lag_limit` behind, the pacer turns to auto with no upper bound (`went_auto` says when), so a
stack started at 0 still works, as fast as it keeps up.
"""
import math
from dataclasses import dataclass, field
from typing import Dict, Optional, Tuple

AUTO = 'auto'
# The defaults of the simulator's parameters (declared here once; sim/node.py reads them by name).
MIN_RTF = 0.25      # ~min_real_time_factor [sim s / wall s]
MAX_RTF = 100.0     # ~max_real_time_factor
MAX_LAG = 0.15      # ~max_lag [simulated s]: half of move_base's usual transform_tolerance (0.3 s)
MAX_HOLD = 0.1      # ~max_hold [wall s]: the longest auto waits for a late node (0: never)


class PacingError(ValueError):
    """A real_time_factor parameter that cannot be used (names the parameter)."""


@dataclass
class _Heard:
    lag: float = 0.0       # [simulated s] worst lag since the last adjustment
    last_wall: float = 0.0  # [wall s] when the last heartbeat arrived
    stamp: float = -math.inf  # [simulated s] the newest stamp heard
    interval: float = 0.0  # [simulated s] usual time between its stamps (0: not known yet)
    passed: bool = False   # waited for max_hold without a heartbeat: not waited for until the next


@dataclass
class Pacer:
    """The real-time factor. `auto` False: `rtf` stays as given (inf = free-running)."""
    rtf: float = 1.0                 # [sim s / wall s] current target; inf = no pacing
    auto: bool = False
    min_rtf: float = MIN_RTF         # [sim s / wall s] auto never goes below
    max_rtf: float = MAX_RTF         # [sim s / wall s] auto never goes above (inf allowed)
    max_lag: float = MAX_LAG         # [simulated s] the worst node lag auto aims below
    adjust_period: float = 0.25      # [wall s]
    increase: float = 1.1            # factor per adjust_period while every node keeps up
    forget_after: float = 2.0        # [wall s] a node silent this long no longer counts
    heard: Dict[str, _Heard] = field(default_factory=dict)
    achieved: float = 0.0            # [sim s / wall s] measured over the last adjust_period
    worst: Tuple[str, float] = ('', 0.0)  # the node with the worst lag in the last period, and its lag
    free_lag_limit: float = 1.0      # [simulated s] a lag that turns free-running into auto
    went_auto: bool = False          # set when free-running turned into auto
    max_hold: float = MAX_HOLD       # [wall s] the longest the clock waits for a late node (0: never)
    held_s: float = 0.0              # [wall s] spent waiting for late nodes, in all
    holds: int = 0                   # times the clock waited
    passed_by: int = 0               # times a node was passed by after max_hold
    _mark: Optional[Tuple[float, float]] = None  # (wall, sim) at the last adjustment
    _hold: Optional[Tuple[str, float]] = None    # (node, wall) of the wait under way

    def heartbeat(self, node: str, lag: float, wall: float, stamp: Optional[float] = None) -> None:
        """A node's heartbeat arrived at `wall` [s] with the clock `lag` [simulated s] past its
        `stamp` [simulated s; given for the waiting of late nodes]."""
        h = self.heard.setdefault(node, _Heard())
        if wall - h.last_wall > self.adjust_period:
            h.lag = lag  # first beat of this period
        else:
            h.lag = max(h.lag, lag)
        h.last_wall = wall
        h.passed = False
        if stamp is not None:
            gap = stamp - h.stamp
            if 0.0 < gap <= 1.0:  # longer: the node paused (no goal) or time jumped
                h.interval = gap if h.interval == 0.0 else 0.8 * h.interval + 0.2 * gap
            h.stamp = max(h.stamp, stamp) if gap > -1.0 else stamp  # time went back: start again

    def late(self, sim_next: float, wall: float) -> Optional[str]:
        """Under auto, the node that the clock should wait for before it goes on to `sim_next`
        [simulated s], or None. Counts the waiting; after max_hold wall seconds the node is passed by."""
        if not self.auto or self.max_hold <= 0.0:
            return None
        for node, h in self.heard.items():
            if h.passed or h.interval == 0.0 or wall - h.last_wall > self.forget_after:
                continue
            if sim_next > h.stamp + h.interval + self.max_lag:
                if self._hold is None or self._hold[0] != node:
                    self._hold = (node, wall)
                    self.holds += 1
                if wall - self._hold[1] > self.max_hold:
                    h.passed = True
                    self.passed_by += 1
                    self._end_hold(wall)
                    continue
                return node
        self._end_hold(wall)
        return None

    def _end_hold(self, wall: float) -> None:
        if self._hold is not None:
            self.held_s += wall - self._hold[1]
            self._hold = None

    def restart(self, wall: float, sim: float) -> None:
        """Time jumped (reset_simulation) or was paused: measure from here."""
        self._mark = (wall, sim)

    def update(self, wall: float, sim: float) -> bool:
        """Call often with the wall and simulated time [s]; True when the factor was re-decided."""
        if self._mark is None:
            self._mark = (wall, sim)
            return False
        dw = wall - self._mark[0]
        if dw < self.adjust_period:
            return False
        self.achieved = (sim - self._mark[1]) / dw
        self._mark = (wall, sim)
        live = {n: h for n, h in self.heard.items() if wall - h.last_wall <= self.forget_after}
        self.worst = max(((n, h.lag) for n, h in live.items()), key=lambda t: t[1], default=('', 0.0))
        for h in live.values():
            h.lag = 0.0
        if not self.auto and math.isinf(self.rtf) and self.worst[1] > self.free_lag_limit:
            self.auto, self.max_rtf, self.went_auto = True, math.inf, True
        if not self.auto:
            return True
        lag = self.worst[1]
        current = self.rtf if math.isfinite(self.rtf) else max(self.achieved, self.min_rtf)
        if lag > self.max_lag:
            self.rtf = current * max(0.5, self.max_lag / lag)
        elif lag < 0.5 * self.max_lag and self.achieved >= 0.8 * current:
            # Raise only a factor that the simulator actually reaches, or it winds up far above.
            self.rtf = current * self.increase
        self.rtf = min(max(self.rtf, self.min_rtf), self.max_rtf)
        return True


def make_pacer(real_time_factor, min_rtf: float = MIN_RTF, max_rtf: float = MAX_RTF, max_lag: float = MAX_LAG,
               max_hold: float = MAX_HOLD) -> Pacer:
    """The pacer for the simulator's ~real_time_factor: a number >= 0 (0: as fast as possible) or
    'auto' (start at 1x, within [min_rtf, max_rtf]). Raises PacingError naming the parameter."""
    if not (min_rtf > 0 and max_rtf >= min_rtf):
        raise PacingError('~min_real_time_factor must be > 0 and ~max_real_time_factor >= it (got %r, %r)'
                          % (min_rtf, max_rtf))
    if not max_lag > 0:
        raise PacingError('~max_lag must be > 0 simulated seconds (got %r)' % max_lag)
    if not (0 <= max_hold <= 5.0):
        raise PacingError('~max_hold must lie in [0, 5] wall seconds (got %r)' % max_hold)
    if isinstance(real_time_factor, str) and real_time_factor.strip().lower() == AUTO:
        return Pacer(rtf=min(max(1.0, min_rtf), max_rtf), auto=True, min_rtf=min_rtf, max_rtf=max_rtf,
                     max_lag=max_lag, max_hold=max_hold)
    try:
        value = float(real_time_factor)
    except (TypeError, ValueError):
        raise PacingError('~real_time_factor must be a number >= 0 or "auto" (got %r)' % (real_time_factor,)) from None
    if not value >= 0 or math.isnan(value):
        raise PacingError('~real_time_factor must be a number >= 0 or "auto" (got %r)' % (real_time_factor,))
    return Pacer(rtf=value if value > 0 else math.inf, auto=False, min_rtf=min_rtf, max_rtf=max_rtf, max_lag=max_lag,
                 max_hold=max_hold)
