"""Turn a BallDetection into a drive command, without ROS.

Two controllers:
- CourseController is the course's rule: the mean column of the ball's pixels
  falls in the left, middle or right third of the image, and the robot turns
  left, drives forward or turns right at fixed speeds; no ball, stop.
- ProportionalController steers in proportion to the ball's horizontal offset,
  slows down as the ball grows in the image, stops when it is close, and stops
  (or turns slowly to search) when there is no ball.

CommandGate decides when a command is worth a service call: every frame's,
or only one that differs enough from the last one sent.

Velocities follow REP 103: linear_x in m/s forward, angular_z in rad/s with
positive turning left.
"""
import dataclasses
import math


@dataclasses.dataclass(frozen=True)
class DriveCommand:
    linear_x: float
    angular_z: float


STOP = DriveCommand(0.0, 0.0)


def _check_non_negative(owner, **values):
    for name, value in values.items():
        if not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
            raise ValueError('%s: %s must be a finite number >= 0, got %r' % (owner, name, value))


@dataclasses.dataclass
class CourseController:
    """Fixed commands by which third of the image holds the ball's mean column.

    forward_speed: m/s when the ball is in the middle third.
    turn_speed: rad/s when it is in the left (turn left) or right (turn right) third.
    """

    forward_speed: float = 0.5
    turn_speed: float = 0.5

    def __post_init__(self):
        _check_non_negative('course controller', forward_speed=self.forward_speed,
                            turn_speed=self.turn_speed)

    def command(self, detection):
        if not detection.found:
            return STOP
        third = detection.image_width / 3.0
        if detection.centroid_column < third:
            return DriveCommand(0.0, self.turn_speed)
        if detection.centroid_column < 2.0 * third:
            return DriveCommand(self.forward_speed, 0.0)
        return DriveCommand(0.0, -self.turn_speed)


@dataclasses.dataclass
class ProportionalController:
    """Steer toward the ball and slow down as it gets close.

    max_linear_x: m/s forward when the ball is far away and straight ahead.
    steering_gain: rad/s per unit of horizontal offset (offset is -1 at the
        left image edge, +1 at the right edge).
    max_angular_z: rad/s, largest turn rate asked for.
    stop_width_fraction: the robot stops driving forward once the ball's
        bounding width reaches this fraction of the image width (but see
        min_linear_x).
    stop_area_fraction: likewise for the fraction of pixels that are ball.
    min_linear_x: m/s; when above 0, the robot reaches this crawl speed at
        stop_width_fraction and keeps crawling until stop_area_fraction. A
        wide-angle camera sees a near ball span the whole image width a few
        centimetres before it is close, so only the area can tell the last
        stretch.
    search_turn: rad/s to turn when no ball is seen, toward the side where it
        was last seen (left if never seen); 0 stops instead.

    Forward speed falls linearly with the ball's width from max_linear_x to
    min_linear_x at stop_width_fraction, and also with the offset, so a ball
    at the image edge is turned toward in place. Once close, the robot does
    not drive on but still turns to keep the ball centred.
    """

    max_linear_x: float = 0.5
    steering_gain: float = 1.5
    max_angular_z: float = 1.0
    stop_width_fraction: float = 0.3
    stop_area_fraction: float = 0.1
    search_turn: float = 0.0
    min_linear_x: float = 0.0
    _last_seen_side: float = dataclasses.field(default=1.0, init=False, repr=False)

    def __post_init__(self):
        _check_non_negative('proportional controller', max_linear_x=self.max_linear_x,
                            steering_gain=self.steering_gain, max_angular_z=self.max_angular_z,
                            search_turn=self.search_turn, min_linear_x=self.min_linear_x)
        if self.min_linear_x > self.max_linear_x:
            raise ValueError('proportional controller: min_linear_x %r exceeds max_linear_x %r'
                             % (self.min_linear_x, self.max_linear_x))
        for name in ('stop_width_fraction', 'stop_area_fraction'):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not 0 < value <= 1:
                raise ValueError('proportional controller: %s must be in (0, 1], got %r' % (name, value))

    def is_close(self, detection):
        if detection.area_fraction >= self.stop_area_fraction:
            return True
        return self.min_linear_x == 0 and detection.width_fraction >= self.stop_width_fraction

    def command(self, detection):
        if not detection.found:
            if self.search_turn == 0:
                return STOP
            return DriveCommand(0.0, math.copysign(self.search_turn, self._last_seen_side))
        offset = detection.horizontal_offset
        if offset != 0:
            # Positive angular_z turns left, toward a ball with a negative offset.
            self._last_seen_side = -offset
        angular = min(max(-self.steering_gain * offset, -self.max_angular_z), self.max_angular_z)
        if self.is_close(detection):
            return DriveCommand(0.0, angular + 0.0)
        nearness = min(1.0, detection.width_fraction / self.stop_width_fraction)
        approach = self.min_linear_x + (self.max_linear_x - self.min_linear_x) * (1.0 - nearness)
        linear = approach * max(0.0, 1.0 - abs(offset))
        return DriveCommand(linear, angular + 0.0)


class CommandGate:
    """Decides whether a command should go to drive_bot now.

    With every_frame, every command is sent. Otherwise a command is sent when it differs from the
    last one sent by more than the deadbands (m/s, rad/s), when it is an exact stop and the last one
    was not, when resend_interval seconds passed since the last send (0 = never resend; useful with
    drive_bot's cmd_timeout), or when nothing was sent yet. After a failed call, nothing is tried
    for retry_delay seconds, then the command is sent again whatever the deadband says. Times are
    seconds on any clock that only moves forward.
    """

    def __init__(self, linear_deadband=0.02, angular_deadband=0.02, resend_interval=0.0, retry_delay=0.5,
                 every_frame=False):
        _check_non_negative('command gate', linear_deadband=linear_deadband,
                            angular_deadband=angular_deadband, resend_interval=resend_interval,
                            retry_delay=retry_delay)
        self.linear_deadband = linear_deadband
        self.angular_deadband = angular_deadband
        self.resend_interval = resend_interval
        self.retry_delay = retry_delay
        self.every_frame = every_frame
        self.last_sent = None
        self._last_sent_time = None
        self._last_attempt_time = None
        self._retry_after = None

    def changes_meaningfully(self, command):
        previous = self.last_sent
        if previous is None:
            return True
        if command == STOP:
            return previous != STOP
        return (abs(command.linear_x - previous.linear_x) > self.linear_deadband
                or abs(command.angular_z - previous.angular_z) > self.angular_deadband)

    def should_send(self, command, now):
        if self._last_attempt_time is not None and now < self._last_attempt_time:
            # The clock went back (a simulation reset): start afresh.
            self.last_sent = self._last_sent_time = self._last_attempt_time = self._retry_after = None
        if self._retry_after is not None:
            return now >= self._retry_after
        if self.every_frame or self.changes_meaningfully(command):
            return True
        return self.resend_interval > 0 and now - self._last_sent_time >= self.resend_interval

    def sent(self, command, now):
        self.last_sent = command
        self._last_sent_time = self._last_attempt_time = now
        self._retry_after = None

    def failed(self, now):
        self._last_attempt_time = now
        self._retry_after = now + self.retry_delay
