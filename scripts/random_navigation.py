#!/usr/bin/env python3
"""The exploration tutorial's random_navigation.py: move_base goals to the home's nine points (p1..p9)
in random order, round after round, with success rate, running time and distance in the log.
`rosrun mbot_slam_navigation random_navigation.py [_rest_time:=2] [_max_goals:=N] [_max_duration:=S]
[_locations_file:=FILE.yaml] [_seed:=N]`; see mbot_slam_navigation/nav/random_navigation.py.
"""
from mbot_slam_navigation.nav.random_navigation import main

if __name__ == '__main__':
    main()
