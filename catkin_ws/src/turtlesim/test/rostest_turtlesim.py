#!/usr/bin/env python
"""turtlesim_node through ROS, as the tutorials use it: driving by cmd_vel
against the kinematics, the 1 s stop, the wall, spawn and kill, teleports,
pens and the canvas image, the rotation action, bad input, draw_square and
mimic. (turtle_teleop_key and the lesson's commands need roscore's rosout,
which rostest does not start: tests/test_lesson1.py runs them.)

Every wait is for an event (a message, a log line, a process ending), bounded
by WAIT_S of wall time so that a broken node fails the test instead of hanging.
"""
import math
import re
import signal
import subprocess
import sys
import threading
import time
import unittest

import actionlib
import numpy as np
import rosgraph
import roslib.packages
import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from geometry_msgs.msg import Twist
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import Image
from std_srvs.srv import Empty

from turtlesim.msg import Color, Pose, RotateAbsoluteAction, RotateAbsoluteGoal
from turtlesim.srv import Kill, SetPen, Spawn, TeleportAbsolute, TeleportRelative

WAIT_S = 15.0
# Wall seconds between commands that must each reach turtlesim (its cmd_vel queue holds one).
COMMAND_GAP_S = 0.1
DT = 0.016
CANVAS = float(np.float32(499.0) / np.float32(45.0))
CENTRE = float(np.float32(CANVAS) / np.float32(2.0))
BACKGROUND = (69, 86, 255)
RED = (255, 0, 0)


class Recorder:
    """Every message on a topic, in order, and waits for one that matches."""

    def __init__(self, topic, msg_type):
        self.messages = []
        self.condition = threading.Condition()
        self.subscriber = rospy.Subscriber(topic, msg_type, self._add, queue_size=100)

    def _add(self, message):
        with self.condition:
            self.messages.append(message)
            self.condition.notify_all()

    def mark(self):
        with self.condition:
            return len(self.messages)

    def wait(self, predicate, what, since=0, timeout=WAIT_S):
        """The first message from index `since` on that satisfies predicate, and its index."""
        deadline = time.monotonic() + timeout
        with self.condition:
            index = since
            while True:
                while index < len(self.messages):
                    if predicate(self.messages[index]):
                        return self.messages[index], index
                    index += 1
                remaining = deadline - time.monotonic()
                if remaining <= 0:
                    last = self.messages[-1] if self.messages else None
                    raise AssertionError('%s: not within %.1f s (last message: %s)' % (what, timeout, last))
                self.condition.wait(remaining)


def wait_until(predicate, what):
    deadline = time.monotonic() + WAIT_S
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError('%s: not within %.0f s' % (what, WAIT_S))
        time.sleep(0.01)


def call(name, srv_type, *args):
    rospy.wait_for_service(name, WAIT_S)
    return rospy.ServiceProxy(name, srv_type)(*args)


def twist(linear_x=0.0, angular_z=0.0, linear_y=0.0):
    message = Twist()
    message.linear.x, message.linear.y, message.angular.z = linear_x, linear_y, angular_z
    return message


def picture(image):
    return np.frombuffer(image.data, dtype=np.uint8).reshape(image.height, image.width, 3)


def to_pixel(x, y):
    """(row, column) of pose coordinates (y up from the bottom)."""
    return int(math.floor((CANVAS - y) * 45 + 0.5)), int(math.floor(x * 45 + 0.5))


def node_executable(name):
    """The devel space's executable for one of the package's nodes: what rosrun runs, without its start-up."""
    return roslib.packages.find_node('turtlesim', name)[0]


class TurtlesimTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node('turtlesim_test')
        cls.poses = Recorder('turtle1/pose', Pose)
        cls.colors = Recorder('turtle1/color_sensor', Color)
        cls.images = Recorder('turtlesim/image', Image)
        cls.logs = Recorder('/rosout', Log)
        cls.cmd_vel = rospy.Publisher('turtle1/cmd_vel', Twist, queue_size=10)
        wait_until(lambda: cls.cmd_vel.get_num_connections() >= 1, 'turtlesim subscribing to turtle1/cmd_vel')
        # Log lines count only once /rosout is connected: clear until one arrives.
        deadline = time.monotonic() + WAIT_S
        while True:
            mark = cls.logs.mark()
            call('clear', Empty)
            try:
                cls.logs.wait(lambda m: m.name == '/turtlesim' and m.msg == 'Clearing turtlesim.',
                              'turtlesim logging to /rosout', mark, timeout=0.5)
                break
            except AssertionError:
                if time.monotonic() > deadline:
                    raise

    def setUp(self):
        mark = self.poses.mark()
        call('reset', Empty)
        self.poses.wait(lambda p: (p.x, p.y, p.theta, p.linear_velocity) == (CENTRE, CENTRE, 0.0, 0.0),
                        'turtle1 back in the centre after reset', mark)

    def log_line(self, pattern, since, level=None):
        message, _ = self.logs.wait(
            lambda m: m.name == '/turtlesim' and re.search(pattern, m.msg) and (level is None or m.level == level),
            'turtlesim logging %r' % pattern, since)
        return message

    def drive_until_stopped(self, linear_x, angular_z=0.0, pose_topic=None):
        """Publish one command; the pose where the turtle has stopped again."""
        poses = pose_topic or self.poses
        mark = poses.mark()
        self.cmd_vel.publish(twist(linear_x, angular_z))
        _, moving = poses.wait(lambda p: p.linear_velocity != 0 or p.angular_velocity != 0, 'moving', mark)
        stopped, _ = poses.wait(lambda p: p.linear_velocity == 0 and p.angular_velocity == 0,
                                'stopped by itself', moving)
        return stopped

    def drive_along_x(self, to_x):
        """Drive turtle1 (facing +x) at 2 m/s, commanding again whenever it stops, until it passes to_x;
        the pose where it then stops."""
        while True:
            stopped = self.drive_until_stopped(2.0)
            if stopped.x >= to_x:
                return stopped

    def teleport(self, x, y, theta):
        mark = self.poses.mark()
        call('turtle1/teleport_absolute', TeleportAbsolute, x, y, theta)
        return self.poses.wait(lambda p: abs(p.x - x) < 1e-5 and abs(p.y - y) < 1e-5, 'teleported', mark)[0]

    def test_drive_follows_the_kinematics_and_stops_after_one_second(self):
        speed, turn = 1.0, 0.5
        stopped = self.drive_until_stopped(speed, turn)
        ticks = int(round(stopped.theta / (turn * DT)))
        # A command lasts 1 s of wall time: at most 63 updates of 16 ms; fewer if the machine is busy.
        self.assertLessEqual(ticks, 63)
        self.assertGreaterEqual(ticks, 10)
        self.assertAlmostEqual(stopped.theta, ticks * turn * DT, delta=1e-5)
        headings = [k * turn * DT for k in range(1, ticks + 1)]
        self.assertAlmostEqual(stopped.x, CENTRE + sum(math.cos(h) for h in headings) * speed * DT, delta=1e-4)
        self.assertAlmostEqual(stopped.y, CENTRE + sum(math.sin(h) for h in headings) * speed * DT, delta=1e-4)
        mark = self.poses.mark()
        later, _ = self.poses.wait(lambda p: True, 'a pose after stopping', mark + 5)
        self.assertEqual((later.x, later.y, later.theta), (stopped.x, stopped.y, stopped.theta))

    def test_the_wall_clamps_the_turtle_with_the_originals_warning(self):
        self.teleport(10.8, 3.0, 0.0)
        mark = self.logs.mark()
        stopped = self.drive_until_stopped(2.0)
        self.assertEqual((stopped.x, stopped.y), (CANVAS, 3.0))
        warning = self.log_line(r'^Oh no! I hit the wall! \(Clamping from \[x=11\.\d{6}, y=8\.088889\]\)$',
                                mark, Log.WARN)
        self.assertGreater(float(warning.msg.split('x=')[1].split(',')[0]), CANVAS)

    def test_spawn_names_places_and_kill_removes_turtles(self):
        mark = self.logs.mark()
        self.assertEqual(call('spawn', Spawn, 2.0, 3.0, 0.5, '').name, 'turtle2')
        self.log_line(r'^Spawning turtle \[turtle2\] at x=\[2\.000000\], y=\[3\.000000\], theta=\[0\.500000\]$',
                      mark)
        turtle2 = Recorder('turtle2/pose', Pose)
        pose, _ = turtle2.wait(lambda p: True, 'turtle2 publishing its pose')
        self.assertEqual((pose.x, pose.y, pose.theta), (2.0, 3.0, 0.5))
        with self.assertRaisesRegex(rospy.ServiceException, r'A turtled named \[turtle2\] already exists'):
            call('spawn', Spawn, 1.0, 1.0, 0.0, 'turtle2')
        call('kill', Kill, 'turtle2')
        master = rosgraph.Master(rospy.get_name())
        wait_until(lambda: not any(t == '/turtle2/pose' for t, _ in master.getPublishedTopics('/')),
                   'turtle2/pose unadvertised')
        with self.assertRaises(rosgraph.MasterError):
            master.lookupService('/turtle2/set_pen')
        with self.assertRaisesRegex(rospy.ServiceException, r'Tried to kill turtle \[turtle2\], which does not exist'):
            call('kill', Kill, 'turtle2')
        self.assertEqual(call('spawn', Spawn, 1.0, 1.0, 0.0, '').name, 'turtle3')
        self.assertEqual(call('spawn', Spawn, 1.0, 1.0, 0.0, 'turtle2').name, 'turtle2')
        turtle2.subscriber.unregister()

    def test_teleport_absolute_then_relative(self):
        self.teleport(2.0, 3.0, 1.0)
        mark = self.poses.mark()
        call('turtle1/teleport_relative', TeleportRelative, 1.0, 0.5)
        pose, _ = self.poses.wait(lambda p: abs(p.theta - 1.5) < 1e-5, 'turned by teleport_relative', mark)
        self.assertAlmostEqual(pose.x, 2.0 + math.cos(1.5), delta=1e-5)
        self.assertAlmostEqual(pose.y, 3.0 + math.sin(1.5), delta=1e-5)

    def test_the_pen_draws_the_path_on_the_published_canvas(self):
        call('turtle1/set_pen', SetPen, 0, 0, 0, 0, 1)
        self.teleport(1.0, 1.0, 0.0)
        call('turtle1/set_pen', SetPen, 255, 0, 0, 5, 0)
        stopped = self.drive_along_x(3.0)
        self.colors.wait(lambda c: (c.r, c.g, c.b) == RED, 'the colour sensor reading the red line',
                         self.colors.mark())
        stamp = rospy.Time.now()
        image, _ = self.images.wait(lambda m: m.header.stamp > stamp, 'a canvas image after the drive',
                                    self.images.mark())
        self.assertEqual((image.encoding, image.width, image.height, image.step), ('rgb8', 500, 500, 1500))
        canvas = picture(image)
        row, start = to_pixel(1.0, 1.0)
        _, end = to_pixel(stopped.x, 1.0)
        # Leave out the start and the turtle drawn over the end of the line.
        line = canvas[row - 2:row + 3, start + 3:end - 25]
        self.assertTrue(np.all(line == RED), 'the width-5 line is red throughout')
        for outside in (row - 4, row + 4):
            self.assertTrue(np.all(canvas[outside, start + 3:end - 25] == BACKGROUND))
        # The pen lifted: a drive leaves no trace.
        call('turtle1/set_pen', SetPen, 0, 255, 0, 5, 1)
        self.teleport(1.0, 5.0, 0.0)
        stopped = self.drive_along_x(3.0)
        stamp = rospy.Time.now()
        image, _ = self.images.wait(lambda m: m.header.stamp > stamp, 'an image after the pen-up drive',
                                    self.images.mark())
        row, start = to_pixel(1.0, 5.0)
        _, end = to_pixel(stopped.x, 5.0)
        self.assertTrue(np.all(picture(image)[row - 2:row + 3, start + 3:end - 25] == BACKGROUND))

    def test_clear_reads_the_background_parameters_again(self):
        try:
            rospy.set_param('/turtlesim/background_r', 10)
            rospy.set_param('/turtlesim/background_g', 'green')
            rospy.set_param('/turtlesim/background_b', 30)
            mark, log_mark = self.colors.mark(), self.logs.mark()
            call('clear', Empty)
            self.colors.wait(lambda c: (c.r, c.g, c.b) == (10, 86, 30), 'the new background, g at its default',
                             mark)
            self.log_line(r'background_g must be an integer from 0 to 255', log_mark, Log.WARN)
        finally:
            for channel, value in zip('rgb', BACKGROUND):
                rospy.set_param('/turtlesim/background_' + channel, value)

    def test_rotate_absolute_turns_in_place_and_a_velocity_command_aborts_it(self):
        client = actionlib.SimpleActionClient('turtle1/rotate_absolute', RotateAbsoluteAction)
        self.assertTrue(client.wait_for_server(rospy.Duration(WAIT_S)))
        client.send_goal(RotateAbsoluteGoal(theta=0.5))
        self.assertTrue(client.wait_for_result(rospy.Duration(WAIT_S)))
        self.assertEqual(client.get_state(), GoalStatus.SUCCEEDED)
        self.assertAlmostEqual(client.get_result().delta, -0.5, delta=0.021)
        pose, _ = self.poses.wait(lambda p: p.angular_velocity == 0, 'still', self.poses.mark())
        self.assertAlmostEqual(pose.theta, 0.5, delta=0.021)
        self.assertEqual((pose.x, pose.y), (CENTRE, CENTRE))
        feedback = []
        client.send_goal(RotateAbsoluteGoal(theta=3.0), feedback_cb=feedback.append)
        wait_until(lambda: feedback, 'rotation feedback')
        self.cmd_vel.publish(twist(1.0))
        self.assertTrue(client.wait_for_result(rospy.Duration(WAIT_S)))
        self.assertEqual(client.get_state(), GoalStatus.ABORTED)

    def test_bad_input_gets_an_error_or_the_originals_behaviour_and_turtlesim_stays_up(self):
        mark, pose_mark = self.logs.mark(), self.poses.mark()
        for bad in (float('nan'), float('inf'), -float('inf')):
            for command in (twist(bad, 1.0), twist(1.0, 1.0, linear_y=bad)):
                self.cmd_vel.publish(command)
                # turtlesim's cmd_vel queue holds one message, as the original's does: sent at
                # once, the next could take a command's place before it is handled.
                time.sleep(COMMAND_GAP_S)
        # Messages on one connection arrive in order: once this one shows, the bad ones were handled.
        self.cmd_vel.publish(twist(0.0, 1e-3))
        self.log_line(r'^Ignored a velocity command for turtle1: .*finite', mark, Log.WARN)
        pose, _ = self.poses.wait(lambda p: p.angular_velocity == np.float32(1e-3), 'the good command', pose_mark)
        self.assertEqual((pose.x, pose.y), (CENTRE, CENTRE))
        bad_requests = [
            ('turtle1/teleport_absolute', TeleportAbsolute, (float('nan'), 1.0, 0.0), 'finite'),
            ('turtle1/teleport_relative', TeleportRelative, (float('inf'), 0.0), 'finite'),
            ('spawn', Spawn, (float('nan'), 1.0, 0.0, ''), 'finite'),
            ('spawn', Spawn, (1.0, 1.0, 0.0, 'no spaces!'), 'not a legal ROS name'),
            ('kill', Kill, ('nobody',), r'Tried to kill turtle \[nobody\], which does not exist'),
        ]
        for service, srv_type, args, error in bad_requests:
            with self.assertRaisesRegex(rospy.ServiceException, error):
                call(service, srv_type, *args)
        with self.assertRaises(rospy.ROSException):
            rospy.wait_for_service('nobody/teleport_absolute', 0.1)
        # Off the canvas: spawned where asked, then clamped to the wall, as the original does.
        mark = self.logs.mark()
        self.assertEqual(call('spawn', Spawn, 20.0, 20.0, 0.0, 'far').name, 'far')
        far_poses = Recorder('far/pose', Pose)
        far, _ = far_poses.wait(lambda p: True, 'far publishing its pose')
        far_poses.subscriber.unregister()
        self.assertEqual((far.x, far.y), (CANVAS, CANVAS))
        self.log_line(r'^Oh no! I hit the wall!', mark)
        # Pen width 0 is Qt's default pen, 1 pixel wide.
        call('turtle1/set_pen', SetPen, 0, 0, 0, 0, 0)
        self.drive_until_stopped(1.0)
        self.colors.wait(lambda c: (c.r, c.g, c.b) == (0, 0, 0), 'a black line', self.colors.mark())
        pose, _ = self.poses.wait(lambda p: True, 'turtle1 still published', self.poses.mark())
        self.assertTrue(all(math.isfinite(v) for v in (pose.x, pose.y, pose.theta)))
        self.assertGreater(pose.x, CENTRE)

    def test_draw_square_resets_and_drives_the_first_side(self):
        mark = self.logs.mark()
        square = subprocess.Popen([node_executable('draw_square')], stdout=subprocess.DEVNULL,
                                  stderr=subprocess.DEVNULL)
        try:
            self.logs.wait(lambda m: m.name == '/draw_square' and m.msg == 'New goal [%f %f, %f]'
                           % (CENTRE + 2.0, CENTRE, 0.0), 'draw_square aiming 2 m ahead of the centre', mark)
            pose, _ = self.poses.wait(lambda p: p.linear_velocity == 1.0 and p.x > CENTRE,
                                      'turtle1 driving the first side', self.poses.mark())
            self.assertEqual((pose.y, pose.theta), (CENTRE, 0.0))
        finally:
            square.send_signal(signal.SIGINT)
            square.wait(WAIT_S)

    def test_mimic_copies_turtle1s_motion_onto_another_turtle(self):
        call('spawn', Spawn, 2.0, 2.0, 0.0, 'copycat')
        copycat = Recorder('copycat/pose', Pose)
        copycat.wait(lambda p: True, 'copycat publishing its pose')
        self.cmd_vel.publish(twist(1.0, 0.5))
        copycat.wait(lambda p: p.linear_velocity == 1.0 and p.angular_velocity == 0.5,
                     'copycat moving as turtle1 does', copycat.mark())
        copycat.subscriber.unregister()


if __name__ == '__main__':
    rostest.rosrun('turtlesim', 'turtlesim', TurtlesimTest, sys.argv)
