#!/usr/bin/env python3
"""The arm through ROS: command topics, safe_move's clamp and rosparam, the camera, bad input.

The launch starts robot_spawn.launch with look_away off and arm_mover's
max_joint_2_angle at 1.0 (the lesson's first setting), as fast as possible.
Joint 2 holds the upper link against gravity with p = 100 and no integral
action (i without i_clamp does nothing in ros_control), so it settles past
its goal by m g l / p = 1 kg * 9.81 m/s^2 * 0.375 m / 100 = 0.037 rad when
the link is horizontal.
"""
import math
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rospy
import rostest
from controller_manager_msgs.srv import ListControllers, LoadController
from sensor_msgs.msg import Image, JointState
from std_msgs.msg import Float64

from simple_arm.srv import GoToPosition

WALL_LIMIT_S = 60.0
SAG = 1.0 * 9.81 * 0.375 / 100.0
WIDTH, HEIGHT, HFOV = 640, 480, 1.4


class Latest:
    def __init__(self, topic, kind):
        self.msg = None
        self.count = 0
        self.sub = rospy.Subscriber(topic, kind, self.on_msg, queue_size=1)

    def on_msg(self, msg):
        self.msg = msg
        self.count += 1

    def fresh(self, wall_timeout=WALL_LIMIT_S):
        count = self.count
        deadline = time.time() + wall_timeout
        while self.count <= count + 1:
            if time.time() > deadline or rospy.is_shutdown():
                raise AssertionError('no message on %s' % self.sub.name)
            time.sleep(0.005)
        return self.msg


def wait_until(predicate, what, sim_timeout=15.0):
    """sim_timeout None waits in wall time only, for what takes wall time however fast the world runs."""
    start = rospy.get_time()
    deadline = time.time() + WALL_LIMIT_S
    while not predicate():
        if (sim_timeout is not None and rospy.get_time() - start > sim_timeout) or time.time() > deadline:
            raise AssertionError('timed out waiting for %s' % what)
        time.sleep(0.01)


def read_until(process, text, wall_timeout=WALL_LIMIT_S):
    """The process's output up to and including the line that holds text."""
    lines = []
    deadline = time.time() + wall_timeout
    while time.time() < deadline:
        ready, _, _ = select.select([process.stdout], [], [], 0.5)
        if ready:
            line = process.stdout.readline()
            if not line:
                break
            lines.append(line)
            if text in line:
                break
    return ''.join(lines)


class ArmTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('arm_test')
        cls.joints = Latest('/simple_arm/joint_states', JointState)
        cls.image = Latest('/rgb_camera/image_raw', Image)
        cls.commands = [rospy.Publisher('/simple_arm/joint_%d_position_controller/command' % j,
                                        Float64, queue_size=1, latch=True) for j in (1, 2)]
        rospy.wait_for_service('/arm_mover/safe_move', timeout=WALL_LIMIT_S)
        cls.safe_move = rospy.ServiceProxy('/arm_mover/safe_move', GoToPosition)
        rospy.wait_for_service('/simple_arm/controller_manager/list_controllers', timeout=WALL_LIMIT_S)
        cls.list_controllers = rospy.ServiceProxy('/simple_arm/controller_manager/list_controllers',
                                                  ListControllers)
        wait_until(lambda: sum(c.state == 'running' for c in cls.list_controllers().controller) == 3,
                   'the spawner to start three controllers', sim_timeout=None)
        cls.load = rospy.ServiceProxy('/simple_arm/controller_manager/load_controller', LoadController)

    def positions(self):
        msg = self.joints.fresh()
        self.assertEqual(list(msg.name), ['joint_1', 'joint_2'])
        return msg.position

    def settle(self, goal, tolerance=0.01, sim_timeout=8.0):
        """Wait until both joints are within tolerance of goal and still; returns the positions."""
        def settled():
            msg = self.joints.fresh()
            return (all(abs(p - g) < tolerance for p, g in zip(msg.position, goal))
                    and all(abs(v) < 0.01 for v in msg.velocity))
        wait_until(settled, 'joints at %s' % (goal,), sim_timeout)
        return self.positions()

    def test_1_camera_sees_uniform_sky_at_the_start(self):
        position = self.positions()
        self.assertLess(max(abs(p) for p in position), 0.01)
        data = bytes(self.image.fresh().data)
        self.assertEqual(data.count(data[0]), len(data))

    def test_2_command_topics_move_each_joint(self):
        self.commands[0].publish(Float64(0.8))
        self.commands[1].publish(Float64(0.0))
        self.settle((0.8, 0.0))
        self.commands[1].publish(Float64(0.6))
        # Joint 2 at 0.6 rad holds the link against gravity: it sags by SAG * sin(0.6).
        self.settle((0.8, 0.6 + SAG * math.sin(0.6)), tolerance=0.005)

    def test_3_safe_move_clamps_then_obeys_the_new_parameter(self):
        reply = self.safe_move(1.57, 1.57)
        self.assertEqual(reply.msg_feedback, 'Joint angles set - j1: 1.570000 , j2: 1.000000')
        self.settle((1.57, 1.0 + SAG * math.sin(1.0)), tolerance=0.005)
        rospy.set_param('/arm_mover/max_joint_2_angle', 1.57)
        reply = self.safe_move(1.57, 1.57)
        self.assertEqual(reply.msg_feedback, 'Joint angles set - j1: 1.570000 , j2: 1.570000')
        self.settle((1.57, 1.57 + SAG), tolerance=0.005)
        data = bytes(self.image.fresh().data)
        self.assertNotEqual(data.count(data[0]), len(data), 'the camera should see the kitchen')

    def test_4_horizon_where_the_pinhole_model_puts_it(self):
        # Facing -y, away from the kitchen, tipped past horizontal: floor and sky only.
        self.commands[0].publish(Float64(-1.57))
        self.commands[1].publish(Float64(2.0))
        self.settle((-1.57, 2.0), tolerance=0.05)
        position = self.positions()
        msg = self.image.fresh()
        pixels = bytes(msg.data)
        pitch = position[1] - math.pi / 2      # the camera looks up link_2, which tips by joint 2
        focal = WIDTH / (2 * math.tan(HFOV / 2))
        horizon = (HEIGHT - 1) / 2.0 - focal * math.tan(pitch)
        column = WIDTH // 2
        sky = pixels[0:3]
        first_floor = next(row for row in range(HEIGHT)
                           if pixels[(row * WIDTH + column) * 3:(row * WIDTH + column) * 3 + 3] != sky)
        self.assertAlmostEqual(first_floor, math.floor(horizon) + 1, delta=1)

    def test_5_bad_input_gets_clear_errors_and_nothing_dies(self):
        # A NaN command: ros_control's PID gives no effort; the joint keeps being simulated.
        self.commands[0].publish(Float64(float('nan')))
        self.positions()
        self.commands[0].publish(Float64(0.5))
        self.settle((0.5, self.positions()[1]), tolerance=0.05, sim_timeout=10.0)
        # An unknown controller type, a controller without parameters, a joint without transmission.
        rospy.set_param('/simple_arm/bogus_controller', {'type': 'effort_controllers/NoSuchController',
                                                         'joint': 'joint_1'})
        rospy.set_param('/simple_arm/camera_controller', {
            'type': 'effort_controllers/JointPositionController', 'joint': 'camera_joint',
            'pid': {'p': 1.0}})
        for name in ('bogus_controller', 'no_parameters_controller', 'camera_controller'):
            self.assertFalse(self.load(name).ok, name)
        # A spawner given a YAML file that is not there, one that is not YAML, and a
        # controller with no parameters says so for each and keeps going.
        broken = tempfile.NamedTemporaryFile('w', suffix='.yaml', delete=False)
        broken.write('joint_1_position_controller: {type: [unclosed\n')
        broken.close()
        spawner = subprocess.Popen(
            ['rosrun', 'controller_manager', 'spawner', '--namespace', '/simple_arm',
             '/nonexistent/controllers.yaml', broken.name, 'no_such_controller', '__name:=bad_spawner'],
            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, start_new_session=True)
        output = read_until(spawner, 'Failed to load no_such_controller')
        still_running = spawner.poll() is None
        os.killpg(spawner.pid, signal.SIGKILL)
        spawner.wait(timeout=30)
        os.unlink(broken.name)
        self.assertIn('looks like a YAML file of controllers, but there is no such file', output)
        self.assertIn('Failed to load /nonexistent/controllers.yaml', output)
        self.assertIn('cannot load %s: while parsing' % broken.name, output)
        self.assertIn('Failed to load no_such_controller', output)
        self.assertNotIn('Traceback', output)
        self.assertTrue(still_running, 'the spawner should keep running after bad arguments')
        # flatsim still steps, and the launch's controllers still run and answer.
        self.assertEqual(sorted(c.name for c in self.list_controllers().controller if c.state == 'running'),
                         ['joint_1_position_controller', 'joint_2_position_controller',
                          'joint_state_controller'])
        self.positions()
        self.assertTrue(self.safe_move(0.2, 0.2).msg_feedback.startswith('Joint angles set'))

    def test_6_safe_move_refuses_a_target_too_large_to_track(self):
        # Without bounds arm_mover passes a finite request on; at 1e308 the controller's error
        # would never shrink and joint 1, a continuous joint, would spin without end.
        bounds = {name: rospy.get_param('/arm_mover/%s' % name) for name in
                  ('min_joint_1_angle', 'max_joint_1_angle')}
        for name in bounds:
            rospy.delete_param('/arm_mover/%s' % name)
        try:
            for target in (1e308, -1e308):
                with self.assertRaises(rospy.ServiceException) as refused:
                    self.safe_move(target, 0.3)
                self.assertIn('j1=%g: too large to track' % target, str(refused.exception))
        finally:
            for name, value in bounds.items():
                rospy.set_param('/arm_mover/%s' % name, value)
        self.assertTrue(self.safe_move(0.4, 0.3).msg_feedback.startswith('Joint angles set'))
        self.settle((0.4, 0.3 + SAG * math.sin(0.3)), tolerance=0.05)


if __name__ == '__main__':
    rostest.rosrun('simple_arm', 'arm', ArmTest, sys.argv)
