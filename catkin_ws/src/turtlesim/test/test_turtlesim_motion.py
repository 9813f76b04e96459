"""One turtle's motion, without ROS: the kinematics, the 1 s command timeout,
the wall clamp, teleports and bad numbers."""
import math

import numpy as np
import pytest

from turtlesim.motion import (CANVAS_METERS, CENTRE, COMMAND_TIMEOUT, PI, UPDATE_PERIOD, Motion,
                              TurtlesimError, normalize_angle)


def test_canvas_is_the_originals_500_pixels_at_45_per_metre():
    assert '%f' % CANVAS_METERS == '11.088889'
    assert '%f' % CENTRE == '5.544445'


def test_straight_ahead_moves_linear_x_times_dt_along_the_heading():
    motion = Motion(2.0, 3.0, 0.0)
    motion.command(1.5, 0.0, 0.0, now=0.0)
    step = motion.step(now=0.0)
    assert step.old == (2.0, 3.0)
    assert motion.position == pytest.approx((2.0 + 1.5 * UPDATE_PERIOD, 3.0))
    x, y, theta, linear, angular = motion.pose()
    assert (y, linear, angular) == pytest.approx((CANVAS_METERS - 3.0, 1.5, 0.0))


def test_heading_turns_first_then_the_turtle_moves_along_the_new_heading():
    motion = Motion(5.0, 5.0, 0.0)
    motion.command(1.0, 0.0, 0.5, now=0.0)
    for tick in range(1, 11):
        motion.step(now=tick * UPDATE_PERIOD)
    headings = [k * 0.5 * UPDATE_PERIOD for k in range(1, 11)]
    assert motion.theta == pytest.approx(headings[-1])
    # Canvas y points down, so a left turn from +x makes y smaller.
    assert motion.x == pytest.approx(5.0 + sum(math.cos(h) for h in headings) * UPDATE_PERIOD)
    assert motion.y == pytest.approx(5.0 - sum(math.sin(h) for h in headings) * UPDATE_PERIOD)


def test_linear_y_moves_sideways_and_counts_in_the_pose_speed():
    motion = Motion(5.0, 5.0, 0.0)
    motion.command(0.0, 2.0, 0.0, now=0.0)
    motion.step(now=0.0)
    assert motion.position == pytest.approx((5.0, 5.0 - 2.0 * UPDATE_PERIOD))
    motion.command(3.0, 4.0, 0.0, now=0.0)
    motion.step(now=0.0)
    assert motion.pose()[3] == pytest.approx(5.0)


def test_a_command_lasts_one_second_of_the_clock_it_is_given():
    motion = Motion(1.0, 1.0, 0.0)
    motion.command(1.0, 0.0, 1.0, now=100.0)
    motion.step(now=100.0 + COMMAND_TIMEOUT)
    assert motion.pose()[3:] == (1.0, 1.0)
    before = motion.position
    motion.step(now=100.0 + COMMAND_TIMEOUT + 0.001)
    assert motion.position == before
    assert motion.pose()[3:] == (0.0, 0.0)


def test_a_turtle_never_commanded_stands_still():
    motion = Motion(1.0, 1.0, 0.3)
    step = motion.step(now=0.0)
    assert step.new == step.old and step.clamped_from is None


@pytest.mark.parametrize('start, command, expected', [
    ((11.0, 5.0, 0.0), (10.0, 0.0), (CANVAS_METERS, 5.0)),
    ((0.05, 5.0, PI), (10.0, 0.0), (0.0, 5.0)),
    ((5.0, 0.05, PI / 2), (10.0, 0.0), (5.0, 0.0)),
    ((5.0, 11.0, -PI / 2), (10.0, 0.0), (5.0, CANVAS_METERS)),
])
def test_the_wall_clamps_and_reports_the_unclamped_position(start, command, expected):
    motion = Motion(*start)
    motion.command(command[0], 0.0, command[1], now=0.0)
    step = motion.step(now=0.0)
    assert motion.position == pytest.approx(expected)
    unclamped = (start[0] + math.cos(motion.theta) * 10.0 * UPDATE_PERIOD,
                 start[1] - math.sin(motion.theta) * 10.0 * UPDATE_PERIOD)
    assert step.clamped_from == pytest.approx(unclamped)
    # Resting against the wall is not hitting it again.
    motion.stop()
    assert motion.step(now=0.0).clamped_from is None


def test_theta_wraps_into_minus_pi_to_pi():
    motion = Motion(5.0, 5.0, PI - 0.001)
    motion.command(0.0, 0.0, 1.0, now=0.0)
    motion.step(now=0.0)
    assert motion.theta == pytest.approx(-PI - 0.001 + UPDATE_PERIOD)
    for angle in (0.0, 1.0, -3.0, 7.0, -100.0, 1e20, -1e300):
        assert -PI <= normalize_angle(angle) < PI
        assert math.sin(normalize_angle(angle)) == pytest.approx(math.sin(angle), abs=1e-6) \
            or abs(angle) > 1e15


def test_teleport_absolute_flips_y_and_keeps_it_on_the_canvas():
    motion = Motion(1.0, 1.0, 0.0)
    assert motion.teleport_absolute(2.0, 3.0, 1.0) == (1.0, 1.0)
    assert motion.pose()[:3] == pytest.approx((2.0, 3.0, 1.0))
    motion.teleport_absolute(2.0, 50.0, 0.0)
    assert motion.y == 0.0


def test_teleport_relative_turns_then_moves():
    motion = Motion(2.0, 5.0, 0.5)
    motion.teleport_relative(1.0, 0.5)
    assert motion.theta == pytest.approx(1.0)
    assert motion.position == pytest.approx((2.0 + math.cos(1.0), 5.0 - math.sin(1.0)))


@pytest.mark.parametrize('bad', [float('nan'), float('inf'), -float('inf')])
def test_nan_and_infinite_numbers_are_refused_and_change_nothing(bad):
    motion = Motion(1.0, 2.0, 0.5)
    motion.command(1.0, 0.0, 0.0, now=0.0)
    for call in (lambda: motion.command(bad, 0.0, 0.0, now=0.0),
                 lambda: motion.command(0.0, 0.0, bad, now=0.0),
                 lambda: motion.teleport_absolute(1.0, bad, 0.0),
                 lambda: motion.teleport_relative(bad, 0.0)):
        with pytest.raises(TurtlesimError, match='finite'):
            call()
    assert (motion.x, motion.y, motion.theta, motion.linear_x) == (1.0, 2.0, 0.5, 1.0)


def test_huge_finite_velocities_end_at_the_wall_with_a_finite_pose():
    motion = Motion(5.0, 5.0, 0.3)
    motion.command(1e300, 0.0, 1e300, now=0.0)
    motion.step(now=0.0)
    pose = np.array(motion.pose()[:3])
    assert np.all(np.isfinite(pose)) and -PI <= motion.theta < PI
    assert 0.0 <= motion.x <= CANVAS_METERS and 0.0 <= motion.y <= CANVAS_METERS
