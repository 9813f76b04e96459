"""draw_square: reset turtlesim, then drive turtle1 round a 2 m square, forever.

Subscribes turtle1/pose (turtlesim/Pose); publishes turtle1/cmd_vel
(geometry_msgs/Twist) every 0.016 s; calls reset (std_srvs/Empty) once at start.
"""
import rospy
from geometry_msgs.msg import Twist
from std_srvs.srv import Empty

from turtlesim.msg import Pose
from turtlesim.square import SquareDriver

TIMER_PERIOD = 0.016
RESET_WAIT_S = 5.0


class DrawSquare:
    def __init__(self):
        self.driver = SquareDriver()
        self.pose = None
        self.publisher = rospy.Publisher('turtle1/cmd_vel', Twist, queue_size=1)
        self.subscriber = rospy.Subscriber('turtle1/pose', Pose, self.on_pose, queue_size=1)

    def on_pose(self, pose):
        self.pose = pose

    def on_timer(self, _event):
        pose = self.pose
        if pose is None:
            return
        command, log = self.driver.update((pose.x, pose.y, pose.theta, pose.linear_velocity,
                                           pose.angular_velocity))
        for line in log:
            rospy.loginfo('%s', line)
        if command is not None:
            twist = Twist()
            twist.linear.x, twist.angular.z = command
            self.publisher.publish(twist)

    def reset_turtlesim(self):
        try:
            rospy.wait_for_service('reset', RESET_WAIT_S)
            rospy.ServiceProxy('reset', Empty)()
        except (rospy.ROSException, rospy.ServiceException) as error:
            rospy.logwarn('draw_square could not reset turtlesim, it starts from where turtle1 is: %s', error)
        # The square starts from a pose taken after the reset.
        self.pose = None


def main():
    rospy.init_node('draw_square')
    square = DrawSquare()
    square.reset_turtlesim()
    rospy.Timer(rospy.Duration(TIMER_PERIOD), square.on_timer)
    rospy.spin()
