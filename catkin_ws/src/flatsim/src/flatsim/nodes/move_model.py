"""move_model: teleport a model, as dragging it in Gazebo's window does.

  rosrun flatsim move_model white_ball 2.0 1.5        # x y [yaw], metres and radians
"""
import argparse
import sys

import rospy

from gazebo_msgs.msg import ModelState
from gazebo_msgs.srv import GetModelState, SetModelState

from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='move_model', description=__doc__.split('\n')[0])
    parser.add_argument('model', help='model name, e.g. white_ball')
    parser.add_argument('x', type=float)
    parser.add_argument('y', type=float)
    parser.add_argument('yaw', type=float, nargs='?', default=0.0)
    return parser.parse_args(argv)


def main():
    args = parse_args(rospy.myargv(sys.argv)[1:])
    rospy.init_node('move_model', anonymous=True)
    try:
        rospy.wait_for_service('/gazebo/set_model_state', timeout=10.0)
        current = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)(args.model, '')
        z = current.pose.position.z if current.success else 0.0
        response = rospy.ServiceProxy('/gazebo/set_model_state', SetModelState)(ModelState(
            model_name=args.model, pose=rosmsg.pose_msg(Pose(args.x, args.y, z, 0, 0, args.yaw))))
    except (rospy.ROSException, rospy.ServiceException) as error:
        rospy.logerr('move_model: %s (is flatsim running?)', error)
        sys.exit(1)
    if not response.success:
        rospy.logerr('move_model: %s', response.status_message)
        sys.exit(1)
    print(response.status_message)
