"""The simulator's pacing (sim/pacing.py): fixed factors, and auto following the slowest node."""
import math

import pytest

from mbot_slam_navigation.sim.pacing import PacingError, make_pacer


def run(pacer, seconds, lag_of, rtf_reached=None, dt=0.05, wall0=0.0, sim0=0.0):
    """Drives the pacer for `seconds` of wall time: the simulator reaches the pacer's factor (or
    rtf_reached, if lower), and a node reports lag_of(rtf) simulated seconds every dt."""
    wall, sim = wall0, sim0
    while wall < wall0 + seconds:
        wall += dt
        rate = pacer.rtf if rtf_reached is None else min(pacer.rtf, rtf_reached)
        sim += rate * dt
        lag = lag_of(pacer.rtf)
        if lag is not None:
            pacer.heartbeat('/move_base', lag, wall)
        pacer.update(wall, sim)
    return wall, sim


def test_parameters():
    assert make_pacer(4.0).rtf == 4.0 and not make_pacer(4.0).auto
    assert math.isinf(make_pacer(0).rtf)
    p = make_pacer('auto', min_rtf=0.5, max_rtf=20.0)
    assert p.auto and p.rtf == 1.0
    assert make_pacer(' AUTO ').auto
    for bad in ('fast', -1.0, float('nan'), None):
        with pytest.raises(PacingError, match='~real_time_factor'):
            make_pacer(bad)
    with pytest.raises(PacingError, match='~min_real_time_factor'):
        make_pacer('auto', min_rtf=0.0)
    with pytest.raises(PacingError, match='~max_real_time_factor'):
        make_pacer('auto', min_rtf=5.0, max_rtf=2.0)


def test_auto_settles_where_the_node_keeps_up():
    # The node's lag grows with the factor: 0.02 s per 1x (it keeps up to about 7.5x within 0.15 s).
    p = make_pacer('auto', max_lag=0.15)
    run(p, 60.0, lambda rtf: 0.02 * rtf)
    assert 3.5 <= p.rtf <= 7.5, p.rtf
    assert p.worst[0] == '/move_base'


def test_auto_slows_down_when_the_node_falls_behind():
    p = make_pacer('auto', max_lag=0.15)
    run(p, 30.0, lambda rtf: 0.01 * rtf)         # fast node: up to ~15x
    fast = p.rtf
    run(p, 30.0, lambda rtf: 0.05 * rtf, wall0=30.0, sim0=1e3)  # the machine got busy
    assert p.rtf < 0.5 * fast
    assert 0.05 * p.rtf <= 0.3


def test_auto_without_heartbeats_rises_to_the_maximum_and_a_silent_node_is_forgotten():
    p = make_pacer('auto', max_rtf=20.0)
    run(p, 60.0, lambda rtf: None)
    assert p.rtf == 20.0
    # A node that reported a huge lag and then stopped (SIGSTOP) holds the factor down only for
    # forget_after seconds.
    p.heartbeat('/stopped', 50.0, 60.0)
    p.update(60.3, p._mark[1] + 0.3 * 20.0)
    assert p.rtf < 20.0
    run(p, 60.0, lambda rtf: None, wall0=60.3, sim0=p._mark[1])
    assert p.rtf == 20.0


def test_auto_stays_within_its_bounds():
    p = make_pacer('auto', min_rtf=0.5, max_rtf=8.0)
    run(p, 30.0, lambda rtf: 10.0)  # a node that never keeps up
    assert p.rtf == 0.5
    run(p, 60.0, lambda rtf: 0.0, wall0=30.0, sim0=1e3)
    assert p.rtf == 8.0


def test_auto_does_not_wind_up_beyond_what_the_simulator_reaches():
    p = make_pacer('auto', max_rtf=100.0)
    run(p, 60.0, lambda rtf: 0.0, rtf_reached=12.0)
    assert p.rtf <= 12.0 / 0.8 * 1.1 + 1e-9
    assert p.achieved == pytest.approx(12.0, rel=0.01)


def test_fixed_factor_is_kept_and_measured():
    p = make_pacer(4.0)
    run(p, 5.0, lambda rtf: 5.0)
    assert p.rtf == 4.0
    assert p.achieved == pytest.approx(4.0, rel=0.01)
    assert p.worst == ('/move_base', 5.0)


def test_free_running_stays_free_alone_and_turns_auto_when_a_node_falls_behind():
    p = make_pacer(0)
    run(p, 10.0, lambda rtf: None, rtf_reached=120.0)
    assert math.isinf(p.rtf) and not p.auto and p.achieved == pytest.approx(120.0, rel=0.01)
    run(p, 1.0, lambda rtf: 0.5, rtf_reached=120.0, wall0=10.0, sim0=1200.0)  # behind, but under 1 s
    assert math.isinf(p.rtf) and not p.went_auto
    run(p, 0.5, lambda rtf: 30.0, rtf_reached=120.0, wall0=11.0, sim0=1400.0)  # 30 s behind
    assert p.went_auto and p.auto and math.isinf(p.max_rtf)
    assert p.rtf < 120.0  # slowed from what it reached


def test_auto_waits_for_a_late_node_at_most_max_hold_and_a_fixed_factor_never_waits():
    # move_base's heartbeats carry its pose's stamp every 0.1 simulated s; the clock may run
    # interval + max_lag past the last one, then waits for the next (at most max_hold wall s).
    p = make_pacer('auto', max_lag=0.15)
    for k in range(10):
        p.heartbeat('/move_base', 0.02, wall=0.01 * k, stamp=0.1 * k)
    assert abs(p.heard['/move_base'].interval - 0.1) < 1e-9
    assert p.late(1.14, wall=0.1) is None              # 0.9 + 0.1 + 0.15 = 1.15
    assert p.late(1.16, wall=0.1) == '/move_base'
    assert p.late(1.16, wall=0.15) == '/move_base' and p.holds == 1
    p.heartbeat('/move_base', 0.26, wall=0.16, stamp=1.0)  # it came: go on to 1.25
    assert p.late(1.16, wall=0.16) is None and p.held_s > 0.05
    assert p.late(1.26, wall=0.17) == '/move_base'
    assert p.late(1.26, wall=0.17 + p.max_hold + 0.01) is None  # passed by, not a deadlock
    assert p.passed_by == 1 and p.late(5.0, wall=0.3) is None
    p.heartbeat('/move_base', 0.02, wall=0.35, stamp=1.1)   # back in its rhythm: waited for again
    assert p.late(1.5, wall=0.36) == '/move_base'
    assert p.late(1.5, wall=0.36 + p.forget_after + 0.1) is None  # silent: forgotten

    never = make_pacer('auto', max_hold=0.0)
    for k in range(10):
        never.heartbeat('/move_base', 0.02, wall=0.01 * k, stamp=0.1 * k)
    assert never.late(100.0, wall=0.1) is None
    with pytest.raises(PacingError, match='~max_hold'):
        make_pacer('auto', max_hold=-0.1)

    fixed = make_pacer(4.0)
    for k in range(10):
        fixed.heartbeat('/move_base', 0.02, wall=0.01 * k, stamp=0.1 * k)
    assert fixed.late(100.0, wall=0.1) is None


def test_time_going_back_restarts_a_nodes_rhythm():
    p = make_pacer('auto', max_lag=0.15)
    for k in range(5):
        p.heartbeat('/slam_gmapping', 0.0, wall=0.01 * k, stamp=100.0 + 0.1 * k)
    p.heartbeat('/slam_gmapping', 0.0, wall=0.06, stamp=0.1)  # reset_simulation
    assert p.heard['/slam_gmapping'].stamp == 0.1
    assert p.late(0.3, wall=0.07) is None and p.late(0.36, wall=0.07) == '/slam_gmapping'
