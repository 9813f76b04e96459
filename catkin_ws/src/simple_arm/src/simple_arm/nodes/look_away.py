"""look_away: when the camera sees one uniform colour and the arm is still, look at the blocks.

Subscribes to /simple_arm/joint_states and rgb_camera/image_raw; calls
/arm_mover/safe_move with (1.57, 1.57), as the course's node does.
"""
import rospy
from overlay_check import shadowed
from sensor_msgs.msg import Image, JointState

from simple_arm.arm import MotionWatch, is_uniform
from simple_arm.srv import GoToPosition

CENTRE = (1.57, 1.57)


class LookAway:
    def __init__(self):
        self.watch = MotionWatch()
        self.client = rospy.ServiceProxy('/arm_mover/safe_move', GoToPosition)
        self.joint_sub = rospy.Subscriber('/simple_arm/joint_states', JointState, self.on_joints,
                                          queue_size=10)
        self.image_sub = rospy.Subscriber('rgb_camera/image_raw', Image, self.on_image, queue_size=10)

    def on_joints(self, msg):
        self.watch.update(msg.position)

    def on_image(self, msg):
        if is_uniform(msg.data) and not self.watch.moving:
            self.move_arm_center()

    def move_arm_center(self):
        rospy.loginfo('Moving the arm to the center')
        try:
            self.client(*CENTRE)
        except (rospy.ServiceException, rospy.ROSException) as error:
            rospy.logerr('Failed to call service safe_move: %s', error)


def main():
    shadowed.warn_if_shadowed(__file__)
    rospy.init_node('look_away')
    LookAway()
    rospy.spin()
