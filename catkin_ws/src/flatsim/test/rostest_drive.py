#!/usr/bin/env python3
"""Commands on /cmd_vel move the robot the commanded way, by /odom and by the simulator's ground truth,
and the robot pushes a unit box spawned in its way.

Works for both my_robot variants (diff drive and skid steer): the robot starts
at the origin facing +x with 3.9 m of free floor ahead (Wall_7 of chase_house).

Physics is paused while a command is delivered and while the robot is
measured: with the simulator running as fast as it can, a few milliseconds of
message latency are a sizeable stretch of sim time.

Parameters: ~model (str, my_robot): the spawned model's name.
"""
import math
import sys
import unittest

import rospy
import rostest
from gazebo_msgs.srv import DeleteModel, SpawnModel
from geometry_msgs.msg import Point, Pose, Quaternion
from std_srvs.srv import Empty

from rostest_support import (drivable_robot, ground_truth, odom_pose, paused_latest, publish_while_paused,
                             wait_sim, wrap)

FORWARD_SPEED = 0.3
# Gazebo's unit box as its Insert tab drops it: 1 kg, dynamic, 1 m on a side.
UNIT_BOX = ('<?xml version="1.0"?><sdf version="1.6"><model name="unit_box"><link name="link">'
            '<inertial><mass>1</mass><inertia><ixx>0.166667</ixx><iyy>0.166667</iyy>'
            '<izz>0.166667</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial>'
            '<collision name="collision"><geometry><box><size>1 1 1</size></box></geometry>'
            '</collision><visual name="visual"><geometry><box><size>1 1 1</size></box></geometry>'
            '</visual></link></model></sdf>')
TURN_RATE = 0.5
COMMAND_SECONDS = 2.0


class DriveTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_drive')
        cls.model = rospy.get_param('~model', 'my_robot')
        cls.odom, cls.cmd_pub, cls.get_model_state = drivable_robot()
        rospy.wait_for_service('/gazebo/pause_physics', timeout=10.0)
        cls.pause = rospy.ServiceProxy('/gazebo/pause_physics', Empty)
        cls.unpause = rospy.ServiceProxy('/gazebo/unpause_physics', Empty)

    def command(self, linear, angular, seconds):
        """Hold a command for `seconds` of sim time (the drive keeps the last one), then pause.

        Returns the last odometry message before the pause.
        """
        publish_while_paused(self.cmd_pub, linear, angular, self.pause, self.unpause)
        wait_sim(seconds)
        return self.paused_odom()

    def paused_odom(self):
        return paused_latest(self.pause, self.odom)

    def assert_odom_matches_ground_truth(self, odom_msg):
        x, y, yaw = ground_truth(self.get_model_state, self.model)
        ox, oy, oyaw = odom_pose(odom_msg)
        # Odometry comes at 50 Hz: the robot may have gone on for one period (0.02 s) since.
        self.assertAlmostEqual(ox, x, delta=0.01)
        self.assertAlmostEqual(oy, y, delta=0.01)
        self.assertAlmostEqual(wrap(oyaw - yaw), 0.0, delta=0.015)

    def test_forward_then_turn_left(self):
        before = self.paused_odom()
        start = odom_pose(before)
        self.assertAlmostEqual(start[0], 0.0, delta=1e-3)
        self.assertAlmostEqual(start[2], 0.0, delta=1e-3)

        moved = self.command(FORWARD_SPEED, 0.0, COMMAND_SECONDS)
        elapsed = (moved.header.stamp - before.header.stamp).to_sec()
        self.assertGreaterEqual(elapsed, COMMAND_SECONDS - 0.03)
        x, y, yaw = odom_pose(moved)
        # Full speed all along at most; diff drive's 1 m/s^2 ramp loses 0.045 m of it.
        self.assertLess(x - start[0], FORWARD_SPEED * elapsed + 0.01)
        self.assertGreater(x - start[0], FORWARD_SPEED * elapsed - 0.08)
        self.assertAlmostEqual(y, start[1], delta=0.03)
        self.assertAlmostEqual(wrap(yaw - start[2]), 0.0, delta=0.03)
        self.assertAlmostEqual(moved.twist.twist.linear.x, FORWARD_SPEED, delta=0.03)
        self.assertAlmostEqual(moved.twist.twist.angular.z, 0.0, delta=0.03)
        self.assert_odom_matches_ground_truth(moved)

        turned = self.command(0.0, TURN_RATE, COMMAND_SECONDS)
        elapsed = (turned.header.stamp - moved.header.stamp).to_sec()
        tx, ty, tyaw = odom_pose(turned)
        # Positive angular z turns left (counter-clockwise), REP 103; ideally 1 rad.
        self.assertGreater(wrap(tyaw - yaw), 0.6)
        self.assertLess(wrap(tyaw - yaw), TURN_RATE * elapsed + 0.02)
        self.assertAlmostEqual(turned.twist.twist.angular.z, TURN_RATE, delta=0.05)
        # Turning in place: the footprint origin stays where it was (the drive axis is there).
        self.assertLess(math.hypot(tx - x, ty - y), 0.1)
        self.assert_odom_matches_ground_truth(turned)

        stopped = self.command(0.0, 0.0, 1.0)
        self.unpause()
        self.assertAlmostEqual(stopped.twist.twist.linear.x, 0.0, delta=0.01)
        self.assertAlmostEqual(stopped.twist.twist.angular.z, 0.0, delta=0.01)

    def test_the_robot_pushes_a_unit_box_out_of_its_way(self):
        self.pause()
        rospy.ServiceProxy('/gazebo/reset_world', Empty)()
        spawn = rospy.ServiceProxy('/gazebo/spawn_sdf_model', SpawnModel)
        # Its near face 0.6 m ahead of the robot's origin, a third of a metre ahead of its front.
        placed = spawn(model_name='unit_box', model_xml=UNIT_BOX, robot_namespace='',
                       initial_pose=Pose(Point(1.1, 0.0, 0.5), Quaternion(0, 0, 0, 1)),
                       reference_frame='world')
        self.assertTrue(placed.success, placed.status_message)
        try:
            self.command(FORWARD_SPEED, 0.0, 4.0)
            box_x, box_y, _ = ground_truth(self.get_model_state, 'unit_box')
            robot_x, _, _ = ground_truth(self.get_model_state, self.model)
            # 1.2 m of driving: the robot goes on past where the box stood, the box ahead of it.
            self.assertGreater(robot_x, 0.8)
            self.assertGreater(box_x, 1.1 + 0.4)
            self.assertGreater(box_x - 0.5, robot_x)
            self.assertAlmostEqual(box_y, 0.0, delta=0.3)
        finally:
            self.command(0.0, 0.0, 0.1)
            rospy.ServiceProxy('/gazebo/delete_model', DeleteModel)(model_name='unit_box')
            self.unpause()


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'drive', DriveTest, sys.argv)
