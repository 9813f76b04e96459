#!/usr/bin/env python3
"""Bad input to the running nodes: each case gets a clear error to the caller
or in the log, and every node keeps running.

flatsim: non-finite and huge /cmd_vel, unknown models, NaN poses and huge
twists, spawn_model with a missing parameter, a duplicate name or a missing
file, a ball too small to simulate, a sensor at 1e300 Hz, a 1,000-link robot. drive_bot:
NaN, inf, huge and -0.0 requests. process_image: malformed images and
unsupported encodings, published on its own image topic (bad_input.test
remaps it) so the camera does not interfere. "Still running" means the same
pid: drive_bot's launch file respawns it, so a new pid counts as a crash.
"""
import math
import subprocess
import sys
import threading
import time
import unittest
import xmlrpc.client

import rosgraph
import rospy
import rostest
from gazebo_msgs.msg import ModelState
from gazebo_msgs.srv import DeleteModel, SetModelState, SpawnModel
from geometry_msgs.msg import Point, Pose, Quaternion, Twist, Vector3
from rosgraph_msgs.msg import Clock, Log
from roslib.packages import find_node
from sensor_msgs.msg import Image
from std_srvs.srv import Empty

from ball_chaser.srv import DriveToTarget
from rostest_support import (DELIVERY_S, drivable_robot, ground_truth, odom_pose, paused_latest,
                             publish_while_paused, set_model_state_proxy, wait_sim, wait_until)

ROBOT = 'my_robot'
SPEED = 0.3
IMAGE_TOPIC = '/bad_input/image_raw'
WATCHED_NODES = ('/flatsim', '/drive_bot', '/process_image')


def node_pid(name):
    """The pid of a registered node, or None when it is not registered or does not answer."""
    try:
        uri = rosgraph.Master('/rostest_bad_input').lookupNode(name)
        code, _message, pid = xmlrpc.client.ServerProxy(uri).getPid('/rostest_bad_input')
    except (rosgraph.MasterError, OSError):
        return None
    return pid if code == 1 else None


def image(height, width, encoding, step, data):
    return Image(height=height, width=width, encoding=encoding, step=step, data=bytes(data))


class BadInputTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('rostest_bad_input')
        cls.warnings = []
        cls.warnings_lock = threading.Lock()
        cls.rosout = rospy.Subscriber('/rosout', Log, cls.on_log, queue_size=100)
        cls.odom, cls.cmd_pub, cls.get_model_state = drivable_robot()
        cls.set_model_state = set_model_state_proxy()
        cls.pause = rospy.ServiceProxy('/gazebo/pause_physics', Empty)
        cls.unpause = rospy.ServiceProxy('/gazebo/unpause_physics', Empty)
        cls.reset_world = rospy.ServiceProxy('/gazebo/reset_world', Empty)
        rospy.wait_for_service('/ball_chaser/command_robot', timeout=30.0)
        cls.command_robot = rospy.ServiceProxy('/ball_chaser/command_robot', DriveToTarget)
        cls.image_pub = rospy.Publisher(IMAGE_TOPIC, Image, queue_size=10)
        wait_until(lambda: cls.image_pub.get_num_connections() > 0, 'process_image subscribing',
                   sim_timeout=1e9)
        cls.cmd_vel_seen = []
        cls.cmd_vel_sub = rospy.Subscriber('/cmd_vel', Twist, cls.cmd_vel_seen.append)
        cls.pids = {name: node_pid(name) for name in WATCHED_NODES}

    @classmethod
    def on_log(cls, msg):
        with cls.warnings_lock:
            cls.warnings.append((msg.name, msg.level, msg.msg))

    def flatsim_warnings(self):
        return self.logged('/flatsim', Log.WARN)

    def logged(self, node, level):
        with self.warnings_lock:
            return [text for name, lvl, text in self.warnings if name == node and lvl == level]

    def wait_for_log(self, node, level, text):
        wait_until(lambda: any(text in line for line in self.logged(node, level)),
                   'a log line from %s containing %r' % (node, text), sim_timeout=1e9, wall_timeout=10.0)

    def tearDown(self):
        # Every test starts from the robot's spawn pose, at rest, with no command.
        self.command_robot(0.0, 0.0)
        self.reset_world()

    def assert_nodes_alive(self):
        for name, pid in self.pids.items():
            self.assertIsNotNone(pid, '%s was not running at the start' % name)
            self.assertEqual(node_pid(name), pid, '%s is not the process it was at the start' % name)

    def robot_state(self):
        state = self.get_model_state(model_name=ROBOT)
        self.assertTrue(state.success, state.status_message)
        values = [state.pose.position.x, state.pose.position.y, state.pose.orientation.z,
                  state.pose.orientation.w, state.twist.linear.x, state.twist.linear.y, state.twist.angular.z]
        self.assertTrue(all(math.isfinite(v) for v in values), 'model state is not finite: %s' % state)
        return state

    def planar_speed(self):
        linear = self.robot_state().twist.linear
        return math.hypot(linear.x, linear.y)

    def publish(self, linear, angular):
        publish_while_paused(self.cmd_pub, linear, angular, self.pause, self.unpause)

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
        # Both are read while paused: the robot is moving, and in a world running faster
        # than real time the wall time between two readings is more of its driving.
        try:
            odom_x = odom_pose(paused_latest(self.pause, self.odom))[0]
            x = ground_truth(self.get_model_state, ROBOT)[0]
        finally:
            self.unpause()
        # Odometry comes at 50 Hz: the robot may have gone on for one period (0.02 s) since.
        self.assertAlmostEqual(x, odom_x, delta=0.01)
        wait_until(lambda: any('not finite' in text for text in self.flatsim_warnings()),
                   'a flatsim warning about the non-finite command', sim_timeout=5.0)
        self.publish(0.0, 0.0)

    def test_get_model_state_of_an_unknown_model_fails_as_in_gazebo(self):
        response = self.get_model_state(model_name='no_such_model')
        self.assertFalse(response.success)
        self.assertEqual(response.status_message, 'GetModelState: model does not exist')

    def test_set_model_state_of_an_unknown_model_fails_as_in_gazebo(self):
        pose = Pose()
        pose.orientation.w = 1.0
        response = self.set_model_state(model_name='no_such_model', pose=pose)
        self.assertFalse(response.success)
        self.assertEqual(response.status_message, 'SetModelState: model does not exist')

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
        scripts = find_node('gazebo_ros', 'spawn_model')
        self.assertTrue(scripts, 'rosrun cannot find gazebo_ros spawn_model')
        proc = subprocess.run(
            [scripts[0], '-urdf', '-param', 'no_such_description', '-model', 'ghost', '-timeout', '5'],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60, check=False)
        self.assertNotEqual(proc.returncode, 0, proc.stdout)
        self.assertIn('no_such_description', proc.stdout)
        self.assertIn('does not exist', proc.stdout)
        self.assertNotIn('Traceback', proc.stdout)
        self.assertFalse(self.get_model_state(model_name='ghost').success)

    def test_spawn_model_with_a_duplicate_name_or_a_missing_file_exits_with_a_clear_message(self):
        scripts = find_node('gazebo_ros', 'spawn_model')
        for args, lines in [
                (['-urdf', '-param', '/robot_description', '-model', ROBOT],
                 # gazebo_ros spawn_model's own two lines
                 ['Spawn status: SpawnModel: Failure - entity already exists.',
                  'Spawn service failed. Exiting.']),
                (['-sdf', '-file', '/nonexistent/ball.sdf', '-model', 'ball2'],
                 ['spawn_model: cannot spawn', 'specified file /nonexistent/ball.sdf does not exist'])]:
            proc = subprocess.run([scripts[0]] + args + ['-timeout', '20'], stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, timeout=60, check=False)
            self.assertEqual(proc.returncode, 1, proc.stdout)
            for line in lines:
                self.assertIn(line, proc.stdout)
            self.assertNotIn('Traceback', proc.stdout)
        self.assertFalse(self.get_model_state(model_name='ball2').success)
        self.robot_state()
        self.assert_nodes_alive()

    def test_huge_and_infinite_cmd_vel_keep_the_model_state_finite(self):
        for linear, angular in [(1e308, 0.0), (-math.inf, 0.0), (-1e308, 1e308), (1e30, -1e30),
                                (0.0, 1e308), (math.nan, math.nan)]:
            self.publish(linear, angular)
            wait_sim(0.5)
            self.robot_state()
            self.assertTrue(all(math.isfinite(v) for v in odom_pose(self.odom.get())))
        self.publish(0.0, 0.0)
        # Waited for rather than timed: on a busy machine the stop may reach flatsim
        # after the 0.3 s of wall time it is given while paused.
        wait_until(lambda: self.planar_speed() < 0.05, 'the robot stopping after a zero /cmd_vel',
                   sim_timeout=5.0)
        self.assert_nodes_alive()

    def test_drive_bot_refuses_non_finite_requests_and_clamps_huge_ones(self):
        for linear, angular, field in [(math.nan, 0.0, 'linear_x'), (math.inf, 0.0, 'linear_x'),
                                       (-math.inf, 0.0, 'linear_x'), (0.0, math.nan, 'angular_z'),
                                       (0.0, math.inf, 'angular_z')]:
            with self.assertRaises(rospy.ServiceException) as caught:
                self.command_robot(linear, angular)
            self.assertIn('refused drive request: %s must be a finite number' % field, str(caught.exception))
        self.wait_for_log('/drive_bot', Log.ERROR, 'refused drive request: angular_z must be a finite number')
        feedback = self.command_robot(1e308, -1e308).msg_feedback
        self.assertTrue(feedback.startswith('Velocities applied: linear_x=1 m/s, angular_z=-2 rad/s ('),
                        feedback)
        self.assertIn('linear_x 1e+308 clamped to max_linear_x 1', feedback)
        self.wait_for_log('/drive_bot', Log.WARN, 'clamped to max_angular_z 2')
        self.assertEqual(self.command_robot(-0.0, -0.0).msg_feedback,
                         'Velocities applied: linear_x=0 m/s, angular_z=0 rad/s')
        feedback = self.command_robot(1.7976931348623157e308, 1e300).msg_feedback
        self.assertIn('angular_z 1e+300 clamped to max_angular_z 2', feedback)
        self.assertEqual(self.command_robot(0.3, 0.0).msg_feedback,
                         'Velocities applied: linear_x=0.3 m/s, angular_z=0 rad/s')
        self.assert_nodes_alive()

    def test_process_image_reports_bad_images_and_still_chases(self):
        width, height = 40, 30
        self.image_pub.publish(image(height, width, 'rgb8', width * 3 - 1, bytes(width * height * 3)))
        self.wait_for_log('/process_image', Log.ERROR,
                          'bad image: step 119 is shorter than a rgb8 row of 40 pixels (120 bytes)')
        for bad in [image(height, width, 'rgb8', width * 3, bytes(width * height * 3 - 1)),
                    image(0, width, 'rgb8', width * 3, b''),
                    image(height, 0, 'rgb8', 0, b''),
                    image(0, 0, 'rgb8', 0, b'')]:
            self.image_pub.publish(bad)
            time.sleep(DELIVERY_S)
        for encoding in ['mono16', '16UC1', 'rgb16', 'yuv422']:
            self.image_pub.publish(image(height, width, encoding, width * 2, bytes(width * height * 2)))
            self.wait_for_log('/process_image', Log.ERROR, 'unsupported image encoding %r' % encoding)
        # A white ball on the left of a grey frame: process_image asks drive_bot to turn left.
        pixels = bytearray([120] * (width * height * 3))
        for row in range(10, 16):
            pixels[(row * width + 2) * 3:(row * width + 8) * 3] = b'\xff' * 18
        del self.cmd_vel_seen[:]
        self.image_pub.publish(image(height, width, 'rgb8', width * 3, pixels))
        wait_until(lambda: any(msg.angular.z > 0.1 for msg in list(self.cmd_vel_seen)),
                   'process_image steering toward a ball after the bad images', sim_timeout=1e9,
                   wall_timeout=10.0)
        self.assert_nodes_alive()

    # The loader's and the simulation's bounds, through the running node -------------------
    def clock_advances(self):
        start = rospy.get_time()
        wait_until(lambda: rospy.get_time() > start + 0.1, 'sim time moving on', sim_timeout=1e9,
                   wall_timeout=10.0)

    def test_a_twist_beyond_flatsims_bounds_is_refused_and_time_goes_on(self):
        before = ground_truth(self.get_model_state, ROBOT)
        response = gazebo_set_model_state(ModelState(
            model_name=ROBOT, pose=Pose(orientation=Quaternion(w=1.0)),
            twist=Twist(linear=Vector3(x=1e308))))
        self.assertFalse(response.success)
        self.assertIn('beyond the 100 m/s and 1000 rad/s flatsim simulates', response.status_message)
        self.clock_advances()
        self.assertAlmostEqual(ground_truth(self.get_model_state, ROBOT)[0], before[0], delta=0.5)
        self.assert_nodes_alive()

    def test_a_ball_too_small_to_simulate_is_refused_at_spawn(self):
        response = rospy.ServiceProxy('/gazebo/spawn_sdf_model', SpawnModel)(
            model_name='dust', model_xml=TINY_BALL_SDF, initial_pose=Pose(orientation=Quaternion(w=1.0)))
        self.assertFalse(response.success)
        self.assertIn("no shape flatsim can use; dust/link/collision: sphere radius '1e-300' is "
                      'outside the 0.0001 to 1e+06 m that flatsim simulates', response.status_message)
        self.clock_advances()
        self.assertFalse(self.get_model_state(model_name='dust').success)
        self.assert_nodes_alive()

    def test_a_robot_with_an_absurd_sensor_rate_or_a_thousand_links_spawns_without_stalling(self):
        spawn = rospy.ServiceProxy('/gazebo/spawn_urdf_model', SpawnModel)
        fast = rospy.get_param('/robot_description').replace(
            '<update_rate>30</update_rate>', '<update_rate>1e300</update_rate>')
        ticks = []
        clock = rospy.Subscriber('/clock', Clock, ticks.append)
        for name, xml in [('fast_robot', fast), ('chain', CHAIN_URDF)]:
            del ticks[:]
            response = spawn(model_name=name, model_xml=xml, robot_namespace='/' + name,
                             initial_pose=Pose(position=Point(x=-3.0, y=-3.0), orientation=Quaternion(w=1.0)))
            self.assertTrue(response.success, response.status_message)
            # The world kept stepping while the model was read.
            self.assertTrue(ticks, 'no /clock while %s was spawned' % name)
            self.clock_advances()
            delete = rospy.ServiceProxy('/gazebo/delete_model', DeleteModel)(model_name=name)
            self.assertTrue(delete.success, delete.status_message)
        clock.unregister()
        self.assert_nodes_alive()


TINY_BALL_SDF = ('<sdf version="1.6"><model name="dust"><link name="link"><collision name="collision">'
                 '<geometry><sphere><radius>1e-300</radius></sphere></geometry></collision></link>'
                 '</model></sdf>')
CHAIN_URDF = '<robot name="chain">%s%s</robot>' % (
    ''.join('<link name="l%d"><collision><origin xyz="0.05 0 0.1"/><geometry><box size="0.1 0.1 0.1"/>'
            '</geometry></collision></link>' % i for i in range(1000)),
    ''.join('<joint name="j%d" type="fixed"><parent link="l%d"/><child link="l%d"/>'
            '<origin xyz="0.001 0 0"/></joint>' % (i, i - 1, i) for i in range(1, 1000)))


def gazebo_set_model_state(state):
    return rospy.ServiceProxy('/gazebo/set_model_state', SetModelState)(state)


if __name__ == '__main__':
    rostest.rosrun('flatsim', 'bad_input', BadInputTest, sys.argv)
