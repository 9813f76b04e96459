#!/usr/bin/env python3
"""A robot whose leftJoint sits on its right turns clockwise for +angular.z, through ROS.

The diff drive gives the joint named in <leftJoint> the slower wheel speed when
turning left; that wheel is on the robot's right, so the robot turns right, by
/odom and by the simulator's ground truth alike.

Parameters: ~model (str, drive_bot): the spawned model's name.
"""
import sys
import unittest

import rospy
import rostest
from std_srvs.srv import Empty

from rostest_support import (drivable_robot, ground_truth, odom_pose, paused_latest, publish_while_paused,
                             wait_sim, wrap)

TURN_RATE = 0.5
COMMAND_SECONDS = 2.0


class WheelGeometryTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_wheel_geometry')
        cls.model = rospy.get_param('~model', 'drive_bot')
        cls.odom, cls.cmd_pub, cls.get_model_state = drivable_robot()
        rospy.wait_for_service('/gazebo/pause_physics', timeout=10.0)
        cls.pause = rospy.ServiceProxy('/gazebo/pause_physics', Empty)
        cls.unpause = rospy.ServiceProxy('/gazebo/unpause_physics', Empty)

    def test_positive_angular_z_turns_it_clockwise(self):
        before = paused_latest(self.pause, self.odom)
        start = odom_pose(before)
        publish_while_paused(self.cmd_pub, 0.0, TURN_RATE, self.pause, self.unpause)
        wait_sim(COMMAND_SECONDS)
        turned = paused_latest(self.pause, self.odom)
        elapsed = (turned.header.stamp - before.header.stamp).to_sec()
        turn = wrap(odom_pose(turned)[2] - start[2])
        self.assertLess(turn, -0.6)
        self.assertGreater(turn, -TURN_RATE * elapsed - 0.02)
        self.assertAlmostEqual(turned.twist.twist.angular.z, -TURN_RATE, delta=0.05)
        _, _, yaw = ground_truth(self.get_model_state, self.model)
        self.assertAlmostEqual(wrap(yaw - odom_pose(turned)[2]), 0.0, delta=0.02)
        publish_while_paused(self.cmd_pub, 0.0, 0.0, self.pause, self.unpause)


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'wheel_geometry', WheelGeometryTest, sys.argv)
