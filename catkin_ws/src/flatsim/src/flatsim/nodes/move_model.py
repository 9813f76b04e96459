"""move_model: teleport a model, as dragging it in Gazebo's window does.

  rosrun flatsim move_model 2.0 1.5                   # the world's ball, whatever its name
  rosrun flatsim move_model white_ball 2.0 1.5 0.5    # [model] x y [yaw], metres and radians

Without a model name it moves the world's ball (its one pushable sphere, as
flatsim lists them in /flatsim/ball_names); with several balls it names them
and exits 1.
"""
import argparse
import math
import sys

import rospy

from gazebo_msgs.msg import ModelState
from gazebo_msgs.srv import GetModelState, SetModelState

from flatsim.errors import FlatsimError
from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg
from flatsim.world.entities import the_ball

BALL_NAMES_PARAM = '/flatsim/ball_names'


def _is_number(text):
    try:
        float(text)
    except ValueError:
        return False
    return True


def finite_float(text):
    """argparse's type for a coordinate: NaN and inf name no place (and no heading)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError('%r is not a number' % text) from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError('%r is not a finite number' % text)
    return value


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='move_model', description=__doc__.split('\n')[0],
                                     usage='move_model [-h] [model] x y [yaw]')
    parser.add_argument('model', nargs='?', default='',
                        help="model name, e.g. white_ball (default: the world's ball)")
    parser.add_argument('x', type=finite_float)
    parser.add_argument('y', type=finite_float)
    parser.add_argument('yaw', type=finite_float, nargs='?', default=0.0)
    # argparse fills positionals greedily from the left: a leading number is x, not a name.
    if argv and _is_number(argv[0]):
        argv = [''] + list(argv)
    return parser.parse_args(argv)


def main():
    args = parse_args(rospy.myargv(sys.argv)[1:])
    rospy.init_node('move_model', anonymous=True)
    try:
        rospy.wait_for_service('/gazebo/set_model_state', timeout=10.0)
        name = args.model or the_ball(rospy.get_param(BALL_NAMES_PARAM, []))
        current = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)(name, '')
        z = current.pose.position.z if current.success else 0.0
        response = rospy.ServiceProxy('/gazebo/set_model_state', SetModelState)(ModelState(
            model_name=name, pose=rosmsg.pose_msg(Pose(args.x, args.y, z, 0, 0, args.yaw))))
    except FlatsimError as error:
        rospy.logerr('move_model: %s: give its name (move_model NAME x y)', error)
        sys.exit(1)
    except (rospy.ROSException, rospy.ServiceException) as error:
        rospy.logerr('move_model: %s (is flatsim running?)', error)
        sys.exit(1)
    if not response.success:
        rospy.logerr('move_model: %s', response.status_message)
        sys.exit(1)
    print(response.status_message)
