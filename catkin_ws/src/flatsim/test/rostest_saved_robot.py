#!/usr/bin/env python3
"""A robot saved in the world file runs on its plugins' topics, as Gazebo runs it.

saved_robot.world holds the robot as "Save World" writes it, 3 m from a wall,
and nothing is spawned. Its laser publishes /scan, its camera
/camera/rgb/image_raw, and its diff drive takes /cmd_vel and publishes /odom.
A robot spawned later under the same name replaces the saved copy.
"""
import os
import sys
import unittest

import rosgraph
import rospy
import rostest
from gazebo_msgs.srv import SpawnModel
from geometry_msgs.msg import Pose as PoseMsg, Twist
from sensor_msgs.msg import Image, LaserScan

from rostest_support import WALL_LIMIT_S, Latest, drivable_robot, ground_truth, wait_until

ROBOT = 'saved_bot'
WORLD = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'fixtures', 'worlds',
                     'saved_robot.world')
WALL_FACE_X = 3.4
LASER_X = 0.15
SPAWNED = ('<robot name="other"><link name="base"><collision><geometry><box size="0.3 0.3 0.1"/>'
           '</geometry></collision></link></robot>')


class SavedRobotTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_saved_robot')
        cls.odom, cls.cmd_vel, cls.get_model_state = drivable_robot()

    def test_1_its_laser_and_camera_publish_on_their_topics(self):
        scan = rospy.wait_for_message('/scan', LaserScan, timeout=WALL_LIMIT_S)
        x = ground_truth(self.get_model_state, ROBOT)[0]
        ahead = scan.ranges[len(scan.ranges) // 2]
        self.assertAlmostEqual(ahead, WALL_FACE_X - x - LASER_X, delta=0.03)
        image = rospy.wait_for_message('/camera/rgb/image_raw', Image, timeout=WALL_LIMIT_S)
        self.assertEqual((image.width, image.height), (64, 48))

    def test_2_it_drives_on_cmd_vel_and_reports_odom(self):
        start = ground_truth(self.get_model_state, ROBOT)[0]
        msg = Twist()
        msg.linear.x = 0.5
        self.cmd_vel.publish(msg)
        wait_until(lambda: ground_truth(self.get_model_state, ROBOT)[0] > start + 0.3,
                   'the saved robot driving forward', sim_timeout=5.0)
        self.cmd_vel.publish(Twist())
        wait_until(lambda: self.odom.msg.pose.pose.position.x > start + 0.3, '/odom following it')

    def test_3_a_robot_spawned_under_its_name_replaces_it(self):
        rospy.wait_for_service('/gazebo/spawn_urdf_model', timeout=WALL_LIMIT_S)
        pose = PoseMsg()
        pose.position.x, pose.position.y = -2.0, 1.0
        pose.orientation.w = 1.0
        response = rospy.ServiceProxy('/gazebo/spawn_urdf_model', SpawnModel)(
            model_name=ROBOT, model_xml=SPAWNED, initial_pose=pose, reference_frame='')
        self.assertTrue(response.success, response.status_message)
        x, y, _ = ground_truth(self.get_model_state, ROBOT)
        self.assertAlmostEqual(x, -2.0, places=3)
        self.assertAlmostEqual(y, 1.0, places=3)
        # The saved robot's plugins went with it: nobody takes /cmd_vel any more.
        _, subscribers, _ = rosgraph.Master(rospy.get_name()).getSystemState()
        self.assertNotIn('/cmd_vel', [topic for topic, _ in subscribers])

    def test_4_the_same_robot_spawned_as_sdf_drives_too(self):
        with open(WORLD) as handle:
            world = handle.read()
        model = world[world.index('<model name="saved_bot">'):world.index('<state ')]
        rospy.wait_for_service('/gazebo/spawn_sdf_model', timeout=WALL_LIMIT_S)
        pose = PoseMsg()
        pose.position.x, pose.position.y = 0.5, -1.5
        pose.orientation.w = 1.0
        response = rospy.ServiceProxy('/gazebo/spawn_sdf_model', SpawnModel)(
            model_name='sdf_bot', model_xml='<sdf version="1.6">%s</sdf>' % model,
            initial_pose=pose, reference_frame='')
        self.assertTrue(response.success, response.status_message)
        start = ground_truth(self.get_model_state, 'sdf_bot')[0]
        self.assertAlmostEqual(start, 0.5, places=3)
        wait_until(lambda: self.cmd_vel.get_num_connections() > 0, 'sdf_bot taking /cmd_vel',
                   sim_timeout=None)
        msg = Twist()
        msg.linear.x = 0.5
        self.cmd_vel.publish(msg)
        wait_until(lambda: ground_truth(self.get_model_state, 'sdf_bot')[0] > start + 0.3,
                   'the robot spawned from SDF driving forward', sim_timeout=5.0)
        self.cmd_vel.publish(Twist())


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'saved_robot', SavedRobotTest, sys.argv)
