#!/usr/bin/env python
"""The course's rosservice examples against drive_bot and the simulated robot:
linear_x 0.5 drives forward, angular_z 0.5 turns left (yaw grows), -0.5 turns
right, 0 0 stops; a NaN request is refused and publishes nothing on cmd_vel.

Each command runs for about DRIVE_S of sim time from the origin, facing +x;
the checks are on mean speeds over the sim time that really passed, since the
simulator runs on for a little while the test asks it to pause.
"""
import math
import sys
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist

from rostest_chase_support import HIDDEN_BALL_XY, ROBOT, ChaseRig, angle_difference, yaw_of

DRIVE_S = 1.0
# Wall time for a cmd_vel message to reach flatsim while physics is paused.
DELIVERY_WALL_S = 0.3


class CommandRobot(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.rig = ChaseRig(needs_process_image=False)
        cls.cmd_vel = []
        rospy.Subscriber('/cmd_vel', Twist, cls.cmd_vel.append, queue_size=10)
        cls.rig.pause()
        cls.rig.move_ball(*HIDDEN_BALL_XY)

    def paused_time(self):
        """Sim time once physics is paused and the last /clock has arrived."""
        time.sleep(DELIVERY_WALL_S)
        return rospy.get_time()

    def drive(self, linear_x, angular_z, seconds=DRIVE_S):
        """Robot at the origin, stopped; the command is applied; sim runs.
        Returns mean (x speed, y speed, yaw rate) in the world frame."""
        self.rig.pause()
        self.rig.command_robot(0.0, 0.0)
        self.rig.move(ROBOT, 0.0, 0.0)
        response = self.rig.command_robot(linear_x, angular_z)
        self.assertIn('linear_x=%g' % linear_x, response.msg_feedback)
        self.assertIn('angular_z=%g' % angular_z, response.msg_feedback)
        start = self.paused_time()
        self.rig.unpause()
        self.rig.run_for(seconds)
        self.rig.pause()
        elapsed = self.paused_time() - start
        pose = self.rig.pose(ROBOT)
        motion = (pose.position.x / elapsed, pose.position.y / elapsed,
                  angle_difference(yaw_of(pose), 0.0) / elapsed)
        rospy.loginfo('linear_x %g angular_z %g for %.2f s: mean vx %.3f m/s, vy %.3f m/s, yaw rate %.3f rad/s',
                      linear_x, angular_z, elapsed, *motion)
        return motion

    def test_forward(self):
        vx, vy, yaw_rate = self.drive(0.5, 0.0)
        self.assertGreater(vx, 0.35)
        self.assertLessEqual(vx, 0.5 + 1e-6)
        self.assertLess(abs(vy), 0.02)
        self.assertLess(abs(yaw_rate), 0.02)

    def test_turn_left(self):
        vx, vy, yaw_rate = self.drive(0.0, 0.5)
        self.assertGreater(yaw_rate, 0.35)
        self.assertLessEqual(yaw_rate, 0.5 + 1e-6)
        self.assertLess(math.hypot(vx, vy), 0.02)

    def test_turn_right(self):
        vx, vy, yaw_rate = self.drive(0.0, -0.5)
        self.assertLess(yaw_rate, -0.35)
        self.assertGreaterEqual(yaw_rate, -0.5 - 1e-6)
        self.assertLess(math.hypot(vx, vy), 0.02)

    def test_stop(self):
        self.drive(0.5, 0.0)
        self.rig.command_robot(0.0, 0.0)
        self.paused_time()
        self.rig.unpause()
        self.rig.run_for(0.5)
        stopped = self.rig.pose(ROBOT)
        self.rig.run_for(DRIVE_S)
        self.rig.pause()
        later = self.rig.pose(ROBOT)
        self.assertLess(math.hypot(later.position.x - stopped.position.x,
                                   later.position.y - stopped.position.y), 0.005)
        self.assertLess(abs(angle_difference(yaw_of(later), yaw_of(stopped))), 0.005)

    def test_nan_is_refused_and_publishes_nothing(self):
        self.rig.command_robot(0.2, 0.0)
        time.sleep(DELIVERY_WALL_S)
        published = len(self.cmd_vel)
        self.assertGreater(published, 0, 'cmd_vel is not reaching this test')
        for request in ((float('nan'), 0.0), (0.0, float('nan')), (float('inf'), 0.0)):
            with self.assertRaises(rospy.ServiceException, msg='%r was accepted' % (request,)):
                self.rig.command_robot(*request)
        time.sleep(DELIVERY_WALL_S)
        self.assertEqual(len(self.cmd_vel), published, 'a refused request published on cmd_vel')
        self.assertEqual((self.cmd_vel[-1].linear.x, self.cmd_vel[-1].angular.z), (0.2, 0.0))


def main():
    rospy.init_node('command_robot')
    rostest.rosrun('ball_chaser', 'command_robot', CommandRobot, sys.argv)


if __name__ == '__main__':
    main()
