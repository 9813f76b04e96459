#!/usr/bin/env python3
"""A point published on /clicked_point (rviz's Publish Point tool) moves the world's ball there,
at rest; with two balls it moves neither. `rosrun flatsim move_model x y` moves the ball too.

Also checks what rviz and image_view show: the whole world arrives on
/flatsim/world_markers in the odom frame, and /flatsim/overhead/image_raw is
an rgb8 picture. Physics is paused while the ball is measured, so the ball
cannot roll between the click and the reading.
"""
import math
import subprocess
import sys
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import PointStamped
from sensor_msgs.msg import Image
from gazebo_msgs.srv import DeleteModel, SpawnModel
from std_srvs.srv import Empty
from visualization_msgs.msg import Marker, MarkerArray

from rostest_support import WALL_LIMIT_S, model_state_proxy, wait_until

BALL = 'white_ball'
SECOND_BALL = ('<sdf version="1.6"><model name="red_ball"><pose>0 0 0.1 0 0 0</pose><link name="link">'
               '<collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry>'
               '</collision></link></model></sdf>')
# Wall time for a message in flight to arrive while physics is paused.
DELIVERY_S = 0.5


class ClickedPointTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_clicked_point')
        cls.get_model_state = model_state_proxy()
        wait_until(lambda: cls.get_model_state(model_name=BALL).success, 'the ball in the world')
        cls.click_pub = rospy.Publisher('/clicked_point', PointStamped, queue_size=1)
        wait_until(lambda: cls.click_pub.get_num_connections() > 0, 'a /clicked_point subscriber',
                   sim_timeout=None)
        rospy.wait_for_service('/gazebo/pause_physics', timeout=WALL_LIMIT_S)
        rospy.ServiceProxy('/gazebo/pause_physics', Empty)()

    @classmethod
    def tearDownClass(cls):
        rospy.ServiceProxy('/gazebo/unpause_physics', Empty)()

    def click(self, x, y, frame_id='odom'):
        msg = PointStamped()
        msg.header.frame_id = frame_id
        msg.point.x, msg.point.y, msg.point.z = x, y, 0.0
        self.click_pub.publish(msg)

    def ball(self):
        return self.get_model_state(model_name=BALL)

    def test_click_moves_the_ball_there_at_rest(self):
        start = self.ball()
        target = (start.pose.position.x - 1.3, start.pose.position.y + 0.4)
        self.click(*target)
        wait_until(lambda: math.hypot(self.ball().pose.position.x - target[0],
                                      self.ball().pose.position.y - target[1]) < 1e-6,
                   'the ball at the clicked point %r' % (target,))
        state = self.ball()
        self.assertAlmostEqual(state.pose.position.z, start.pose.position.z, places=6)
        twist = state.twist
        self.assertEqual((twist.linear.x, twist.linear.y, twist.angular.z), (0.0, 0.0, 0.0))

    def test_with_two_balls_a_click_moves_neither_until_one_is_deleted(self):
        self.assertEqual(rospy.get_param('/flatsim/ball_names'), [BALL])
        rospy.wait_for_service('/gazebo/spawn_sdf_model', timeout=WALL_LIMIT_S)
        spawned = rospy.ServiceProxy('/gazebo/spawn_sdf_model', SpawnModel)(
            model_name='red_ball', model_xml=SECOND_BALL, reference_frame='')
        self.assertTrue(spawned.success, spawned.status_message)
        try:
            self.assertEqual(rospy.get_param('/flatsim/ball_names'), ['red_ball', BALL])
            before = self.ball().pose.position
            self.click(before.x + 0.5, before.y)
            time.sleep(DELIVERY_S)
            after = self.ball().pose.position
            self.assertEqual((after.x, after.y), (before.x, before.y))
        finally:
            rospy.ServiceProxy('/gazebo/delete_model', DeleteModel)(model_name='red_ball')
        self.assertEqual(rospy.get_param('/flatsim/ball_names'), [BALL])

    def test_move_model_without_a_name_moves_the_ball(self):
        start = self.ball().pose.position
        target = (start.x + 0.7, start.y - 0.2)
        subprocess.run(['rosrun', 'flatsim', 'move_model', '%.3f' % target[0], '%.3f' % target[1]],
                       check=True, timeout=WALL_LIMIT_S)
        position = self.ball().pose.position
        self.assertAlmostEqual(position.x, target[0], places=3)
        self.assertAlmostEqual(position.y, target[1], places=3)

    def test_click_in_another_frame_leaves_the_ball(self):
        before = self.ball().pose.position
        self.click(before.x + 1.0, before.y, frame_id='base_footprint')
        time.sleep(DELIVERY_S)
        after = self.ball().pose.position
        self.assertEqual((after.x, after.y), (before.x, before.y))

    def test_world_markers_hold_the_walls_and_the_ball(self):
        array = rospy.wait_for_message('/flatsim/world_markers', MarkerArray, timeout=WALL_LIMIT_S)
        markers = [m for m in array.markers if m.action == Marker.ADD]
        self.assertTrue(all(m.header.frame_id == 'odom' for m in markers))
        cubes = [m for m in markers if m.type == Marker.CUBE]
        # chase_house.world: 11 building walls and the table, shelf, counter and crate boxes.
        self.assertGreaterEqual(len(cubes), 11)
        tall = [m for m in cubes if abs(m.scale.z - 1.0) < 1e-9 and abs(m.pose.position.z - 0.5) < 1e-9]
        self.assertGreaterEqual(len(tall), 11)
        spheres = [m for m in markers if m.type == Marker.SPHERE]
        self.assertEqual(len(spheres), 1)
        ball = self.ball().pose.position
        self.assertAlmostEqual(spheres[0].pose.position.x, ball.x, places=6)
        self.assertAlmostEqual(spheres[0].pose.position.y, ball.y, places=6)
        self.assertEqual((spheres[0].color.r, spheres[0].color.g, spheres[0].color.b), (1.0, 1.0, 1.0))

    def test_overhead_picture_is_published_on_demand(self):
        rospy.ServiceProxy('/gazebo/unpause_physics', Empty)()
        try:
            image = rospy.wait_for_message('/flatsim/overhead/image_raw', Image,
                                           timeout=WALL_LIMIT_S)
        finally:
            rospy.ServiceProxy('/gazebo/pause_physics', Empty)()
        self.assertEqual(image.encoding, 'rgb8')
        self.assertEqual(image.step, 3 * image.width)
        self.assertEqual(len(image.data), image.step * image.height)
        self.assertGreater(image.width, 100)


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'clicked_point', ClickedPointTest, sys.argv)
