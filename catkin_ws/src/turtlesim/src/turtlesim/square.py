"""draw_square's steering: 2 m forward at 1 m/s, stop, a quarter turn left
at 0.4 rad/s, stop, and again, forever, as the original tutorial does it
(with its own PI of 3.141592 and its tolerances)."""
import math
from dataclasses import dataclass

PI = 3.141592
SIDE = 2.0
FORWARD_SPEED = 1.0
TURN_SPEED = 0.4

FORWARD, STOP_FORWARD, TURN, STOP_TURN = 'forward', 'stop_forward', 'turn', 'stop_turn'


@dataclass
class Goal:
    x: float
    y: float
    theta: float


class SquareDriver:
    """Feed it the latest pose (x, y, theta, linear_velocity, angular_velocity)
    on every timer tick; it returns the (linear, angular) command to publish
    and the lines to log."""

    def __init__(self):
        self.state = FORWARD
        self.goal = None

    def update(self, pose):
        x, y, theta, linear_velocity, angular_velocity = pose
        log = []
        if self.goal is None:
            self._goal_ahead(x, y, theta, log)
        stopped = angular_velocity < 0.0001 and linear_velocity < 0.0001
        if self.state == FORWARD:
            if self._reached(x, y, theta):
                self.state = STOP_FORWARD
                return (0.0, 0.0), log
            return (FORWARD_SPEED, 0.0), log
        if self.state == TURN:
            if self._reached(x, y, theta):
                self.state = STOP_TURN
                return (0.0, 0.0), log
            return (0.0, TURN_SPEED), log
        if not stopped:
            return (0.0, 0.0), log
        log.append('Reached goal')
        if self.state == STOP_FORWARD:
            self.state = TURN
            heading = math.fmod(theta + PI / 2.0, 2 * PI)
            if heading >= PI:
                heading -= 2 * PI
            self.goal = Goal(x, y, heading)
            log.append(self._goal_line())
        else:
            self.state = FORWARD
            self._goal_ahead(x, y, theta, log)
        return None, log

    def _goal_ahead(self, x, y, theta, log):
        self.goal = Goal(math.cos(theta) * SIDE + x, math.sin(theta) * SIDE + y, theta)
        log.append(self._goal_line())

    def _reached(self, x, y, theta):
        goal = self.goal
        return abs(x - goal.x) < 0.1 and abs(y - goal.y) < 0.1 and abs(theta - goal.theta) < 0.01

    def _goal_line(self):
        return 'New goal [%f %f, %f]' % (self.goal.x, self.goal.y, self.goal.theta)
