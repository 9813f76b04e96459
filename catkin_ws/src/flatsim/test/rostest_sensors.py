#!/usr/bin/env python3
"""my_robot in chase_house.world: camera_info, the TF chain and laser ranges against the world's geometry.

Expected values come from my_robot.xacro / my_robot.gazebo and from the
walls of chase_house.world (building model at x = 2):
  Wall_7  centre x = 4.0, 0.15 thick, spans y -2.2..1.8   -> near face x = 3.925
  Wall_3  centre x = -3.0, 0.15 thick                      -> near face x = -2.925
"""
import math
import sys
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import Pose, Quaternion
from sensor_msgs.msg import CameraInfo, LaserScan

from rostest_support import (Latest, ground_truth, model_state_proxy, set_model_state_proxy, wait_until,
                             yaw_of)

ROBOT = 'my_robot'
# my_robot.gazebo
HFOV = 1.3962634
WIDTH = HEIGHT = 800
HACK_BASELINE = 0.0
LASER_SAMPLES = 720
LASER_STDDEV = 0.01
LASER_RESOLUTION = 0.01
# my_robot.xacro: chassis 0.46 x 0.30 x 0.10 on wheels of radius 0.08; camera cube 0.05
# at the chassis front, 0.03 up; hokuyo 0.08 behind the front, on the chassis top.
CAMERA_IN_FOOTPRINT = (0.46 / 2 + 0.05 / 2, 0.0, 0.08 + 0.03)
HOKUYO_IN_FOOTPRINT = (0.46 / 2 - 0.08, 0.0, 0.08 + 0.10 / 2 + 0.07 / 2)
WALL_7_FACE_X = 4.0 - 0.15 / 2
WALL_3_FACE_X = -3.0 + 0.15 / 2


def straight_ahead(scan):
    """Mean of the two beams either side of 0 rad (720 beams have none at exactly 0)."""
    middle = len(scan.ranges) // 2
    return (scan.ranges[middle - 1] + scan.ranges[middle]) / 2.0


class SensorsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_sensors')
        cls.scan = Latest('/scan', LaserScan)
        cls.first_scan = cls.scan.wait(sim_timeout=30.0)
        cls.info = Latest('/camera/rgb/camera_info', CameraInfo)
        cls.tf_buffer = tf2_ros.Buffer()
        cls.tf_listener = tf2_ros.TransformListener(cls.tf_buffer)
        cls.get_model_state = model_state_proxy()

    def test_1_first_scan_sees_the_wall_ahead_of_the_spawn_pose(self):
        scan = self.first_scan
        self.assertEqual(scan.header.frame_id, 'hokuyo')
        self.assertEqual(len(scan.ranges), LASER_SAMPLES)
        self.assertAlmostEqual(scan.angle_min, -math.pi / 2, places=6)
        self.assertAlmostEqual(scan.angle_max, math.pi / 2, places=6)
        x, y, yaw = ground_truth(self.get_model_state, ROBOT)
        self.assertAlmostEqual(x, 0.0, delta=1e-3)
        self.assertAlmostEqual(y, 0.0, delta=1e-3)
        self.assertAlmostEqual(yaw, 0.0, delta=1e-3)
        expected = WALL_7_FACE_X - HOKUYO_IN_FOOTPRINT[0]
        self.assertAlmostEqual(straight_ahead(scan), expected,
                               delta=3 * LASER_STDDEV + LASER_RESOLUTION / 2)

    def test_2_camera_info_is_what_gazebo_ros_camera_publishes(self):
        info = self.info.wait(sim_timeout=10.0)
        f = WIDTH / (2.0 * math.tan(HFOV / 2.0))
        cx, cy = (WIDTH + 1) / 2.0, (HEIGHT + 1) / 2.0
        self.assertEqual(info.header.frame_id, 'camera')
        self.assertGreater(info.header.stamp.to_sec(), 0.0)
        self.assertEqual((info.width, info.height), (WIDTH, HEIGHT))
        self.assertEqual(info.distortion_model, 'plumb_bob')
        self.assertEqual(list(info.D), [0.0] * 5)
        for got, want in zip(info.K, [f, 0, cx, 0, f, cy, 0, 0, 1]):
            self.assertAlmostEqual(got, want, places=6)
        for got, want in zip(info.R, [1, 0, 0, 0, 1, 0, 0, 0, 1]):
            self.assertAlmostEqual(got, want, places=9)
        for got, want in zip(info.P, [f, 0, cx, -f * HACK_BASELINE, 0, f, cy, 0, 0, 0, 1, 0]):
            self.assertAlmostEqual(got, want, places=6)
        self.assertAlmostEqual(f, 476.7014, places=3)

    def test_3_tf_chain_reaches_the_camera_and_the_laser(self):
        x, y, yaw = ground_truth(self.get_model_state, ROBOT)
        timeout = rospy.Duration(10.0)
        base = self.tf_buffer.lookup_transform('odom', 'robot_footprint', rospy.Time(0), timeout)
        self.assertAlmostEqual(base.transform.translation.x, x, delta=0.01)
        self.assertAlmostEqual(base.transform.translation.y, y, delta=0.01)
        for frame, offset in [('camera', CAMERA_IN_FOOTPRINT), ('hokuyo', HOKUYO_IN_FOOTPRINT)]:
            mount = self.tf_buffer.lookup_transform('robot_footprint', frame, rospy.Time(0), timeout)
            got = mount.transform.translation
            for axis, value, want in zip('xyz', (got.x, got.y, got.z), offset):
                self.assertAlmostEqual(value, want, places=4, msg='%s %s' % (frame, axis))
            chained = self.tf_buffer.lookup_transform('odom', frame, rospy.Time(0), timeout)
            got = chained.transform.translation
            world_x = x + math.cos(yaw) * offset[0] - math.sin(yaw) * offset[1]
            world_y = y + math.sin(yaw) * offset[0] + math.cos(yaw) * offset[1]
            self.assertAlmostEqual(got.x, world_x, delta=0.01, msg=frame)
            self.assertAlmostEqual(got.y, world_y, delta=0.01, msg=frame)
            self.assertAlmostEqual(got.z, offset[2], delta=0.01, msg=frame)

    def test_4_scan_follows_the_robot_when_it_is_placed_facing_another_wall(self):
        set_model_state = set_model_state_proxy()
        # At (-1, 0.5) facing -x the beam straight ahead meets Wall_3.
        pose = Pose()
        pose.position.x, pose.position.y = -1.0, 0.5
        pose.orientation = Quaternion(0.0, 0.0, 1.0, 0.0)
        response = set_model_state(model_name=ROBOT, pose=pose)
        self.assertTrue(response.success, response.status_message)
        state = self.get_model_state(model_name=ROBOT)
        self.assertTrue(state.success, state.status_message)
        self.assertAlmostEqual(state.pose.position.x, -1.0, delta=1e-3)
        self.assertAlmostEqual(abs(yaw_of(state.pose.orientation)), math.pi, delta=1e-3)
        # flatsim stamps its answer with its own clock, at most a /clock period (0.01 s)
        # behind the step that placed the robot. This process's clock may lag further when
        # the machine is busy, so it cannot tell a scan taken before the placement.
        scan = self.scan.wait(newer_than=state.header.stamp.to_sec() + 0.05)
        hokuyo_x = -1.0 - HOKUYO_IN_FOOTPRINT[0]
        self.assertAlmostEqual(straight_ahead(scan), hokuyo_x - WALL_3_FACE_X,
                               delta=3 * LASER_STDDEV + LASER_RESOLUTION / 2)
        # The odometry pose follows the teleport: odometrySource is world.
        wait_until(lambda: self.tf_buffer.can_transform('odom', 'robot_footprint', rospy.Time(0))
                   and self.tf_buffer.lookup_transform('odom', 'robot_footprint', rospy.Time(0))
                   .transform.translation.x < -0.99, 'odom -> robot_footprint after the move')


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'sensors', SensorsTest, sys.argv)
