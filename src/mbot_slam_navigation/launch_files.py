"""What roslaunch puts on the parameter server for a launch file, read with roslaunch's own loader
(args, includes, $(find), rosparam files and last-one-wins all resolved) without starting anything.
"""
from typing import Dict, Iterable

import roslaunch.config


def launch_config(path: str, args: Iterable[str] = ()):
    """roslaunch's ROSLaunchConfig for `path` with `args` ("name:=value"); raises RLException."""
    return roslaunch.config.load_config_default([(path, list(args))], None)


def node_params(path: str, namespace: str, args: Iterable[str] = ()) -> Dict[str, object]:
    """The parameters under `namespace` (e.g. "/amcl"), keyed relative to it, typed as rosparam does."""
    prefix = namespace.rstrip('/') + '/'
    return {k[len(prefix):]: p.value for k, p in launch_config(path, args).params.items() if k.startswith(prefix)}
