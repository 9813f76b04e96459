#!/usr/bin/env python
"""The robot reaches the ball from several placements in the chase_house world,
one after another, with the robot stopped and both models placed while paused.

Private parameters:
  ~placements (list of names from PLACEMENTS, default all of them, in order).
  ~expect_stop (bool, default true): after reaching, the robot must stay within
      reach and must not have pushed the ball far. The course's thirds rule
      never stops for a ball ahead, so its test turns this off.

World frame of chase_house: the main room spans x -2.9..3.9, y -1.4..3.9; a
doorway at x = 4, y 1.8..2.8 opens into the north-east room.
"""
import math
import sys
import unittest

import rospy
import rostest

from rostest_chase_support import BALL, CHASE_TIMEOUT_S, REACH_M, ROBOT, ChaseRig, planar_distance

# name: ((robot x, y, yaw), (ball x, y))
PLACEMENTS = {
    'ahead': ((0.0, 0.0, 0.0), (2.0, 0.0)),
    'left': ((0.0, 0.0, 0.0), (1.2, 0.8)),
    'right': ((0.0, 0.0, 0.0), (1.2, -0.8)),
    'far': ((-2.5, 0.0, 0.0), (3.0, 0.3)),
    'near_wall': ((-0.5, 1.5, math.atan2(2.25, 1.0)), (0.5, 3.75)),
    'other_room': ((2.0, 2.3, 0.0), (5.5, 2.4)),
}
SETTLE_AFTER_REACH_S = 1.0
# The robot may nudge the ball when it arrives, but not drive it off.
MAX_BALL_PUSH_M = 0.15


class ChasePlacements(unittest.TestCase):
    expect_stop = True

    @classmethod
    def setUpClass(cls):
        cls.rig = ChaseRig()

    def check_reaches(self, name):
        robot_start, ball_start = PLACEMENTS[name]
        self.rig.reset(robot_start, ball_start)
        result = self.rig.chase()
        rospy.loginfo('placement %s: %s', name, result)
        self.assertTrue(result.reached, '%s: not within %.2f m of the ball after %.0f s of sim time: %s'
                        % (name, REACH_M, CHASE_TIMEOUT_S, result))
        if not self.expect_stop:
            return
        self.rig.run_for(SETTLE_AFTER_REACH_S)
        robot, ball = self.rig.pose(ROBOT), self.rig.pose(BALL)
        settled_gap = planar_distance(robot, ball)
        pushed = math.hypot(ball.position.x - ball_start[0], ball.position.y - ball_start[1])
        rospy.loginfo('placement %s: %.1f s after reaching, %.3f m apart, ball pushed %.3f m',
                      name, SETTLE_AFTER_REACH_S, settled_gap, pushed)
        self.assertLessEqual(settled_gap, REACH_M, '%s: the robot did not stay close to the ball' % name)
        self.assertLess(pushed, MAX_BALL_PUSH_M, '%s: the robot pushed the ball %.2f m' % (name, pushed))


def add_placement_tests(names):
    """One test method per placement, numbered so they run in the given order."""
    for index, name in enumerate(names, start=1):
        if name not in PLACEMENTS:
            raise ValueError('unknown placement %r; known: %s' % (name, ', '.join(PLACEMENTS)))
        setattr(ChasePlacements, 'test_%d_%s' % (index, name),
                lambda self, name=name: self.check_reaches(name))


def main():
    rospy.init_node('chase_placements')
    add_placement_tests(rospy.get_param('~placements', list(PLACEMENTS)))
    ChasePlacements.expect_stop = bool(rospy.get_param('~expect_stop', True))
    rostest.rosrun('ball_chaser', 'chase_placements', ChasePlacements, sys.argv)


if __name__ == '__main__':
    main()
