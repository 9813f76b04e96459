"""mimic (node turtle_mimic): make one turtle copy another's motion.

Subscribes input/pose (turtlesim/Pose) and publishes output/cmd_vel
(geometry_msgs/Twist) with its linear and angular velocity. Remap input and
output to two turtles, as launch/multisim.launch does.
"""
import rospy
from geometry_msgs.msg import Twist

from turtlesim.msg import Pose


def twist_from_pose(pose):
    twist = Twist()
    twist.linear.x = pose.linear_velocity
    twist.angular.z = pose.angular_velocity
    return twist


class Mimic:
    def __init__(self):
        # input and output are namespaces, remapped as wholes as the original's node handles are;
        # rospy remaps only whole names, so they are resolved (and remapped) first.
        self.publisher = rospy.Publisher(rospy.resolve_name('output') + '/cmd_vel', Twist, queue_size=1)
        self.subscriber = rospy.Subscriber(rospy.resolve_name('input') + '/pose', Pose, self.on_pose,
                                           queue_size=1)

    def on_pose(self, pose):
        self.publisher.publish(twist_from_pose(pose))


def main():
    rospy.init_node('turtle_mimic')
    Mimic()
    rospy.spin()
