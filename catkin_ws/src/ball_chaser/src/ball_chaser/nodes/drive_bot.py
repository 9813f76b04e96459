"""drive_bot: serve /ball_chaser/command_robot and publish the requested velocities on cmd_vel.

Service:
  /ball_chaser/command_robot (ball_chaser/DriveToTarget): linear_x (m/s) and
      angular_z (rad/s) to apply. msg_feedback states the velocities applied.
      A request with a NaN or infinite velocity is refused with an error and
      nothing is published; a velocity beyond a limit is clamped, with a warning.
      Every call is logged at DEBUG, request and answer on one line:
      `command_robot: linear_x=0.5 angular_z=0 -> Velocities applied: ...` (or
      `-> refused drive request: ...`). At DEBUG so that a console is not flooded
      at the camera's rate; the studio's chase view raises the node's logger
      to DEBUG (~set_logger_level, logger rosout) while it is open, to show
      the calls.

Publishes:
  cmd_vel (geometry_msgs/Twist): the applied velocities; a zero Twist on
      shutdown and when the watchdog fires.

Parameters:
  ~max_linear_x (float, m/s, default 1.0): largest |linear_x| applied.
  ~max_angular_z (float, rad/s, default 2.0): largest |angular_z| applied.
  ~cmd_timeout (float, s, default 0): publish a zero Twist when no request
      arrived for this long. 0 turns the watchdog off, so the last command
      persists as with the course's Gazebo diff drive.
"""
import sys
import threading

import rospy
from geometry_msgs.msg import Twist
from overlay_check import shadowed

from ball_chaser import rejoin
from ball_chaser.drive_logic import CommandWatchdog, DriveLimits, DriveRequestError, apply_limits
from ball_chaser.srv import DriveToTarget, DriveToTargetResponse

SERVICE_NAME = '/ball_chaser/command_robot'


def twist(linear_x=0.0, angular_z=0.0):
    message = Twist()
    message.linear.x = linear_x
    message.angular.z = angular_z
    return message


def log_call(request, answer):
    """One DEBUG line per call, request and answer: a service call is seen by no other node, so
    this line is how the studio's chase view (and anyone reading /rosout) sees it."""
    rospy.logdebug('command_robot: linear_x=%s angular_z=%s -> %s', _number(request.linear_x),
                   _number(request.angular_z), answer)


def _number(value):
    """A request's velocity as %g writes it; anything else shortly, as it came."""
    try:
        return '%g' % value
    except OverflowError:
        return 'an integer too large for a float'
    except (TypeError, ValueError):
        return '%.40r' % (value,)


class DriveBot:
    def __init__(self):
        self.limits = DriveLimits(float(rospy.get_param('~max_linear_x', 1.0)),
                                  float(rospy.get_param('~max_angular_z', 2.0)))
        self.watchdog = CommandWatchdog(float(rospy.get_param('~cmd_timeout', 0.0)))
        self._lock = threading.Lock()
        self.publisher = rospy.Publisher('cmd_vel', Twist, queue_size=1)
        self.service = rospy.Service(SERVICE_NAME, DriveToTarget, self.handle_command)
        rospy.on_shutdown(self.stop)
        if self.watchdog.enabled:
            # reset=True: a simulation reset sends sim time back, which would otherwise
            # raise in the timer's thread and end the watchdog for good.
            self.timer = rospy.Timer(rospy.Duration(self.watchdog.timeout / 4.0), self.check_watchdog,
                                     reset=True)
        rospy.loginfo('drive_bot ready: %s -> %s (limits %g m/s, %g rad/s, cmd_timeout %g s)',
                      SERVICE_NAME, self.publisher.resolved_name, self.limits.max_linear_x,
                      self.limits.max_angular_z, self.watchdog.timeout)

    def handle_command(self, request):
        try:
            result = apply_limits(request.linear_x, request.angular_z, self.limits)
        except DriveRequestError as error:
            rospy.logerr('refused drive request: %s', error)
            log_call(request, 'refused drive request: %s' % error)
            raise rospy.ServiceException('refused drive request: %s' % error)
        if result.clamped:
            rospy.logwarn(result.feedback)
        with self._lock:
            self.publisher.publish(twist(result.linear_x, result.angular_z))
            self.watchdog.feed(rospy.get_time())
        log_call(request, result.feedback)
        return DriveToTargetResponse(result.feedback)

    def check_watchdog(self, _event):
        with self._lock:
            if self.watchdog.expired(rospy.get_time()):
                rospy.logwarn('no drive request for %g s: stopping the robot', self.watchdog.timeout)
                self.publisher.publish(twist())

    def stop(self):
        self.publisher.publish(twist())


def main():
    shadowed.warn_if_shadowed(__file__)
    rospy.init_node('drive_bot')
    # docs/course.md's startup has world.launch own the master: outlive its restart.
    rejoin.keep_registered()
    try:
        DriveBot()
    except ValueError as error:
        rospy.logfatal('drive_bot: %s', error)
        sys.exit(1)
    rospy.spin()
