"""What flatsim's rostest nodes share: waiting in sim time, latest messages, poses."""
import functools
import math
import threading
import time

import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry

from gazebo_msgs.msg import ModelState
from gazebo_msgs.srv import GetModelState, SetModelState

# Wall time for messages in flight to arrive while physics is paused.
DELIVERY_S = 0.3
# Guards every wait in sim time, so a simulator that stops advancing fails the
# test with a message instead of hanging until rostest's time limit.
WALL_LIMIT_S = 40.0


def yaw_of(quaternion):
    q = quaternion
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(angle):
    return math.atan2(math.sin(angle), math.cos(angle))


def wait_until(predicate, what, sim_timeout=10.0, wall_timeout=WALL_LIMIT_S):
    """Poll predicate until it holds; AssertionError naming `what` after the sim or wall timeout.

    sim_timeout None waits in wall time only: for what does not depend on sim time, such as
    a robot being spawned, or a subscriber connecting, while a world at a real-time factor
    of 0 races on without it.
    """
    wall_end = time.monotonic() + wall_timeout
    sim_end = None
    while True:
        if predicate():
            return
        now = rospy.get_time()
        if sim_timeout is not None and now > 0 and sim_end is None:
            sim_end = now + sim_timeout
        if sim_end is not None and now > sim_end:
            raise AssertionError('%s: not within %.1f s of sim time' % (what, sim_timeout))
        if time.monotonic() > wall_end:
            raise AssertionError('%s: not within %.0f s of wall time (sim time %.3f)'
                                 % (what, wall_timeout, now))
        time.sleep(0.002)


def wait_sim(seconds, wall_timeout=WALL_LIMIT_S):
    """Let `seconds` of sim time pass."""
    wait_until(lambda: rospy.get_time() > 0, 'sim time starting', sim_timeout=1e9)
    end = rospy.get_time() + seconds
    wait_until(lambda: rospy.get_time() >= end, '%.2f s of sim time passing' % seconds,
               sim_timeout=seconds + 1.0, wall_timeout=wall_timeout)


class Latest:
    """The newest message on a topic, plus how many arrived."""

    def __init__(self, topic, msg_type):
        self.topic = topic
        self.lock = threading.Lock()
        self.msg = None
        self.count = 0
        self.subscriber = rospy.Subscriber(topic, msg_type, self._on_msg, queue_size=1)

    def _on_msg(self, msg):
        with self.lock:
            self.msg = msg
            self.count += 1

    def get(self):
        with self.lock:
            return self.msg

    def wait(self, newer_than=None, sim_timeout=10.0):
        """The first message (stamped after newer_than, a sim time in seconds, if given).

        sim_timeout counts from when a publisher is connected: a sensor comes with its
        robot, which may be spawned many sim seconds into a world running as fast as it can.
        """
        wait_until(lambda: self.subscriber.get_num_connections() > 0, 'a publisher of %s' % self.topic,
                   sim_timeout=None)

        def arrived():
            msg = self.get()
            if msg is None:
                return False
            return newer_than is None or msg.header.stamp.to_sec() > newer_than
        wait_until(arrived, 'a message on %s' % self.topic, sim_timeout=sim_timeout)
        return self.get()

    def close(self):
        self.subscriber.unregister()


def model_state_proxy():
    rospy.wait_for_service('/gazebo/get_model_state', timeout=WALL_LIMIT_S)
    return rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)


def set_model_state_proxy():
    """A function (model_name, pose) -> gazebo_msgs/SetModelState response."""
    rospy.wait_for_service('/gazebo/set_model_state', timeout=WALL_LIMIT_S)
    proxy = rospy.ServiceProxy('/gazebo/set_model_state', SetModelState)
    # A partial, not a function, so that it stays unbound when kept on a test class.
    return functools.partial(_set_model_state, proxy)


def _set_model_state(proxy, model_name, pose):
    return proxy(ModelState(model_name=model_name, pose=pose))


def drivable_robot():
    """(Latest /odom, latched /cmd_vel publisher, get_model_state proxy) once all are served."""
    odom = Latest('/odom', Odometry)
    odom.wait(sim_timeout=30.0)
    cmd_vel = rospy.Publisher('/cmd_vel', Twist, queue_size=1, latch=True)
    wait_until(lambda: cmd_vel.get_num_connections() > 0, 'a /cmd_vel subscriber', sim_timeout=None)
    return odom, cmd_vel, model_state_proxy()


def publish_while_paused(publisher, linear, angular, pause, unpause):
    """Deliver a /cmd_vel Twist while physics is paused, so it acts from a known sim time."""
    msg = Twist()
    msg.linear.x, msg.angular.z = linear, angular
    pause()
    publisher.publish(msg)
    time.sleep(DELIVERY_S)
    unpause()


def paused_latest(pause, latest):
    """Pause physics; the newest message of a Latest once those in flight have arrived."""
    pause()
    time.sleep(DELIVERY_S)
    return latest.get()


def ground_truth(get_model_state, name):
    """(x, y, yaw) of a model from the simulator."""
    response = get_model_state(model_name=name)
    if not response.success:
        raise AssertionError('get_model_state(%s) failed: %s' % (name, response.status_message))
    pose = response.pose
    return pose.position.x, pose.position.y, yaw_of(pose.orientation)


def odom_pose(msg):
    pose = msg.pose.pose
    return pose.position.x, pose.position.y, yaw_of(pose.orientation)
