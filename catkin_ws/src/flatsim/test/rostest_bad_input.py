#!/usr/bin/env python3
"""Bad input leaves flatsim running: NaN commands, unknown models, spawning from a missing parameter."""
import subprocess
import sys
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Pose, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Log
from roslib.packages import find_node
from std_srvs.srv import Empty

from flatsim.srv import SetModelState
from rostest_support import Latest, ground_truth, model_state_proxy, odom_pose, wait_sim, wait_until

ROBOT = 'my_robot'
SPEED = 0.3
DELIVERY_S = 0.3


class BadInputTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_bad_input')
        cls.warnings = []
        cls.warnings_lock = threading.Lock()
        cls.rosout = rospy.Subscriber('/rosout', Log, cls.on_log, queue_size=100)
        cls.odom = Latest('/odom', Odometry)
        cls.odom.wait(sim_timeout=30.0)
        cls.cmd_pub = rospy.Publisher('/cmd_vel', Twist, queue_size=1, latch=True)
        wait_until(lambda: cls.cmd_pub.get_num_connections() > 0, 'a /cmd_vel subscriber')
        cls.get_model_state = model_state_proxy()
        rospy.wait_for_service('/flatsim/set_model_state', timeout=10.0)
        cls.set_model_state = rospy.ServiceProxy('/flatsim/set_model_state', SetModelState)
        cls.pause = rospy.ServiceProxy('/flatsim/pause_physics', Empty)
        cls.unpause = rospy.ServiceProxy('/flatsim/unpause_physics', Empty)

    @classmethod
    def on_log(cls, msg):
        if msg.name == '/flatsim' and msg.level == Log.WARN:
            with cls.warnings_lock:
                cls.warnings.append(msg.msg)

    def flatsim_warnings(self):
        with self.warnings_lock:
            return list(self.warnings)

    def publish(self, linear, angular):
        """Deliver a command while physics is paused, so it acts from a known sim time."""
        msg = Twist()
        msg.linear.x, msg.angular.z = linear, angular
        self.pause()
        self.cmd_pub.publish(msg)
        time.sleep(DELIVERY_S)
        self.unpause()

    def test_nan_commands_are_ignored_with_a_warning(self):
        self.publish(SPEED, 0.0)
        wait_sim(1.5)
        cruising = self.odom.wait(newer_than=rospy.get_time())
        self.assertAlmostEqual(cruising.twist.twist.linear.x, SPEED, delta=0.03)
        x_before = odom_pose(cruising)[0]

        self.publish(float('nan'), 0.0)
        wait_sim(1.0)
        after = self.odom.wait(newer_than=rospy.get_time())
        self.assertAlmostEqual(after.twist.twist.linear.x, SPEED, delta=0.03)
        self.assertAlmostEqual(after.twist.twist.angular.z, 0.0, delta=0.03)
        self.assertGreater(odom_pose(after)[0], x_before + 0.25)

        self.publish(0.0, float('inf'))
        wait_sim(0.5)
        after = self.odom.wait(newer_than=rospy.get_time())
        self.assertAlmostEqual(after.twist.twist.linear.x, SPEED, delta=0.03)
        self.assertAlmostEqual(after.twist.twist.angular.z, 0.0, delta=0.03)

        # The simulator is alive, and its ground truth is finite and where odometry says.
        x, y, _ = ground_truth(self.get_model_state, ROBOT)
        self.assertAlmostEqual(x, odom_pose(self.odom.get())[0], delta=0.05)
        wait_until(lambda: any('not finite' in text for text in self.flatsim_warnings()),
                   'a flatsim warning about the non-finite command', sim_timeout=5.0)
        self.publish(0.0, 0.0)

    def test_get_model_state_of_an_unknown_model_fails_naming_it(self):
        response = self.get_model_state(model_name='no_such_model')
        self.assertFalse(response.success)
        self.assertIn('no_such_model', response.status_message)

    def test_set_model_state_of_an_unknown_model_fails_naming_it(self):
        pose = Pose()
        pose.orientation.w = 1.0
        response = self.set_model_state(model_name='no_such_model', pose=pose)
        self.assertFalse(response.success)
        self.assertIn('no_such_model', response.status_message)

    def test_set_model_state_with_a_nan_pose_fails_and_the_robot_stays(self):
        before = ground_truth(self.get_model_state, ROBOT)
        pose = Pose()
        pose.position.x = float('nan')
        pose.orientation.w = 1.0
        response = self.set_model_state(model_name=ROBOT, pose=pose)
        self.assertFalse(response.success)
        self.assertIn('finite', response.status_message)
        after = ground_truth(self.get_model_state, ROBOT)
        self.assertTrue(all(value == value for value in after))
        self.assertAlmostEqual(after[0], before[0], delta=0.5)

    def test_spawn_model_from_a_missing_parameter_exits_with_a_clear_message(self):
        scripts = find_node('flatsim', 'spawn_model')
        self.assertTrue(scripts, 'rosrun cannot find flatsim spawn_model')
        proc = subprocess.run(
            [scripts[0], '-urdf', '-param', 'no_such_description', '-model', 'ghost', '-timeout', '5'],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60, check=False)
        self.assertNotEqual(proc.returncode, 0, proc.stdout)
        self.assertIn('no_such_description', proc.stdout)
        self.assertIn('does not exist', proc.stdout)
        self.assertNotIn('Traceback', proc.stdout)
        self.assertFalse(self.get_model_state(model_name='ghost').success)


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'bad_input', BadInputTest, sys.argv)
