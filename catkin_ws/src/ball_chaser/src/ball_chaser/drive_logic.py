"""What drive_bot does with a DriveToTarget request, without ROS.

A request is refused when a velocity is not a finite number, and clamped to
symmetric limits otherwise. The feedback text states the velocities that were
actually applied, so a caller can see a clamp in the service response.
"""
import dataclasses
import math


class DriveRequestError(ValueError):
    """A drive request that cannot be applied (a velocity that is NaN, infinite or not a number)."""


@dataclasses.dataclass(frozen=True)
class DriveLimits:
    """Largest speeds drive_bot applies, in either direction.

    max_linear_x: m/s along the robot's x axis.
    max_angular_z: rad/s about the robot's z axis (positive turns left).
    """

    max_linear_x: float = 1.0
    max_angular_z: float = 2.0

    def __post_init__(self):
        for name in ('max_linear_x', 'max_angular_z'):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError('%s must be a positive finite number, got %r' % (name, value))


@dataclasses.dataclass(frozen=True)
class DriveResult:
    """The velocities to publish, whether a limit changed them, and the text for msg_feedback."""

    linear_x: float
    angular_z: float
    clamped: bool
    feedback: str


def _finite_velocity(name, value):
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise DriveRequestError('%s must be a number, got %r' % (name, value)) from None
    except OverflowError:
        # Not %r: Python refuses to print integers of more than 4300 digits.
        raise DriveRequestError('%s must be a finite number, got an integer too large for a float; '
                                'nothing was published' % name) from None
    if not math.isfinite(number):
        raise DriveRequestError('%s must be a finite number, got %r; nothing was published' % (name, number))
    # Adding 0.0 turns -0.0 into 0.0, so the feedback never reads "-0".
    return number + 0.0


def _clamp(value, limit):
    return min(max(value, -limit), limit)


def apply_limits(linear_x, angular_z, limits=DriveLimits()):
    """Validate a request and clamp it to limits.

    Returns a DriveResult. Raises DriveRequestError for a velocity that is NaN,
    infinite or not a number.
    """
    requested_linear = _finite_velocity('linear_x', linear_x)
    requested_angular = _finite_velocity('angular_z', angular_z)
    applied_linear = _clamp(requested_linear, limits.max_linear_x)
    applied_angular = _clamp(requested_angular, limits.max_angular_z)
    feedback = 'Velocities applied: linear_x=%g m/s, angular_z=%g rad/s' % (applied_linear, applied_angular)
    notes = []
    if applied_linear != requested_linear:
        notes.append('linear_x %g clamped to max_linear_x %g' % (requested_linear, limits.max_linear_x))
    if applied_angular != requested_angular:
        notes.append('angular_z %g clamped to max_angular_z %g' % (requested_angular, limits.max_angular_z))
    if notes:
        feedback += ' (%s)' % '; '.join(notes)
    return DriveResult(applied_linear, applied_angular, bool(notes), feedback)


class CommandWatchdog:
    """Tells when the last command is older than a timeout.

    timeout is in seconds; 0 disables the watchdog, which keeps the Gazebo diff
    drive behaviour where the last command persists. expired() is true once per
    silence, so the stop is published once rather than on every check.
    """

    def __init__(self, timeout):
        if not isinstance(timeout, (int, float)) or not math.isfinite(timeout) or timeout < 0:
            raise ValueError('cmd_timeout must be a finite number of seconds >= 0, got %r' % (timeout,))
        self.timeout = float(timeout)
        self._last_command_time = None

    @property
    def enabled(self):
        return self.timeout > 0

    def feed(self, now):
        """Record that a command was applied at time now (seconds)."""
        self._last_command_time = now

    def expired(self, now):
        """True the first time now is more than timeout after the last command."""
        if not self.enabled or self._last_command_time is None:
            return False
        if now < self._last_command_time:
            # The clock went back (a simulation reset): count the silence from now.
            self._last_command_time = now
        if now - self._last_command_time <= self.timeout:
            return False
        self._last_command_time = None
        return True
