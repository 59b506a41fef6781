"""host_check: a node whose advertised address its peers cannot reach is told what to set."""
from mbot_slam_navigation.host_check import address_problem


def test_one_machine_on_loopback_is_fine():
    assert address_problem('http://localhost:11311', 'http://localhost:40000/') == ''
    assert address_problem('http://127.0.0.1:11311', 'http://127.0.1.1:40000/') == ''


def test_a_loopback_address_with_a_remote_master_is_named_with_what_to_set():
    why = address_problem('http://192.0.2.10:11311', 'http://127.0.1.1:40000/')
    assert 'loopback address' in why and 'ROS_IP=' in why and '192.0.2.10' in why


def test_an_address_of_another_machine_is_named():
    why = address_problem('http://192.0.2.10:11311', 'http://192.0.2.77:40000/')
    assert 'not an address of this host' in why and 'ROS_IP=' in why


def test_a_name_that_does_not_resolve_is_named():
    assert 'does not resolve' in address_problem('http://192.0.2.10:11311', 'http://no-such-host.invalid:4/')
