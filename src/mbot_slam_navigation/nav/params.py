"""Reading a ROS parameter namespace the way the navigation stack does, but checked.

Every key a node reads is declared with its default; what the user set but nobody reads is
reported with the nearest known key (``controller_patiente`` -> ``controller_patience``), or with
the namespace it belongs to when it is a known key of another one (``planner_frequency`` in
``local_costmap``). Wrong types name the key and its namespace (ParamError, a ValueError). Frame ids
lose a leading ``/`` (tf2 rejects them) with one warning each.

The reader is the C++ core's (core/params.h), the one the roscpp move_base reads its namespace
with, so the rospy nodes (amcl, explore) check their parameters with the same rules and messages:
``ParamReader(rospy.get_param('~', {}), rospy.get_name(), rospy.logwarn)``, then ``number``,
``integer``, ``boolean``, ``string``, ``frame``, ``deprecated``, ``raw``, ``has``, ``where``,
``report_unknown``.
"""
from typing import Callable

from mbot_slam_navigation._core import ParamError, ParamReader, nearest_key  # noqa: F401 (re-exported)

Warn = Callable[[str], None]
