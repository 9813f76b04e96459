"""spawn_model: put a URDF or SDF model into flatsim, with gazebo_ros's command line.

  rosrun flatsim spawn_model -urdf -param robot_description -model my_robot -x 0 -y 0 -Y 0
  rosrun flatsim spawn_model -sdf -file ball.sdf -model ball2 -x 1

Exits non-zero with a clear message when the parameter or file does not
exist, the simulator refuses the model, or it does not answer in time.
"""
import argparse
import sys

import rospy

from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg
from flatsim.srv import SpawnModel

SERVICE = '/flatsim/spawn_model'


def parse_args(argv):
    # gazebo_ros spells its options with one dash and capital letters for angles.
    parser = argparse.ArgumentParser(prog='spawn_model', description=__doc__.split('\n')[0])
    kind = parser.add_mutually_exclusive_group(required=True)
    kind.add_argument('-urdf', action='store_true', help='the model is URDF')
    kind.add_argument('-sdf', action='store_true', help='the model is SDF')
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument('-param', help='ROS parameter holding the model XML')
    source.add_argument('-file', help='file holding the model XML')
    parser.add_argument('-model', required=True, help='name of the model in the world')
    for axis in ['x', 'y', 'z', 'R', 'P', 'Y']:
        parser.add_argument('-' + axis, type=float, default=0.0, dest=axis)
    parser.add_argument('-robot_namespace', default='')
    parser.add_argument('-reference_frame', default='')
    parser.add_argument('-timeout', type=float, default=60.0,
                        help='seconds to wait for the simulator (default 60)')
    # Accepted for compatibility with gazebo_ros launch files; they change nothing here.
    for flag in ['-unpause', '-wait', '-gazebo_namespace', '-J', '-package_to_model']:
        parser.add_argument(flag, nargs='?', const=True, help=argparse.SUPPRESS)
    return parser.parse_args(argv)


def read_model_xml(args):
    if args.param:
        if not rospy.has_param(args.param):
            raise SpawnError('parameter %s does not exist (is robot_description.launch included?)'
                             % rospy.resolve_name(args.param))
        return rospy.get_param(args.param)
    try:
        with open(args.file, encoding='utf-8') as handle:
            return handle.read()
    except OSError as error:
        raise SpawnError('cannot read %s: %s' % (args.file, error.strerror)) from None


class SpawnError(Exception):
    pass


def spawn(args):
    xml = read_model_xml(args)
    try:
        rospy.wait_for_service(SERVICE, timeout=args.timeout)
    except rospy.ROSException:
        raise SpawnError('%s did not appear within %.0f s: is flatsim running?'
                         % (SERVICE, args.timeout)) from None
    pose = rosmsg.pose_msg(Pose(args.x, args.y, args.z, args.R, args.P, args.Y))
    call = rospy.ServiceProxy(SERVICE, SpawnModel)
    response = call(model_name=args.model, model_xml=xml, robot_namespace=args.robot_namespace,
                    initial_pose=pose, reference_frame=args.reference_frame)
    if not response.success:
        raise SpawnError(response.status_message)
    return response.status_message


def main():
    args = parse_args(rospy.myargv(sys.argv)[1:])
    rospy.init_node('spawn_model', anonymous=True)
    try:
        rospy.loginfo('spawn_model: %s', spawn(args))
    except (SpawnError, rospy.ServiceException) as error:
        rospy.logerr('spawn_model: cannot spawn %s: %s', args.model, error)
        sys.exit(1)
