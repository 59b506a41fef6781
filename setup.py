# Used by catkin_python_setup() only; do not run directly.
from setuptools import setup
from catkin_pkg.python_setup import generate_distutils_setup

setup(**generate_distutils_setup(
    packages=['mbot_slam_navigation', 'mbot_slam_navigation.maps', 'mbot_slam_navigation.sim',
              'mbot_slam_navigation.slam', 'mbot_slam_navigation.nav'],
    package_dir={'': 'src'},
))
