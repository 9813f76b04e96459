"""simple_mover: swing both joints between -pi/2 and pi/2 over 10 s, at 10 Hz.

Publishes std_msgs/Float64 on /simple_arm/joint_1_position_controller/command
and /simple_arm/joint_2_position_controller/command, as the course's node does.
"""
import rospy
from overlay_check import shadowed
from std_msgs.msg import Float64

from simple_arm.arm import sweep_angle

JOINT_TOPICS = ('/simple_arm/joint_1_position_controller/command',
                '/simple_arm/joint_2_position_controller/command')


class SimpleMover:
    def __init__(self):
        self.publishers = [rospy.Publisher(topic, Float64, queue_size=10) for topic in JOINT_TOPICS]

    def run(self):
        rate = rospy.Rate(10)
        # With sim time, now() is 0 until the first /clock message.
        start = rospy.Time.now().to_sec()
        while start == 0.0 and not rospy.is_shutdown():
            rospy.sleep(0.01)
            start = rospy.Time.now().to_sec()
        while not rospy.is_shutdown():
            angle = sweep_angle(rospy.Time.now().to_sec() - start)
            for publisher in self.publishers:
                publisher.publish(Float64(angle))
            try:
                rate.sleep()
            except rospy.ROSTimeMovedBackwardsException:
                start = rospy.Time.now().to_sec()


def main():
    shadowed.warn_if_shadowed(__file__)
    rospy.init_node('arm_mover')
    try:
        SimpleMover().run()
    except rospy.ROSInterruptException:
        pass
