"""All the turtles on one canvas: spawning and naming them, killing them,
their pens, teleports and rotation goals, and the update that moves them.

It mirrors Noetic's TurtleFrame and Turtle, without ROS: the node feeds it
requests and wall time and publishes what each update returns.
"""
import math
import re
from dataclasses import dataclass

from turtlesim.canvas import DEFAULT_BACKGROUND, Canvas, Pen
from turtlesim.motion import (CANVAS_METERS, CENTRE, UPDATE_PERIOD, Motion, TurtlesimError,
                              normalize_angle, require_finite)

# A name that makes legal ROS topic names under it: the rules of rosgraph.names.is_legal_name.
_LEGAL_NAME = re.compile(r'^[~/]?([A-Za-z][\w]*)(/[A-Za-z][\w]*)*$')
# A rotation goal is reached within this many radians, and steers at this rate (rad/s).
ROTATION_TOLERANCE = 0.02
ROTATION_SPEED = 1.0


@dataclass
class RotationGoal:
    key: str
    theta: float
    start_theta: float
    cancel_requested: bool = False


@dataclass
class RotationEvent:
    """What became of a rotation goal: kind is 'feedback' (value: remaining
    radians), or 'succeeded', 'canceled' or 'aborted' (value: the turn so far,
    start minus now). reason says why a goal was aborted."""
    turtle: str
    key: str
    kind: str
    value: float
    reason: str = ''


@dataclass
class TurtleUpdate:
    """One turtle after an update: its turtlesim/Pose fields, the colour under
    it, and the unclamped canvas position when it hit the wall (else None)."""
    name: str
    pose: tuple
    color: tuple
    clamped_from: tuple = None


class Turtle:
    def __init__(self, name, x, y, theta):
        self.name = name
        self.motion = Motion(x, CANVAS_METERS - y, theta)
        self.pen = Pen()
        self.pen_on = True
        self.teleports = []
        self.rotation = None


class TurtleWorld:
    def __init__(self, background=DEFAULT_BACKGROUND):
        self.canvas = Canvas(background)
        self.turtles = {}
        self.id_counter = 0
        self.rotation_events = []

    # The services

    def spawn(self, name, x, y, theta):
        """A new turtle at pose (x, y up from the bottom, theta); returns its name.
        An empty name gets the first free of turtle1, turtle2, ... after the last given."""
        require_finite('spawn x, y and theta', x, y, theta)
        if not name:
            while True:
                self.id_counter += 1
                name = 'turtle%d' % self.id_counter
                if name not in self.turtles:
                    break
        elif name in self.turtles:
            raise TurtlesimError('A turtled named [%s] already exists' % name)
        elif not _LEGAL_NAME.match(name):
            raise TurtlesimError('Cannot spawn a turtle named [%s]: not a legal ROS name '
                                 '(a letter, then letters, digits, _ or /)' % name)
        self.turtles[name] = Turtle(name, x, y, theta)
        return name

    def kill(self, name):
        turtle = self._turtle(name, 'Tried to kill turtle [%s], which does not exist')
        if turtle.rotation is not None:
            self._finish_rotation(turtle, 'aborted', 'turtle %s was killed' % name)
        del self.turtles[name]

    def reset(self, background):
        """Every turtle gone, a new turtle1 in the centre, the canvas cleared."""
        for turtle in self.turtles.values():
            if turtle.rotation is not None:
                self._finish_rotation(turtle, 'aborted', 'turtlesim was reset')
        self.turtles.clear()
        self.id_counter = 0
        name = self.spawn('', CENTRE, CENTRE, 0.0)
        self.clear(background)
        return name

    def clear(self, background):
        self.canvas.clear(background)

    def command(self, name, linear_x, linear_y, angular, now):
        turtle = self._turtle(name)
        turtle.motion.command(linear_x, linear_y, angular, now)
        if turtle.rotation is not None:
            self._finish_rotation(turtle, 'aborted', 'Velocity command received during rotation goal. '
                                  'Aborting goal')

    def set_pen(self, name, r, g, b, width, off):
        turtle = self._turtle(name)
        turtle.pen_on = not off
        if not off:
            turtle.pen = Pen.from_request(r, g, b, width)

    def teleport_absolute(self, name, x, y, theta):
        """Queued for the next update, as the original does."""
        require_finite('teleport_absolute x, y and theta', x, y, theta)
        self._turtle(name).teleports.append(('absolute', (x, y, theta)))

    def teleport_relative(self, name, linear, angular):
        require_finite('teleport_relative linear and angular', linear, angular)
        self._turtle(name).teleports.append(('relative', (linear, angular)))

    def rotate_absolute(self, name, key, theta):
        """A RotateAbsolute goal: turn in place to heading theta. A goal still
        running on that turtle is aborted."""
        require_finite('rotate_absolute theta', theta)
        turtle = self._turtle(name)
        if turtle.rotation is not None:
            self._finish_rotation(turtle, 'aborted', 'Rotation goal received before a previous goal '
                                  'finished. Aborting previous goal')
        turtle.rotation = RotationGoal(key, theta, turtle.motion.theta)

    def cancel_rotation(self, name, key):
        turtle = self.turtles.get(name)
        if turtle is not None and turtle.rotation is not None and turtle.rotation.key == key:
            turtle.rotation.cancel_requested = True

    def take_rotation_events(self):
        events, self.rotation_events = self.rotation_events, []
        return events

    # The update

    def tick(self, now, dt=UPDATE_PERIOD):
        """Move every turtle by one update at wall time `now`; returns a TurtleUpdate each, by name."""
        return [self._update(self.turtles[name], now, dt) for name in sorted(self.turtles)]

    def picture(self):
        return self.canvas.picture((t.motion.position, t.motion.theta)
                                   for _, t in sorted(self.turtles.items()))

    def _update(self, turtle, now, dt):
        motion = turtle.motion
        for kind, args in turtle.teleports:
            if kind == 'absolute':
                old = motion.teleport_absolute(*args)
            else:
                old = motion.teleport_relative(*args)
            if turtle.pen_on:
                self.canvas.draw_line(motion.position, old, turtle.pen)
        turtle.teleports = []
        if turtle.rotation is not None:
            self._steer(turtle, now)
        step = motion.step(now, dt)
        color = self.canvas.color_at(motion.position)
        if step.new != step.old and turtle.pen_on:
            self.canvas.draw_line(step.new, step.old, turtle.pen)
        return TurtleUpdate(turtle.name, motion.pose(), color, step.clamped_from)

    def _steer(self, turtle, now):
        goal, motion = turtle.rotation, turtle.motion
        if goal.cancel_requested:
            self._finish_rotation(turtle, 'canceled')
            motion.stop()
            return
        remaining = normalize_angle(normalize_angle(goal.theta) - motion.theta)
        self.rotation_events.append(RotationEvent(turtle.name, goal.key, 'feedback', remaining))
        if abs(remaining) < ROTATION_TOLERANCE:
            self._finish_rotation(turtle, 'succeeded')
            motion.stop()
        else:
            motion.hold(math.copysign(ROTATION_SPEED, remaining), now)

    def _finish_rotation(self, turtle, kind, reason=''):
        goal = turtle.rotation
        delta = normalize_angle(goal.start_theta - turtle.motion.theta)
        self.rotation_events.append(RotationEvent(turtle.name, goal.key, kind, delta, reason))
        turtle.rotation = None

    def _turtle(self, name, missing='There is no turtle named [%s]'):
        turtle = self.turtles.get(name)
        if turtle is None:
            raise TurtlesimError(missing % name)
        return turtle
