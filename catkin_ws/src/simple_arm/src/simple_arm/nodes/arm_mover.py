"""arm_mover: the /arm_mover/safe_move service (simple_arm/GoToPosition).

Parameters, read again on every call so that `rosparam set` applies at once (rad):
  ~min_joint_1_angle, ~max_joint_1_angle, ~min_joint_2_angle, ~max_joint_2_angle
  (a missing bound does not clamp).
A NaN or infinite request is refused with an error. A request outside the
bounds is clamped with a warning; clamped angles beyond simple_arm.arm.MAX_TARGET_ANGLE
(a joint's position would be lost to rounding against them) are refused; the rest are
published to both joint position controllers, and the call returns after 3 s
of (sim) time for the arm to settle, as the course's node does.
"""
import math

import rospy
from overlay_check import shadowed
from std_msgs.msg import Float64

from simple_arm.arm import clamp_at_boundaries, too_large_to_track
from simple_arm.nodes.simple_mover import JOINT_TOPICS
from simple_arm.srv import GoToPosition, GoToPositionResponse

SETTLE_SECONDS = 3.0


class ArmMover:
    def __init__(self):
        self.publishers = [rospy.Publisher(topic, Float64, queue_size=10) for topic in JOINT_TOPICS]
        self.service = rospy.Service('/arm_mover/safe_move', GoToPosition, self.handle_safe_move)
        rospy.loginfo('Ready to send joint commands')

    @staticmethod
    def bounds():
        return [(float(rospy.get_param('~min_joint_%d_angle' % joint, -math.inf)),
                 float(rospy.get_param('~max_joint_%d_angle' % joint, math.inf)))
                for joint in (1, 2)]

    def handle_safe_move(self, req):
        rospy.loginfo('GoToPositionRequest received - j1:%1.2f, j2:%1.2f', req.joint_1, req.joint_2)
        if not (math.isfinite(req.joint_1) and math.isfinite(req.joint_2)):
            raise rospy.ServiceException('joint angles must be finite numbers, got j1=%r j2=%r'
                                         % (req.joint_1, req.joint_2))
        angles, warnings = clamp_at_boundaries((req.joint_1, req.joint_2), self.bounds())
        for warning in warnings:
            rospy.logwarn(warning)
        # Without bounds, or with huge ones, a finite request may still be one no joint can track.
        refused = too_large_to_track(angles)
        if refused is not None:
            rospy.logwarn('safe_move refused: %s', refused)
            raise rospy.ServiceException('joint angles %s' % refused)
        for publisher, angle in zip(self.publishers, angles):
            publisher.publish(Float64(angle))
        try:
            rospy.sleep(SETTLE_SECONDS)
        except rospy.ROSInterruptException:
            # Shut down mid-move: the caller hears so, and the log gets no traceback.
            raise rospy.ServiceException('arm_mover shut down before the arm settled') from None
        feedback = 'Joint angles set - j1: %f , j2: %f' % tuple(angles)
        rospy.loginfo(feedback)
        return GoToPositionResponse(msg_feedback=feedback)


def main():
    shadowed.warn_if_shadowed(__file__)
    rospy.init_node('arm_mover')
    ArmMover()
    rospy.spin()
