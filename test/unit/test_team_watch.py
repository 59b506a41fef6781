"""The base station's watch over its robots (nav/team.py TeamWatch): a silent robot is an outage
until it is heard again, and a robot silent for long is lost once the others have ended."""
from mbot_slam_navigation.nav.team import TeamWatch


def test_a_link_cut_for_ten_seconds_is_one_outage_with_its_length():
    w = TeamWatch(['robot1', 'robot2'], silence=5.0, lost_after=60.0)
    for t in range(0, 20):
        w.hear('robot1', float(t))
        w.hear('robot2', float(t))
        assert w.check(float(t)) == []
    # robot2's link goes down after t = 19 for 10 s; robot1 talks on
    begun = []
    for t in range(20, 30):
        w.hear('robot1', float(t))
        begun += w.check(float(t) + 0.5)
    assert [o.robot for o in begun] == ['robot2'] and begun[0].since == 19.0
    assert w.lost(29.5) == []
    ended = w.hear('robot2', 30.0)
    assert ended is begun[0] and ended.as_dict() == {'robot': 'robot2', 'from_s': 19.0, 'to_s': 30.0, 'silent_s': 11.0}
    assert w.check(31.0) == [] and len(w.outages) == 1


def test_a_robot_whose_host_died_is_lost_once_the_others_have_ended():
    w = TeamWatch(['robot1', 'robot2', 'robot3'], silence=5.0, lost_after=60.0)
    for t in range(0, 10):
        for r in ('robot1', 'robot2', 'robot3'):
            w.hear(r, float(t))
    for t in range(10, 100):  # robot3's host dies after t = 9
        w.hear('robot1', float(t))
        if t < 50:
            w.hear('robot2', float(t))
        w.check(float(t), ended=['robot2'] if t >= 50 else [])
    # robot2 ended at 49 (it stopped talking: no outage); robot1 is still exploring
    assert [o.robot for o in w.outages] == ['robot3']
    assert w.lost(99.0, ended=['robot2']) == ['robot3']
    assert w.team_ends_without(99.0, ended=['robot2']) == []  # robot1 has not ended
    assert w.team_ends_without(99.0, ended=['robot1', 'robot2']) == ['robot3']
    assert w.team_ends_without(60.0, ended=['robot1', 'robot2']) == []  # silent 51 s: not yet lost
    assert w.outages[0].as_dict()['to_s'] is None


def test_a_robot_never_heard_is_not_an_outage():
    w = TeamWatch(['robot1', 'robot2'])
    w.hear('robot1', 0.0)
    assert w.check(100.0, ended=['robot1']) == [] and w.lost(100.0) == []
    assert w.hear('somebody', 1.0) is None
