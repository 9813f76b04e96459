"""The two reach rules side by side: where the centre rule (evaluate, demo, report) and the
surface rule (grade) agree, and where they part. Pure: no master."""
import math

import pytest

from chase_tools import demo, evaluate, placement, reach, report
from chase_tools.placement import CameraView, RobotGeometry

CAMERA = CameraView(0.1, 0.0, 0.1, 0.0, 0.0, 1.4, 1.1)
# A small robot: its front 0.1 m ahead of its origin, 0.2 m wide.
SMALL = RobotGeometry(((0.1, -0.1), (0.1, 0.1), (-0.1, 0.1), (-0.1, -0.1)), CAMERA)
# A long robot: its front 0.35 m ahead of its origin, its back 0.3 m behind.
LONG = RobotGeometry(((0.35, -0.15), (0.35, 0.15), (-0.3, 0.15), (-0.3, -0.15)), CAMERA)
BALL_RADIUS = 0.1


def both_rules(robot, pose, ball, ball_moved=0.0):
    """(centre rule, surface rule) for a robot at pose (x, y, yaw), the ball at ball."""
    gap = reach.surface_gaps(robot, [pose], ball, BALL_RADIUS)[0]
    return reach.centre_reached(pose[:2], ball), bool(reach.surface_reached_how(gap, ball_moved))


def test_the_rules_have_distinct_names_and_reaches():
    assert (reach.CENTRE_REACH_M, reach.SURFACE_REACH_M, reach.BALL_PUSHED_M) == (0.4, 0.15, 0.05)


def test_a_small_robot_at_the_centre_reach_has_not_reached_the_surface():
    # Its front 0.3 m from the ball's centre: 0.2 m from its surface.
    assert reach.centre_gap((0.0, 0.0), (0.4, 0.0)) == pytest.approx(0.4)
    assert reach.surface_gaps(SMALL, [(0.0, 0.0, 0.0)], (0.4, 0.0), BALL_RADIUS)[0] == pytest.approx(0.2)
    assert both_rules(SMALL, (0.0, 0.0, 0.0), (0.4, 0.0)) == (True, False)


def test_a_long_robot_at_the_surface_reach_has_not_reached_the_centre():
    # Its front 0.1 m from the ball's surface, its origin 0.55 m from the centre.
    assert both_rules(LONG, (0.0, 0.0, 0.0), (0.55, 0.0)) == (False, True)
    # Backing up to the ball, the same robot's origin is nearer: both rules hold.
    assert both_rules(LONG, (0.0, 0.0, math.pi), (0.4, 0.0)) == (True, True)


def test_a_pushed_ball_counts_only_for_the_surface_rule():
    assert both_rules(SMALL, (0.0, 0.0, 0.0), (1.0, 0.0), ball_moved=0.06) == (False, True)
    assert reach.surface_reached_how(0.5, 0.06) == 'pushed the ball'
    assert reach.surface_reached_how(0.15, 0.0) == 'came within 15 cm of the ball\'s surface'
    assert reach.surface_reached_how(0.16, 0.04) == ''


def test_both_rules_agree_far_from_the_ball_and_at_it():
    assert both_rules(SMALL, (0.0, 0.0, 0.0), (2.0, 0.0)) == (False, False)
    assert both_rules(SMALL, (0.0, 0.0, 0.0), (0.3, 0.0)) == (True, True)


def test_each_tool_takes_its_own_rule_from_the_one_module():
    assert evaluate.REACH_M == demo.REACH_M == report.REACH_M == reach.CENTRE_REACH_M
    assert placement.REACH_GAP_M == reach.SURFACE_REACH_M
    assert placement.BALL_PUSHED_M == reach.BALL_PUSHED_M
    assert placement.reached_how is reach.surface_reached_how
    assert placement.surface_gaps is reach.surface_gaps
