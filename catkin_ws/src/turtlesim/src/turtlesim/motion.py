"""How one turtle moves, step by step, as Noetic's turtlesim moves it.

Positions are kept in the canvas frame, as the original keeps them: metres
from the top-left corner, x to the right and y downwards. The published pose
flips y, so that it grows upwards from the bottom-left corner.

The original's numbers, kept here on purpose:
- one metre is 45 pixels (the height of its turtle image), so the 500-pixel
  canvas is (500 - 1) / 45 = 11.088889 m on a side;
- every update advances by 0.016 s (its timer period), whatever wall time
  really passed;
- a velocity command lasts 1 s of wall time, then the turtle stops;
- theta stays in [-PI, PI) with its PI of 3.14159265.
"""
import math
from dataclasses import dataclass

import numpy as np

CANVAS_PIXELS = 500
METER_PIXELS = 45
# float32, as the original stores its canvas size: the centre prints as 5.544445.
CANVAS_METERS = float(np.float32(CANVAS_PIXELS - 1) / np.float32(METER_PIXELS))
CENTRE = float(np.float32(CANVAS_METERS) / np.float32(2.0))
UPDATE_PERIOD = 0.016
COMMAND_TIMEOUT = 1.0
PI = 3.14159265
WALL_WARNING = 'Oh no! I hit the wall! (Clamping from [x=%f, y=%f])'


class TurtlesimError(ValueError):
    """A request the simulator refuses; the message says why."""


def normalize_angle(angle):
    """angle wrapped into [-PI, PI), with the original's formula."""
    wrapped = angle - 2.0 * PI * math.floor((angle + PI) / (2.0 * PI))
    if -PI <= wrapped < PI:
        return wrapped
    # Past about 1e16 rad the formula loses every digit; fmod is exact at any size.
    wrapped = math.fmod(angle + PI, 2.0 * PI)
    return (wrapped + 2.0 * PI if wrapped < 0.0 else wrapped) - PI


def require_finite(what, *values):
    if not all(math.isfinite(v) for v in values):
        raise TurtlesimError('%s must be finite numbers, got %s'
                             % (what, ', '.join(repr(v) for v in values)))


@dataclass
class Step:
    """What one update did: where the turtle was and is (canvas metres), and
    the unclamped position when it ran into the wall (else None)."""
    old: tuple
    new: tuple
    clamped_from: tuple = None


class Motion:
    """A turtle's position, heading and current velocity command."""

    def __init__(self, x, y, theta):
        """x, y in the canvas frame (y downwards), theta in radians."""
        self.x = float(x)
        self.y = float(y)
        self.theta = float(theta)
        self.linear_x = 0.0
        self.linear_y = 0.0
        self.angular = 0.0
        self.last_command = None

    @property
    def position(self):
        return (self.x, self.y)

    def command(self, linear_x, linear_y, angular, now):
        """A cmd_vel: body-frame velocities (m/s, rad/s) from wall time `now` (s) on.
        linear_y moves the turtle sideways, as in Noetic's turtlesim."""
        require_finite('cmd_vel linear.x, linear.y and angular.z', linear_x, linear_y, angular)
        self.linear_x = float(linear_x)
        self.linear_y = float(linear_y)
        self.angular = float(angular)
        self.last_command = now

    def hold(self, angular, now):
        """Turn in place at `angular`, as a rotation goal steers the turtle."""
        self.linear_x = 0.0
        self.linear_y = 0.0
        self.angular = angular
        self.last_command = now

    def stop(self):
        self.linear_x = self.linear_y = self.angular = 0.0

    def teleport_absolute(self, x, y, theta, height=CANVAS_METERS):
        """Jump to pose (x, y up from the bottom, theta); returns the old position."""
        require_finite('teleport_absolute x, y and theta', x, y, theta)
        old = self.position
        self.x = float(x)
        self.y = max(0.0, height - y)
        self.theta = float(theta)
        return old

    def teleport_relative(self, linear, angular):
        """Turn by `angular`, then move `linear` along the new heading; returns the old position."""
        require_finite('teleport_relative linear and angular', linear, angular)
        old = self.position
        self.theta += angular
        self.x += math.cos(self.theta) * linear
        self.y -= math.sin(self.theta) * linear
        return old

    def step(self, now, dt=UPDATE_PERIOD, width=CANVAS_METERS, height=CANVAS_METERS):
        """Advance by dt; the command times out after COMMAND_TIMEOUT of `now`."""
        if self.last_command is None or now - self.last_command > COMMAND_TIMEOUT:
            self.stop()
        old = self.position
        self.theta = normalize_angle(self.theta + self.angular * dt)
        cos, sin = math.cos(self.theta), math.sin(self.theta)
        self.x += cos * self.linear_x * dt - sin * self.linear_y * dt
        self.y -= cos * self.linear_y * dt + sin * self.linear_x * dt
        clamped_from = None
        if not (0.0 <= self.x <= width and 0.0 <= self.y <= height):
            clamped_from = self.position
            self.x = min(max(self.x, 0.0), width)
            self.y = min(max(self.y, 0.0), height)
        return Step(old, self.position, clamped_from)

    def pose(self, height=CANVAS_METERS):
        """(x, y, theta, linear_velocity, angular_velocity) as turtlesim/Pose carries them."""
        return (self.x, height - self.y, self.theta,
                math.hypot(self.linear_x, self.linear_y), self.angular)
