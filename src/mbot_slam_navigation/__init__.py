"""mbot_slam_navigation: SLAM, navigation and simulation for ROS 1 on a ROS-free C++ core.

Python code imports the typed wrappers in this package (``grid``, ...), never ``_core`` directly.
"""
