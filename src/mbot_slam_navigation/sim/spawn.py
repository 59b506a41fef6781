"""spawn_model: sends a model to the simulator's spawn service, with gazebo_ros's arguments: a URDF
robot (-urdf, spawn_urdf_model) or SDF people, <actor>s (-sdf, spawn_sdf_model)."""
import argparse
import sys

import rospy
from geometry_msgs.msg import Pose
from std_srvs.srv import Empty

from mbot_slam_navigation.transforms import yaw_to_quaternion
from mbot_slam_navigation.srv import SpawnModel, SpawnModelRequest


def argument_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog='spawn_model', description='Spawn a URDF robot or SDF people in the 2D simulator.')
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument('-param', help='parameter holding the URDF (e.g. robot_description)')
    src.add_argument('-file', help='URDF file')
    kind = p.add_mutually_exclusive_group()
    kind.add_argument('-urdf', action='store_true', help='the model is URDF (a robot; the default)')
    kind.add_argument('-sdf', action='store_true', help='the model is SDF with <actor>s (people)')
    p.add_argument('-model', required=True, help='model name')
    for axis, what in (('x', '[m] x'), ('y', '[m] y'), ('z', '[m] z (ignored: the world is flat)'),
                       ('R', '[rad] roll (ignored)'), ('P', '[rad] pitch (ignored)'), ('Y', '[rad] yaw')):
        p.add_argument('-' + axis, type=float, default=0.0, help=what + ' of the spawn pose')
    p.add_argument('-robot_namespace', default='', help="the robot's topics' namespace")
    p.add_argument('-gazebo_namespace', default='/gazebo', help="the simulator's namespace")
    p.add_argument('-reference_frame', default='', help="the pose's frame ('' or world)")
    p.add_argument('-unpause', action='store_true', help='unpause the simulation after spawning')
    p.add_argument('-wait', type=float, default=60.0, help='seconds to wait for the simulator')
    return p


def parse_args(argv):
    return argument_parser().parse_args(argv)


def main():
    argv = rospy.myargv(sys.argv)[1:]
    args = parse_args(argv)
    rospy.init_node('spawn_model', anonymous=True)
    if args.param:
        if not rospy.has_param(args.param):
            rospy.logfatal('spawn_model: parameter %s is not set', rospy.resolve_name(args.param))
            sys.exit(1)
        xml = rospy.get_param(args.param)
    else:
        try:
            with open(args.file, encoding='utf-8') as f:
                xml = f.read()
        except OSError as e:
            rospy.logfatal('spawn_model: cannot read %s: %s', args.file, e)
            sys.exit(1)
    service = args.gazebo_namespace.rstrip('/') + ('/spawn_sdf_model' if args.sdf else '/spawn_urdf_model')
    try:
        rospy.wait_for_service(service, timeout=args.wait)
    except rospy.ROSException:
        rospy.logfatal('spawn_model: service %s not available after %.0f s: is the simulator running?',
                       service, args.wait)
        sys.exit(1)
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = args.x, args.y, args.z
    (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w) = yaw_to_quaternion(args.Y)
    res = rospy.ServiceProxy(service, SpawnModel)(SpawnModelRequest(
        model_name=args.model, model_xml=xml, robot_namespace=args.robot_namespace, initial_pose=pose,
        reference_frame=args.reference_frame))
    if not res.success:
        rospy.logfatal('spawn_model: %s', res.status_message)
        sys.exit(1)
    rospy.loginfo('spawn_model: %s', res.status_message)
    if args.unpause:
        rospy.ServiceProxy(args.gazebo_namespace.rstrip('/') + '/unpause_physics', Empty)()
