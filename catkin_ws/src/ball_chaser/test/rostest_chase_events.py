#!/usr/bin/env python
"""What the chaser does when the ball moves under it: moved within sight it is
re-acquired and reached; moved out of sight, the robot stops and stays still
(default search_turn 0). With ~search_turn set, process_image turns to find a
ball that starts behind the robot.

Private parameters:
  ~search (bool, default false): run only the search test, for a launch that
      sets process_image's ~proportional/search_turn above 0.
"""
import math
import sys
import unittest

import rospy
import rostest
from geometry_msgs.msg import Twist

from rostest_chase_support import (CHASE_TIMEOUT_S, HIDDEN_BALL_XY, REACH_M, ROBOT, ChaseRig,
                                   angle_difference, planar_distance, yaw_of)

MOVE_WHEN_WITHIN_M = 1.3
# Where the ball goes mid-run: this far ahead of the robot and this far to its right.
MOVED_AHEAD_M = 1.3
MOVED_BEARING_RAD = -math.radians(30.0)
STOPPING_S = 1.0
STILL_FOR_S = 3.0
STILL_TOLERANCE_M = 0.01
STILL_TOLERANCE_RAD = 0.01


class ChaseEvents(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.rig = ChaseRig()
        cls.last_cmd_vel = None
        rospy.Subscriber('/cmd_vel', Twist, cls._remember_cmd_vel, queue_size=10)

    @classmethod
    def _remember_cmd_vel(cls, message):
        cls.last_cmd_vel = message

    def point_ahead(self, distance, bearing):
        robot = self.rig.pose(ROBOT)
        heading = yaw_of(robot) + bearing
        return (robot.position.x + distance * math.cos(heading),
                robot.position.y + distance * math.sin(heading))

    def test_1_moved_ball_is_reacquired_and_reached(self):
        self.rig.reset((0.0, 0.0, 0.0), (2.5, 0.0))
        moved_to = []

        def move_ball_once(_elapsed):
            if not moved_to and self.rig.distance() < MOVE_WHEN_WITHIN_M:
                moved_to.append(self.point_ahead(MOVED_AHEAD_M, MOVED_BEARING_RAD))
                self.rig.move_ball(*moved_to[0])
                rospy.loginfo('moved the ball to (%.2f, %.2f)', *moved_to[0])

        result = self.rig.chase(on_poll=move_ball_once)
        rospy.loginfo('moved ball: %s', result)
        self.assertTrue(moved_to, 'the robot never came within %.1f m of the first ball' % MOVE_WHEN_WITHIN_M)
        self.assertTrue(result.reached, 'the moved ball was not reached in %.0f s: %s' % (CHASE_TIMEOUT_S, result))
        gap_to_new_spot = math.hypot(result.ball.position.x - moved_to[0][0],
                                     result.ball.position.y - moved_to[0][1])
        self.assertLess(gap_to_new_spot, 0.15, 'the ball was reached far from where it was moved: %s' % result)

    def check_stops_when_ball_leaves_view(self, hide_ball):
        self.rig.reset((0.0, 0.0, 0.0), (2.5, 0.0))
        start = self.rig.pose(ROBOT)
        self.rig.unpause()
        self.rig.run_for(1.5)
        chasing = self.rig.pose(ROBOT)
        self.assertGreater(planar_distance(start, chasing), 0.2, 'the robot did not start chasing')
        hide_ball()
        self.rig.run_for(STOPPING_S)
        stopped = self.rig.pose(ROBOT)
        self.rig.run_for(STILL_FOR_S)
        later = self.rig.pose(ROBOT)
        moved = planar_distance(stopped, later)
        turned = abs(angle_difference(yaw_of(later), yaw_of(stopped)))
        rospy.loginfo('no ball in view: moved %.4f m and turned %.4f rad in %.0f s', moved, turned, STILL_FOR_S)
        self.assertLess(moved, STILL_TOLERANCE_M)
        self.assertLess(turned, STILL_TOLERANCE_RAD)
        self.assertIsNotNone(self.last_cmd_vel)
        self.assertEqual((self.last_cmd_vel.linear.x, self.last_cmd_vel.angular.z), (0.0, 0.0))

    def test_2_ball_moved_behind_the_robot_stops_it(self):
        self.check_stops_when_ball_leaves_view(
            lambda: self.rig.move_ball(*self.point_ahead(1.5, math.pi)))

    def test_3_ball_moved_out_of_the_house_stops_it(self):
        self.check_stops_when_ball_leaves_view(lambda: self.rig.move_ball(*HIDDEN_BALL_XY))


class ChaseSearch(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.rig = ChaseRig()

    def test_ball_behind_the_robot_is_found_and_reached(self):
        search_turn = rospy.get_param('/process_image/proportional/search_turn')
        self.assertGreater(search_turn, 0, 'this test needs process_image searching')
        self.rig.reset((0.0, 0.0, 0.0), (-1.5, 0.3))
        result = self.rig.chase()
        rospy.loginfo('search: %s', result)
        self.assertTrue(result.reached, 'the ball behind the robot was not reached in %.0f s: %s'
                        % (CHASE_TIMEOUT_S, result))


def main():
    rospy.init_node('chase_events')
    case = ChaseSearch if rospy.get_param('~search', False) else ChaseEvents
    rostest.rosrun('ball_chaser', 'chase_events', case, sys.argv)


if __name__ == '__main__':
    main()
