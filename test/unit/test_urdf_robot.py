"""URDF reading: the Gazebo plugin tags, the laser's pose from the joints, the footprint."""
import math
import os
import subprocess

import numpy as np
import pytest

from mbot_slam_navigation.sim.urdf_robot import parse_urdf
from mbot_slam_navigation.sim.xmlutil import XmlError

PKG = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..'))

BASE = '''<robot name="r">
  <link name="base_footprint"/>
  <joint name="j0" type="fixed"><parent link="base_footprint"/><child link="base_link"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/></joint>
  <link name="base_link"><collision><geometry><box size="0.6 0.4 0.2"/></geometry></collision></link>
  <joint name="j1" type="fixed"><parent link="base_link"/><child link="laser"/>
    <origin xyz="0.2 0.1 0.1" rpy="0 0 1.5707963"/></joint>
  <link name="laser"/>
  %s
</robot>'''
DRIVE = '''<gazebo><plugin name="d" filename="libgazebo_ros_diff_drive.so">
  <wheelSeparation>0.5</wheelSeparation><wheelDiameter>0.2</wheelDiameter><torque>5</torque>
  <legacyMode>true</legacyMode><alwaysOn>true</alwaysOn><odometrySource>encoder</odometrySource>
  <commandTopic>cmd</commandTopic><updateRate>20</updateRate></plugin></gazebo>'''
LASER = '''<gazebo reference="laser"><sensor type="ray" name="lidar"><pose>0.05 0 0 0 0 0</pose>
  <update_rate>5</update_rate><ray><scan><horizontal><samples>%s</samples><resolution>2</resolution>
  <min_angle>-1</min_angle><max_angle>1</max_angle></horizontal></scan>
  <range><min>0.2</min><max>4</max><resolution>0.02</resolution></range>
  <noise><type>gaussian</type><mean>0</mean><stddev>0.03</stddev></noise></ray>
  <plugin name="p" filename="libgazebo_ros_laser.so"><topicName>front/scan</topicName>
  <frameName>laser</frameName></plugin></sensor></gazebo>'''


def test_drive_and_laser_tags():
    spec = parse_urdf(BASE % (DRIVE + LASER % 100))
    d = spec.drive
    assert (d.kind, d.wheel_separation, d.wheel_diameter, d.command_topic, d.update_rate, d.odometry_source) == \
        ('diff', 0.5, 0.2, 'cmd', 20.0, 'encoder')
    assert spec.warnings == []  # torque, legacyMode, alwaysOn: old tags, accepted quietly
    (laser,) = spec.lasers
    assert laser.samples == 200 and laser.topic == 'front/scan' and laser.update_rate == 5
    assert (laser.range_min, laser.range_max, laser.range_resolution, laser.noise_stddev) == (0.2, 4, 0.02, 0.03)
    assert laser.angle_increment == pytest.approx(2.0 / 199)
    # laser link at (0.2, 0.1) turned 90 deg; the sensor's <pose> 0.05 along the link's x = +y in base
    assert laser.pose_in_base == pytest.approx((0.2, 0.15, math.pi / 2), abs=1e-6)
    assert np.allclose(spec.footprint.min(axis=0), [-0.3, -0.2]) and np.allclose(spec.footprint.max(axis=0), [0.3, 0.2])


def test_bad_robots_are_refused_with_what_and_where():
    with pytest.raises(XmlError, match='no drive plugin'):
        parse_urdf(BASE % LASER % 10, 'robot_description')
    with pytest.raises(XmlError, match=r'robot_description:\d+: <sensor name="lidar">: the laser has 0 samples'):
        parse_urdf(BASE % (DRIVE + LASER % 0), 'robot_description')
    unknown = DRIVE.replace('<torque>5</torque>', '<wheelSeperation>1</wheelSeperation>')
    assert any('<wheelSeperation> is not a parameter' in w for w in parse_urdf(BASE % unknown).warnings)


def xacro(path):
    return subprocess.run([os.path.join(PKG, 'scripts', 'xacro'), path], check=True, capture_output=True,
                          text=True).stdout


def test_shipped_robots_through_xacro():
    mbot = parse_urdf(xacro(os.path.join(PKG, 'urdf', 'xacro', 'robot.xacro')))
    assert mbot.drive.kind == 'diff' and mbot.drive.wheel_separation == pytest.approx(0.38)
    assert mbot.lasers[0].topic == 'robot/laser/scan' and mbot.lasers[0].frame_id == 'laser_link'
    assert np.abs(mbot.footprint).max() == pytest.approx(0.2025, abs=1e-3)
    car = parse_urdf(xacro(os.path.join(PKG, 'urdf', 'myrobot.xacro')))
    assert car.drive.kind == 'skid' and len(car.drive.wheel_joints) == 4
    assert car.lasers[0].topic == '/scan' and car.lasers[0].frame_id == 'hokuyo_link'
    assert np.allclose(car.footprint.max(axis=0), [0.2, 0.2], atol=0.01)


def test_wheel_joints_for_publish_wheel_tf():
    from mbot_slam_navigation.transforms import from_xyz_rpy, matrix_to_quaternion, quaternion_multiply
    mbot = parse_urdf(xacro(os.path.join(PKG, 'urdf', 'xacro', 'robot.xacro')))
    left, right = mbot.wheels
    assert (left.name, left.parent, left.child, left.side) == ('left_wheel_joint', 'base_link', 'left_wheel_link', 0)
    assert right.side == 1 and right.origin[1, 3] == pytest.approx(-0.19)
    assert np.allclose(left.axis, [0, 1, 0])
    # Quaternion helpers agree with the matrices they stand for.
    for rpy in ((0.3, -0.2, 2.5), (math.pi, 0, 0), (0, math.pi, 0.1), (0, 0, -math.pi)):
        q = matrix_to_quaternion(from_xyz_rpy((0, 0, 0), rpy))
        assert sum(c * c for c in q) == pytest.approx(1.0)
    qz = matrix_to_quaternion(from_xyz_rpy((0, 0, 0), (0, 0, 0.4)))
    q2 = quaternion_multiply(qz, qz)
    assert q2 == pytest.approx(matrix_to_quaternion(from_xyz_rpy((0, 0, 0), (0, 0, 0.8))))
