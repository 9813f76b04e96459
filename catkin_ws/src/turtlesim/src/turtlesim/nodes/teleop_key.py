"""turtle_teleop_key: drive turtle1 with the arrow keys of this terminal, as /teleop_turtle.

Publishes:
  turtle1/cmd_vel (geometry_msgs/Twist): up/down give linear.x = +-scale_linear,
      left/right give angular.z = +-scale_angular, once per key press. 'q' quits.

Parameters (relative names, as the original reads them):
  scale_linear (float, m/s, default 2.0)
  scale_angular (float, rad/s, default 2.0)

It needs a terminal of its own on standard input and says so otherwise. The
terminal's settings come back when it ends: on 'q', Ctrl-C, end of input or
a shutdown.
"""
import os
import select
import sys

import rospy
from geometry_msgs.msg import Twist

from turtlesim.keys import BANNER, NotATerminalError, RawTerminal, decode_key

STDIN = 0
# How often the key loop looks up from the keyboard to notice a shutdown (s).
POLL_S = 0.1


def read_scale(name):
    value = rospy.get_param(name, 2.0)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError('%s must be a number, not %r' % (rospy.resolve_name(name), value))
    return float(value)


class TeleopTurtle:
    def __init__(self):
        self.linear_scale = read_scale('scale_linear')
        self.angular_scale = read_scale('scale_angular')
        self.publisher = rospy.Publisher('turtle1/cmd_vel', Twist, queue_size=1)

    def on_key(self, byte):
        """Publishes what the key asks for; False when it asks to quit."""
        action = decode_key(byte, self.linear_scale, self.angular_scale)
        if action is None:
            return True
        if action.quit:
            return False
        twist = Twist()
        twist.linear.x = action.linear_x
        twist.angular.z = action.angular_z
        self.publisher.publish(twist)
        return True

    def read_keys(self, fd):
        while not rospy.is_shutdown():
            ready, _, _ = select.select([fd], [], [], POLL_S)
            if not ready:
                continue
            data = os.read(fd, 1)
            if not data or not self.on_key(data[0]):
                return


def main():
    try:
        terminal = RawTerminal(STDIN)
    except NotATerminalError as error:
        sys.stderr.write('turtle_teleop_key: %s; it reads the arrow keys from a terminal of its own '
                         '(in a launch file, give its node launch-prefix="xterm -e")\n' % error)
        sys.exit(1)
    rospy.init_node('teleop_turtle')
    try:
        teleop = TeleopTurtle()
    except ValueError as error:
        rospy.logfatal('turtle_teleop_key: %s', error)
        sys.exit(1)
    with terminal:
        print(BANNER, flush=True)
        try:
            teleop.read_keys(STDIN)
        except KeyboardInterrupt:
            pass
