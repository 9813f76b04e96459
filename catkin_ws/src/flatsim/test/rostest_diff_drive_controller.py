#!/usr/bin/env python3
"""ros_control's diff_drive_controller moves drive_bot from its wheels, through ROS.

The controller's left_wheel sits on the robot's right: a positive angular.z on
/drive_bot/base_controller/cmd_vel turns the robot clockwise by the simulator's
ground truth, while the controller's own odometry, which believes the names,
reports an anticlockwise turn on /drive_bot/base_controller/odom, as in Gazebo.
"""
import sys
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from std_srvs.srv import Empty

from rostest_support import (Latest, ground_truth, model_state_proxy, odom_pose, paused_latest,
                             publish_while_paused, wait_sim, wait_until, wrap)

CONTROLLER = '/drive_bot/base_controller'
TURN_RATE = 0.5
COMMAND_SECONDS = 2.0


class DiffDriveControllerTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_diff_drive_controller')
        cls.odom = Latest(CONTROLLER + '/odom', Odometry)
        cls.odom.wait(sim_timeout=30.0)
        cls.cmd_pub = rospy.Publisher(CONTROLLER + '/cmd_vel', Twist, queue_size=1, latch=True)
        wait_until(lambda: cls.cmd_pub.get_num_connections() > 0, 'a cmd_vel subscriber',
                   sim_timeout=None)
        cls.get_model_state = model_state_proxy()
        rospy.wait_for_service('/gazebo/pause_physics', timeout=10.0)
        cls.pause = rospy.ServiceProxy('/gazebo/pause_physics', Empty)
        cls.unpause = rospy.ServiceProxy('/gazebo/unpause_physics', Empty)

    def test_positive_angular_z_turns_it_clockwise_while_its_odometry_says_anticlockwise(self):
        before = paused_latest(self.pause, self.odom)
        _, _, start_yaw = ground_truth(self.get_model_state, 'drive_bot')
        publish_while_paused(self.cmd_pub, 0.0, TURN_RATE, self.pause, self.unpause)
        wait_sim(COMMAND_SECONDS)
        after = paused_latest(self.pause, self.odom)
        _, _, yaw = ground_truth(self.get_model_state, 'drive_bot')
        self.assertLess(wrap(yaw - start_yaw), -0.6)
        self.assertGreater(wrap(odom_pose(after)[2] - odom_pose(before)[2]), 0.6)
        self.assertEqual(after.child_frame_id, 'base_footprint')
        publish_while_paused(self.cmd_pub, 0.0, 0.0, self.pause, self.unpause)


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'diff_drive_controller', DiffDriveControllerTest, sys.argv)
