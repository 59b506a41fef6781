"""The reference pages (docs/nodes/) are generated from the parameter readers: they must be current,
every parameter must have a line of meaning, and no launch file repeats a default."""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TOOLS = os.path.join(ROOT, 'tools')


def run(tool, *args):
    return subprocess.run([sys.executable, os.path.join(TOOLS, tool)] + list(args), capture_output=True, text=True,
                          timeout=120)


def test_the_reference_pages_are_current_and_every_parameter_has_a_meaning():
    done = run('node_docs.py', '--check')
    assert done.returncode == 0, done.stderr


def test_no_launch_file_repeats_a_default():
    done = run('check_defaults.py')
    assert done.returncode == 0, done.stderr


def test_the_page_check_fails_on_a_parameter_without_meaning(tmp_path):
    """The check is not a formality: a read without a doc is named."""
    sys.path.insert(0, TOOLS)
    import node_docs
    from mbot_slam_navigation import _core
    with _core.ParamCatalog() as catalog:
        r = _core.ParamReader({}, '/n', None)
        r.number('documented', 1.0, '[m] a distance')
        r.number('bare', 2.0)
    d = {e['key']: e for e in catalog.declarations}
    assert (d['documented']['unit'], d['documented']['meaning'], d['documented']['default']) == ('m', 'a distance', '1.0')
    assert d['bare']['meaning'] == ''
    text = node_docs.render('n', {'stands_in_for': 'x', 'executable': 'n', 'summary': 's'},
                            [dict(d['documented'], name='documented')], [])
    assert '| `~documented` | double | `1.0` | m |  | a distance |' in text


def test_a_launch_file_that_repeats_a_default_is_named(tmp_path):
    launch = tmp_path / 'x.launch'
    launch.write_text('<launch><node name="explore" pkg="mbot_slam_navigation" type="explore">'
                      '<param name="planner_frequency" value="0.33"/><param name="hysteresis" value="2.0"/>'
                      '</node></launch>')
    done = run('check_defaults.py', str(launch))
    assert done.returncode == 1
    assert 'passes ~planner_frequency = 0.33, its default' in done.stderr and 'hysteresis' not in done.stderr


def test_the_live_check_names_a_topic_missing_from_the_page_and_one_the_node_lacks():
    """node_interfaces.mismatches (run by the rostests against the real master) on a made-up
    system state: map_server as its page declares it, then with one topic more and one less."""
    sys.path.insert(0, os.path.join(ROOT, 'test', 'integration'))
    from node_interfaces import mismatches
    node = '/map_server'
    pubs = [['/map', [node]], ['/map_metadata', [node]], ['/rosout', [node]]]
    srvs = [['/static_map', [node]], ['/change_map', [node]], ['/map_server/get_loggers', [node]]]
    assert mismatches('map_server', node, [pubs, [], srvs]) == []
    extra = mismatches('map_server', node, [pubs + [['/map_extra', [node]]], [], srvs])
    assert extra == ['/map_server publishes /map_extra, which docs/nodes/map_server.md does not list']
    missing = mismatches('map_server', node, [pubs[1:], [], srvs])
    assert missing == ['docs/nodes/map_server.md says /map_server publishes /map, but it does not']
