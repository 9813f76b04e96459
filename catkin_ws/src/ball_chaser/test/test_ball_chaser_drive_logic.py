"""drive_bot's request handling: validation, clamping, feedback, watchdog."""
import math

import pytest

from ball_chaser.drive_logic import CommandWatchdog, DriveLimits, DriveRequestError, apply_limits

LIMITS = DriveLimits(max_linear_x=1.0, max_angular_z=2.0)


def test_request_within_limits_is_applied_unchanged():
    result = apply_limits(0.5, -0.25, LIMITS)
    assert (result.linear_x, result.angular_z, result.clamped) == (0.5, -0.25, False)
    assert result.feedback == 'Velocities applied: linear_x=0.5 m/s, angular_z=-0.25 rad/s'


def test_request_exactly_at_the_limit_is_not_clamped():
    result = apply_limits(-1.0, 2.0, LIMITS)
    assert (result.linear_x, result.angular_z, result.clamped) == (-1.0, 2.0, False)


@pytest.mark.parametrize('linear, angular, expected', [
    (5.0, 0.0, (1.0, 0.0)),
    (-5.0, 0.0, (-1.0, 0.0)),
    (0.0, 3.0, (0.0, 2.0)),
    (0.0, -3.0, (0.0, -2.0)),
    (1e308, -1e308, (1.0, -2.0)),
])
def test_request_beyond_a_limit_is_clamped_and_says_so(linear, angular, expected):
    result = apply_limits(linear, angular, LIMITS)
    assert (result.linear_x, result.angular_z) == expected
    assert result.clamped
    assert result.feedback.startswith('Velocities applied: linear_x=%g m/s, angular_z=%g rad/s' % expected)
    assert 'clamped' in result.feedback


def test_clamp_feedback_names_the_clamped_velocity_and_its_limit():
    result = apply_limits(3.0, 0.5, LIMITS)
    assert result.feedback == ('Velocities applied: linear_x=1 m/s, angular_z=0.5 rad/s '
                               '(linear_x 3 clamped to max_linear_x 1)')


def test_negative_zero_is_accepted_and_reported_as_zero():
    result = apply_limits(-0.0, -0.0, LIMITS)
    assert (result.linear_x, result.angular_z, result.clamped) == (0.0, 0.0, False)
    assert math.copysign(1.0, result.linear_x) == 1.0
    assert '-0' not in result.feedback


@pytest.mark.parametrize('linear, angular, name', [
    (math.nan, 0.0, 'linear_x'),
    (0.0, math.nan, 'angular_z'),
    (math.inf, 0.0, 'linear_x'),
    (0.0, -math.inf, 'angular_z'),
    ('fast', 0.0, 'linear_x'),
])
def test_non_finite_or_non_numeric_request_is_refused_naming_the_field(linear, angular, name):
    with pytest.raises(DriveRequestError, match=name):
        apply_limits(linear, angular, LIMITS)


@pytest.mark.parametrize('linear, angular', [(0.0, 1.0), (-1.0, 1.0), (math.nan, 1.0), (1.0, math.inf)])
def test_limits_must_be_positive_and_finite(linear, angular):
    with pytest.raises(ValueError, match='must be a positive finite number'):
        DriveLimits(linear, angular)


def test_watchdog_off_never_expires():
    watchdog = CommandWatchdog(0.0)
    watchdog.feed(0.0)
    assert not watchdog.enabled
    assert not watchdog.expired(1e9)


def test_watchdog_expires_once_after_the_timeout():
    watchdog = CommandWatchdog(0.5)
    assert not watchdog.expired(10.0), 'no command yet: nothing to stop'
    watchdog.feed(10.0)
    assert not watchdog.expired(10.5)
    assert watchdog.expired(10.51)
    assert not watchdog.expired(11.0), 'the stop is published once per silence'
    watchdog.feed(11.0)
    assert watchdog.expired(11.6)


@pytest.mark.parametrize('timeout', [-1.0, math.nan, math.inf])
def test_watchdog_timeout_must_be_finite_and_not_negative(timeout):
    with pytest.raises(ValueError, match='cmd_timeout'):
        CommandWatchdog(timeout)
