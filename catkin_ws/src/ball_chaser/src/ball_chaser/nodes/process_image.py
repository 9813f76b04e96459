"""process_image: find the ball in the camera image and ask drive_bot to chase it.

Subscribes:
  camera/rgb/image_raw (sensor_msgs/Image): rgb8, bgr8, rgba8, bgra8 or mono8.
      The name is relative, so in the root namespace it is the course's
      /camera/rgb/image_raw, and it can be remapped.

Calls:
  /ball_chaser/command_robot (ball_chaser/DriveToTarget), once per image
      (~send_every_frame), or only when the command changes by more than the
      deadbands. The connection is kept open; if drive_bot is down or
      restarting, the service is looked up again after ~retry_delay.

Parameters (defaults in config/ball_chaser.yaml):
  ~mode (str, default "proportional"): "course" for the course's
      left/middle/right thirds rule, "proportional" for smooth steering.
  ~target_color (int[3], RGB 0..255, default [255, 255, 255]): ball colour.
  ~color_tolerance (int, 0..255, default 0): largest difference per channel
      for a pixel to count as ball. 0 is the course's exact match.
  ~min_pixels (int, default 1): fewer matching pixels count as no ball.
  ~course/forward_speed (m/s, default 0.5), ~course/turn_speed (rad/s, default 0.5).
  ~proportional/max_linear_x (m/s, default 0.5): speed toward a far, centred ball.
  ~proportional/steering_gain (rad/s per unit offset, default 1.5): offset is
      -1 at the left image edge and +1 at the right edge.
  ~proportional/max_angular_z (rad/s, default 1.0).
  ~proportional/stop_width_fraction (0..1, default 0.3): stop driving forward
      when the ball is this wide relative to the image.
  ~proportional/stop_area_fraction (0..1, default 0.1): or covers this much of it.
  ~proportional/min_linear_x (m/s, default 0): slowest approach until close.
  ~proportional/search_turn (rad/s, default 0): turn rate while no ball is
      seen, toward where it was last seen; 0 stops.
  ~send_every_frame (bool, default true): call the service for every image.
      A simulator in lockstep (flatsim's ~lockstep) waits for an answer to each
      frame, and an answer every frame keeps runs repeatable: whether an
      unchanged command is resent would otherwise depend on which of /clock
      and the image arrived first. False restores the deadbands below.
  ~linear_deadband (m/s, default 0.02), ~angular_deadband (rad/s, default 0.02):
      smaller changes are not sent (without ~send_every_frame).
  ~resend_interval (s, default 0): resend an unchanged command this often;
      0 never resends. Set it below drive_bot's ~cmd_timeout when that is used.
  ~retry_delay (s, default 0.5): wait after a failed service call.
  ~publish_handled (bool, default false): publish the header of every image
      handled on ~handled (std_msgs/Header) once its command is decided and
      sent, so bench/bench_chase_latency.py can count the frames handled and
      time the answers.
"""
import sys

import rospy
from overlay_check import shadowed
from sensor_msgs.msg import Image
from std_msgs.msg import Header

from ball_chaser import rejoin
from ball_chaser.control import STOP, CommandGate, CourseController, ProportionalController
from ball_chaser.detect import (ImageFormatError, UnsupportedEncodingError, find_ball,
                                image_msg_to_array, validate_target)
from ball_chaser.srv import DriveToTarget

SERVICE_NAME = '/ball_chaser/command_robot'
# Room for one 800x800 rgba8 frame (2.56 MB) plus headers, so queue_size=1 really keeps the newest.
IMAGE_BUFFER_BYTES = 2 ** 24


def make_controller(mode):
    if mode == 'course':
        return CourseController(forward_speed=float(rospy.get_param('~course/forward_speed', 0.5)),
                                turn_speed=float(rospy.get_param('~course/turn_speed', 0.5)))
    if mode == 'proportional':
        return ProportionalController(
            max_linear_x=float(rospy.get_param('~proportional/max_linear_x', 0.5)),
            steering_gain=float(rospy.get_param('~proportional/steering_gain', 1.5)),
            max_angular_z=float(rospy.get_param('~proportional/max_angular_z', 1.0)),
            stop_width_fraction=float(rospy.get_param('~proportional/stop_width_fraction', 0.3)),
            stop_area_fraction=float(rospy.get_param('~proportional/stop_area_fraction', 0.1)),
            search_turn=float(rospy.get_param('~proportional/search_turn', 0.0)),
            min_linear_x=float(rospy.get_param('~proportional/min_linear_x', 0.0)))
    raise ValueError('~mode must be "course" or "proportional", got %r' % (mode,))


class ProcessImage:
    def __init__(self):
        self.mode = rospy.get_param('~mode', 'proportional')
        self.controller = make_controller(self.mode)
        self.target_color, self.tolerance = validate_target(
            rospy.get_param('~target_color', [255, 255, 255]), rospy.get_param('~color_tolerance', 0))
        self.min_pixels = int(rospy.get_param('~min_pixels', 1))
        self.gate = CommandGate(linear_deadband=float(rospy.get_param('~linear_deadband', 0.02)),
                                angular_deadband=float(rospy.get_param('~angular_deadband', 0.02)),
                                resend_interval=float(rospy.get_param('~resend_interval', 0.0)),
                                retry_delay=float(rospy.get_param('~retry_delay', 0.5)),
                                every_frame=bool(rospy.get_param('~send_every_frame', True)))
        self._reported_encodings = set()
        self._service_up = False
        # Persistent: a lookup on the master and a new connection per frame would cost more
        # than finding the ball. A failed call drops the connection (see answer()).
        self.drive = rospy.ServiceProxy(SERVICE_NAME, DriveToTarget, persistent=True)
        self.handled_pub = (rospy.Publisher('~handled', Header, queue_size=30)
                            if rospy.get_param('~publish_handled', False) else None)
        self.subscriber = rospy.Subscriber('camera/rgb/image_raw', Image, self.handle_image,
                                           queue_size=1, buff_size=IMAGE_BUFFER_BYTES)
        rospy.loginfo('process_image ready: %s mode, target colour %s +/- %d on %s',
                      self.mode, list(self.target_color), self.tolerance, self.subscriber.resolved_name)

    def command_for(self, message):
        """The command for one image, or STOP for an image that cannot be read."""
        try:
            image = image_msg_to_array(message)
        except UnsupportedEncodingError as error:
            if error.encoding not in self._reported_encodings:
                self._reported_encodings.add(error.encoding)
                rospy.logerr('process_image: %s; stopping the robot until images arrive in one of them', error)
            return STOP
        except ImageFormatError as error:
            rospy.logerr_throttle(5.0, 'process_image: bad image: %s; stopping the robot' % error)
            return STOP
        detection = find_ball(image, message.encoding, self.target_color, self.tolerance, self.min_pixels)
        return self.controller.command(detection)

    def handle_image(self, message):
        self.answer(message)
        if self.handled_pub is not None:
            self.handled_pub.publish(message.header)

    def answer(self, message):
        command = self.command_for(message)
        now = rospy.get_time()
        if not self.gate.should_send(command, now):
            return
        try:
            self.drive(command.linear_x, command.angular_z)
        except (rospy.ServiceException, rospy.ROSException) as error:
            # The next call looks the service up again: drive_bot may have been restarted.
            self.drive.close()
            self.drive = rospy.ServiceProxy(SERVICE_NAME, DriveToTarget, persistent=True)
            self.gate.failed(now)
            self._service_up = False
            rospy.logwarn_throttle(5.0, 'process_image: %s call failed (%s); retrying'
                                   % (SERVICE_NAME, error))
            return
        self.gate.sent(command, now)
        if not self._service_up:
            self._service_up = True
            rospy.loginfo('process_image: connected to %s', SERVICE_NAME)


def main():
    shadowed.warn_if_shadowed(__file__)
    rospy.init_node('process_image')
    # docs/course.md's startup has world.launch own the master: outlive its restart.
    rejoin.keep_registered()
    try:
        ProcessImage()
    except ValueError as error:
        rospy.logfatal('process_image: %s', error)
        sys.exit(1)
    rospy.spin()
