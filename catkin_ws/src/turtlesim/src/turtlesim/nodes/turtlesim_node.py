"""turtlesim_node: Noetic's turtlesim, registered as /turtlesim.

Names are relative to the node's namespace, as the original's are.

Services:
  clear (std_srvs/Empty): repaint the canvas in the background colour, read
      again from ~background_r/g/b.
  reset (std_srvs/Empty): remove every turtle, spawn turtle1 in the centre, clear.
  spawn (turtlesim/Spawn): a turtle at x, y (m, from the bottom-left corner),
      theta (rad). An empty name gives turtle1, turtle2, ...; a name in use,
      an illegal name or a NaN is refused with an error.
  kill (turtlesim/Kill): remove a turtle; an unknown name is an error.

Per turtle NAME:
  NAME/cmd_vel (geometry_msgs/Twist, subscribed): linear.x, linear.y (m/s) and
      angular.z (rad/s) for the next 1 s of wall time. A NaN or infinite
      command is ignored with a warning.
  NAME/pose (turtlesim/Pose) and NAME/color_sensor (turtlesim/Color, the
      canvas colour under the turtle): every update, 62.5 times a second.
  NAME/set_pen (turtlesim/SetPen), NAME/teleport_absolute
      (turtlesim/TeleportAbsolute), NAME/teleport_relative
      (turtlesim/TeleportRelative): a NaN or infinite teleport is refused.
  NAME/rotate_absolute (actionlib, turtlesim/RotateAbsoluteAction): turn in
      place to theta at 1 rad/s; a velocity command or a newer goal aborts it.

Publishes:
  ~image (sensor_msgs/Image): the canvas with the turtles, rgb8, 500x500, at
      ~image_rate while anyone subscribes.

Parameters:
  ~background_r, ~background_g, ~background_b (int 0-255, default 69, 86,
      255): set to the defaults at start-up when absent, as the original does.
  ~image_rate (float, Hz of wall time, default 10): how often ~image is published.

A window opens when there is a display; without one the node runs headless.
"""
import queue
import signal
import sys
import threading
import time
import traceback

import actionlib
import numpy as np
import rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import Image
from std_srvs.srv import Empty, EmptyResponse

from turtlesim.canvas import DEFAULT_BACKGROUND
from turtlesim.motion import CENTRE, UPDATE_PERIOD, WALL_WARNING, TurtlesimError
from turtlesim.msg import (Color, Pose, RotateAbsoluteAction, RotateAbsoluteFeedback,
                           RotateAbsoluteResult)
from turtlesim.srv import (Kill, KillResponse, SetPen, SetPenResponse, Spawn, SpawnResponse,
                           TeleportAbsolute, TeleportAbsoluteResponse, TeleportRelative,
                           TeleportRelativeResponse)
from turtlesim.window import REFRESH_MS, CanvasWindow, WindowUnavailable
from turtlesim.world import TurtleWorld

BACKGROUND_PARAMS = ('~background_r', '~background_g', '~background_b')
SPAWN_LOG = 'Spawning turtle [%s] at x=[%f], y=[%f], theta=[%f]'


def pose_message(fields):
    # float32, as the original's; a huge finite velocity becomes inf rather than failing to pack.
    with np.errstate(over='ignore'):
        return Pose(*(float(v) for v in np.asarray(fields, dtype=np.float32)))


def image_message(picture, stamp):
    rows, columns = picture.shape[:2]
    message = Image(height=rows, width=columns, encoding='rgb8', is_bigendian=0,
                    step=columns * 3, data=picture.tobytes())
    message.header.stamp = stamp
    return message


class TurtleInterface:
    """One turtle's topics, services and action server, handing requests to the node."""

    def __init__(self, node, name):
        # The turtle's name is a namespace: remapping it moves all of its names, as in the original.
        base = rospy.resolve_name(name)
        self.pose_publisher = rospy.Publisher(base + '/pose', Pose, queue_size=1)
        self.color_publisher = rospy.Publisher(base + '/color_sensor', Color, queue_size=1)
        self.cmd_vel = rospy.Subscriber(base + '/cmd_vel', Twist,
                                        lambda message: node.on_cmd_vel(name, message), queue_size=1)
        self.services = [
            rospy.Service(base + '/set_pen', SetPen, lambda request: node.on_set_pen(name, request)),
            rospy.Service(base + '/teleport_absolute', TeleportAbsolute,
                          lambda request: node.on_teleport_absolute(name, request)),
            rospy.Service(base + '/teleport_relative', TeleportRelative,
                          lambda request: node.on_teleport_relative(name, request)),
        ]
        # actionlib calls these holding its own lock: they only queue the request for the update.
        self.rotate_absolute = actionlib.ActionServer(
            base + '/rotate_absolute', RotateAbsoluteAction,
            lambda handle: node.goal_inbox.put(('goal', name, handle)),
            lambda handle: node.goal_inbox.put(('cancel', name, handle)), auto_start=False)
        self.rotate_absolute.start()

    def publish(self, update):
        self.pose_publisher.publish(pose_message(update.pose))
        self.color_publisher.publish(Color(*update.color))

    def shutdown(self):
        self.rotate_absolute.stop()
        for service in self.services:
            service.shutdown()
        self.cmd_vel.unregister()
        self.pose_publisher.unregister()
        self.color_publisher.unregister()


class TurtlesimNode:
    def __init__(self):
        for name, default in zip(BACKGROUND_PARAMS, DEFAULT_BACKGROUND):
            if not rospy.has_param(name):
                rospy.set_param(name, default)
        image_rate = rospy.get_param('~image_rate', 10.0)
        if isinstance(image_rate, bool) or not isinstance(image_rate, (int, float)) or not image_rate > 0:
            raise ValueError('~image_rate must be a number of Hz above 0, not %r' % (image_rate,))
        self.image_period = 1.0 / image_rate
        self.lock = threading.Lock()
        self.world = TurtleWorld(self.background())
        self.interfaces = {}
        self.goal_inbox = queue.SimpleQueue()
        self.goal_handles = {}
        self.image_publisher = rospy.Publisher('~image', Image, queue_size=1)
        self.next_image = 0.0
        self.window_open = False
        self.window_picture = None
        self.last_window_picture = -float('inf')
        self.services = [
            rospy.Service('clear', Empty, self.on_clear),
            rospy.Service('reset', Empty, self.on_reset),
            rospy.Service('spawn', Spawn, self.on_spawn),
            rospy.Service('kill', Kill, self.on_kill),
        ]
        rospy.loginfo('Starting turtlesim with node name %s', rospy.get_name())
        with self.lock:
            self._spawn('', CENTRE, CENTRE, 0.0)
        self.updates = threading.Thread(target=self.run_updates, name='turtlesim updates', daemon=True)

    def start(self):
        self.updates.start()

    def background(self):
        """(r, g, b) from the parameters; a value that is no colour channel gives way to the default."""
        colour = []
        for name, default in zip(BACKGROUND_PARAMS, DEFAULT_BACKGROUND):
            value = rospy.get_param(name, default)
            if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 255:
                rospy.logwarn('%s must be an integer from 0 to 255, not %r: using %d',
                              rospy.resolve_name(name), value, default)
                value = default
            colour.append(value)
        return tuple(colour)

    # The update loop: a fixed step every UPDATE_PERIOD of wall time, as the original's Qt timer.

    def run_updates(self):
        due = time.monotonic()
        while not rospy.is_shutdown():
            try:
                self.update(time.monotonic())
            except Exception:  # noqa: BLE001 - the update must outlive any one bad turn
                rospy.logerr('turtlesim update failed:\n%s', traceback.format_exc())
            due += UPDATE_PERIOD
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                # Behind (a busy machine): skip the missed updates rather than run them in a burst.
                due = time.monotonic()

    def update(self, now):
        with self.lock:
            self._take_goals()
            for update in self.world.tick(now):
                self.interfaces[update.name].publish(update)
                if update.clamped_from is not None:
                    rospy.logwarn(WALL_WARNING, *update.clamped_from)
            self._settle_goals()
            picture, for_image = self._picture_if_due(now)
        if for_image:
            # Scheduled rather than measured from now, so the rate holds between update ticks.
            self.next_image += self.image_period
            if self.next_image < now:
                self.next_image = now + self.image_period
            self.image_publisher.publish(image_message(picture, rospy.Time.now()))

    def _picture_if_due(self, now):
        """(the canvas with the turtles or None, whether ~image wants it): drawn
        only when ~image has subscribers or the window is open, at their rates."""
        for_image = (now >= self.next_image
                     and self.image_publisher.get_num_connections() > 0)
        for_window = self.window_open and now - self.last_window_picture >= REFRESH_MS / 1000.0
        if not (for_image or for_window):
            return None, False
        picture = self.world.picture()
        if for_window:
            self.last_window_picture = now
            self.window_picture = picture
        return picture, for_image

    def take_window_picture(self):
        picture, self.window_picture = self.window_picture, None
        return picture

    # Rotation goals: actionlib queues them, the update hands them to the world and reports back.

    def _take_goals(self):
        while True:
            try:
                kind, name, handle = self.goal_inbox.get_nowait()
            except queue.Empty:
                return
            key = handle.get_goal_id().id
            if kind == 'cancel':
                self.world.cancel_rotation(name, key)
                continue
            try:
                self.world.rotate_absolute(name, key, handle.get_goal().theta)
            except TurtlesimError as error:
                rospy.logerr('%s', error)
                handle.set_rejected(text=str(error))
                continue
            handle.set_accepted()
            self.goal_handles[key] = handle

    def _settle_goals(self):
        for event in self.world.take_rotation_events():
            handle = self.goal_handles.get(event.key)
            if handle is None:
                continue
            if event.kind == 'feedback':
                handle.publish_feedback(RotateAbsoluteFeedback(remaining=event.value))
                continue
            del self.goal_handles[event.key]
            result = RotateAbsoluteResult(delta=event.value)
            if event.kind == 'succeeded':
                rospy.loginfo('Rotation goal completed successfully')
                handle.set_succeeded(result)
            elif event.kind == 'canceled':
                rospy.loginfo('Rotation goal canceled')
                handle.set_canceled(result)
            else:
                rospy.logwarn('%s', event.reason)
                handle.set_aborted(result, event.reason)

    # The services; each takes the lock, so it sees the world between two updates.

    def _refuse(self, error):
        rospy.logerr('%s', error)
        raise rospy.ServiceException(str(error))

    def _spawn(self, name, x, y, theta):
        name = self.world.spawn(name, x, y, theta)
        try:
            self.interfaces[name] = TurtleInterface(self, name)
        except (rospy.ROSException, ValueError) as error:
            self.world.kill(name)
            raise TurtlesimError('Cannot spawn a turtle named [%s]: %s' % (name, error)) from error
        rospy.loginfo(SPAWN_LOG, name, x, y, theta)
        return name

    def _drop_interface(self, name):
        self._settle_goals()
        self.interfaces.pop(name).shutdown()

    def on_spawn(self, request):
        with self.lock:
            try:
                return SpawnResponse(self._spawn(request.name, request.x, request.y, request.theta))
            except TurtlesimError as error:
                self._refuse(error)

    def on_kill(self, request):
        with self.lock:
            try:
                self.world.kill(request.name)
            except TurtlesimError as error:
                self._refuse(error)
            self._drop_interface(request.name)
        return KillResponse()

    def on_clear(self, _request):
        rospy.loginfo('Clearing turtlesim.')
        with self.lock:
            self.world.clear(self.background())
        return EmptyResponse()

    def on_reset(self, _request):
        rospy.loginfo('Resetting turtlesim.')
        with self.lock:
            name = self.world.reset(self.background())
            for old in [n for n in self.interfaces if n != name]:
                self._drop_interface(old)
            # turtle1's topics and services stay registered, so its subscribers keep their connections.
            if name not in self.interfaces:
                self.interfaces[name] = TurtleInterface(self, name)
            rospy.loginfo(SPAWN_LOG, name, CENTRE, CENTRE, 0.0)
        return EmptyResponse()

    def on_cmd_vel(self, name, message):
        with self.lock:
            try:
                self.world.command(name, message.linear.x, message.linear.y, message.angular.z,
                                   time.monotonic())
            except TurtlesimError as error:
                rospy.logwarn_throttle(1.0, 'Ignored a velocity command for %s: %s' % (name, error))

    def _serve(self, response, request_world, *args):
        with self.lock:
            try:
                request_world(*args)
            except TurtlesimError as error:
                self._refuse(error)
        return response

    def on_set_pen(self, name, request):
        return self._serve(SetPenResponse(), self.world.set_pen, name, request.r, request.g, request.b,
                           request.width, request.off)

    def on_teleport_absolute(self, name, request):
        return self._serve(TeleportAbsoluteResponse(), self.world.teleport_absolute, name,
                           request.x, request.y, request.theta)

    def on_teleport_relative(self, name, request):
        return self._serve(TeleportRelativeResponse(), self.world.teleport_relative, name,
                           request.linear, request.angular)


def main():
    # rospy's own handlers would raise KeyboardInterrupt inside Tk's loop; a plain shutdown ends both loops.
    rospy.init_node('turtlesim', disable_signals=True)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: rospy.signal_shutdown('signal'))
    try:
        node = TurtlesimNode()
    except ValueError as error:
        rospy.logfatal('turtlesim: %s', error)
        sys.exit(1)
    node.start()
    try:
        window = CanvasWindow('TurtleSim', node.take_window_picture, lambda: not rospy.is_shutdown(),
                              lambda: rospy.signal_shutdown('window closed'))
    except WindowUnavailable as reason:
        rospy.loginfo('No window (%s): turtlesim runs headless; the canvas is published on %s',
                      reason, node.image_publisher.resolved_name)
        rospy.spin()
        return
    node.window_open = True
    window.run()
