#!/usr/bin/env python3
"""Fails when a launch file of this package passes a node a parameter equal to its default.

A default is written once, in the call that reads it (docs/nodes/<node>.md lists them); a launch
file that repeats it makes two places to change and hides which values are choices. Values made of
$(arg ...) substitutions are not judged. Usage: tools/check_defaults.py [launch files...]
(default: every launch file under launch/). Needs the built package on the Python path.
"""
import ast
import glob
import os
import sys
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import node_docs  # noqa: E402  (the same declarations as the reference pages)

import yaml  # noqa: E402


def _typed(text: str, kind: str):
    """The launch file's text as roslaunch would type it (or the 'type' attribute)."""
    if kind == 'str':
        return text
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def _default(repr_text: str):
    try:
        return ast.literal_eval(repr_text)
    except (ValueError, SyntaxError):
        return repr_text


def declarations_by_executable():
    with open(node_docs.INTERFACES) as f:
        apis = yaml.safe_load(f)
    out = {}
    for node, api in apis.items():
        source = api.get('parameters') or {}
        if not source or 'argparse' in source:
            continue
        params = {p['name']: p for p in node_docs.declared_parameters(node, source)}
        out[api['executable'].split()[0]] = params
    return out


# Launch files that mirror a ROS tool's example value for value, so that users can compare.
EXEMPT = {'amcl_diff.launch': "ROS amcl's examples/amcl_diff.launch"}


def check(paths):
    known = declarations_by_executable()
    problems = []
    for path in paths:
        if os.path.basename(path) in EXEMPT:
            continue
        root = ET.parse(path).getroot()
        for node in root.iter('node'):
            if node.get('pkg') != 'mbot_slam_navigation' or node.get('type') not in known:
                continue
            params = known[node.get('type')]
            for param in node.findall('param'):
                name, value = param.get('name', ''), param.get('value')
                if value is None or '$(' in value or name not in params:
                    continue
                declared = params[name]
                if declared['default'] in ('', 'None'):
                    continue
                if _typed(value, param.get('type', '')) == _default(declared['default']):
                    problems.append('%s: node %s passes ~%s = %s, its default; leave it out'
                                    % (os.path.relpath(path), node.get('name'), name, value))
    return problems


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    paths = argv or sorted(glob.glob(os.path.join(node_docs.ROOT, 'launch', '**', '*.launch'), recursive=True))
    problems = check(paths)
    for p in problems:
        print(p, file=sys.stderr)
    return 1 if problems else 0


if __name__ == '__main__':
    sys.exit(main())
