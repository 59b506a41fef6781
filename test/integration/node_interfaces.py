"""What a running node registers with the master against what its reference page declares
(docs/nodes/interfaces.yaml, from which docs/nodes/<node>.md is generated): a topic or service the
node offers that the page does not list, or one the page lists that the node does not offer, fails.

Names on the page are relative to the node's namespace (`~x` private, `/x` global); `<...>` stands
for a part that depends on the set-up (a robot's namespace, a source's topic) and matches anything.
Entries whose note says they are conditional (only, while, with, unless) need not be present."""
import os
import re

import rosgraph
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
INTERFACES = os.path.join(ROOT, 'docs', 'nodes', 'interfaces.yaml')
CONDITIONAL = re.compile(r'\b(only|while|with|unless|rbpf)\b')


def _pattern(name: str, node: str) -> re.Pattern:
    if name.startswith('~'):
        name = node + '/' + name[1:]
    elif not name.startswith('/') and not name.startswith('<'):
        name = '/' + name
    parts = re.split(r'(<[^>]*>)', name)
    return re.compile('^' + ''.join('.*' if p.startswith('<') else re.escape(p) for p in parts) + '$')


def declared(page: str, node: str):
    """(published, subscribed, services): lists of (pattern, required) for the node `node`
    (its resolved name, e.g. /move_base) as page `page` declares them."""
    with open(INTERFACES) as f:
        api = yaml.safe_load(f)[page]

    def entries(key):
        return [(_pattern(e[0], node), not CONDITIONAL.search(e[2] or '')) for e in api.get(key) or []]

    pub, sub, srv = entries('published'), entries('subscribed'), entries('services')
    for action, _, _ in api.get('actions') or []:
        pub += [(_pattern('%s/%s' % (action, t), node), True) for t in ('feedback', 'status', 'result')]
        sub += [(_pattern('%s/%s' % (action, t), node), True) for t in ('goal', 'cancel')]
    for action, _, _ in api.get('actions_called') or []:
        pub += [(_pattern('%s/%s' % (action, t), node), False) for t in ('goal', 'cancel')]
        sub += [(_pattern('%s/%s' % (action, t), node), False) for t in ('feedback', 'status', 'result')]
    if api.get('tf_provided'):
        pub += [(_pattern('/tf', node), False), (_pattern('/tf_static', node), False)]
    sub += [(_pattern(t, node), False) for t in ('/tf', '/tf_static', '/clock')]
    pub.append((_pattern('/rosout', node), False))
    srv += [(_pattern('~' + s, node), False) for s in ('get_loggers', 'set_logger_level')]
    if api.get('tf_required'):
        srv.append((_pattern('~tf2_frames', node), False))  # tf2_ros's Python Buffer offers it
    return pub, sub, srv


def mismatches(page: str, node: str, state=None):
    """Texts naming each difference between the running node `node` and page `page`; [] if none.
    `state`: the master's getSystemState() (asked for when not given)."""
    if state is None:
        state = rosgraph.Master('/node_interfaces_check').getSystemState()
    actual = [sorted(name for name, nodes in kind if node in nodes) for kind in state]
    problems = []
    for (kind, have), want in zip(zip(('publishes', 'subscribes', 'serves'), actual), declared(page, node)):
        for name in have:
            if not any(p.match(name) for p, _ in want):
                problems.append('%s %s %s, which docs/nodes/%s.md does not list' % (node, kind, name, page))
        for p, required in want:
            if required and not any(p.match(name) for name in have):
                problems.append('docs/nodes/%s.md says %s %s %s, but it does not'
                                % (page, node, kind, p.pattern.strip('^$').replace('\\', '')))
    return problems
