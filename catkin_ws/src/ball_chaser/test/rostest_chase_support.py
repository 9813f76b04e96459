"""Shared rig for the ball_chaser rostest nodes: place the robot and the ball in
flatsim while paused, then run sim time and watch the distance between them.

Distances are between the robot's model pose (its base origin) and the ball's
centre, both from /gazebo/get_model_state. Times are sim seconds.
"""
import math
import time

import rosgraph
import rospy
from geometry_msgs.msg import Pose, Twist
from std_srvs.srv import Empty

from gazebo_msgs.msg import ModelState
from gazebo_msgs.srv import GetModelState, SetModelState

from ball_chaser.srv import DriveToTarget

ROBOT = 'my_robot'
BALL = 'white_ball'
BALL_Z = 0.1
REACH_M = 0.4
CHASE_TIMEOUT_S = 60.0
# Outside the house's closed outer walls, so no camera can see it.
HIDDEN_BALL_XY = (30.0, 30.0)
# Sim time for process_image to see at least one frame (camera at 30 Hz).
SETTLE_S = 0.3
WALL_GUARD_S = 120.0
COMMAND_SERVICE = '/ball_chaser/command_robot'
CAMERA_TOPIC = '/camera/rgb/image_raw'


def make_pose(x, y, z=0.0, yaw=0.0):
    pose = Pose()
    pose.position.x, pose.position.y, pose.position.z = x, y, z
    pose.orientation.z, pose.orientation.w = math.sin(yaw / 2.0), math.cos(yaw / 2.0)
    return pose


def yaw_of(pose):
    q = pose.orientation
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def planar_distance(a, b):
    return math.hypot(a.position.x - b.position.x, a.position.y - b.position.y)


def angle_difference(a, b):
    """a - b wrapped to [-pi, pi)."""
    return (a - b + math.pi) % (2.0 * math.pi) - math.pi


class ChaseResult:
    def __init__(self, reached_after, closest, robot, ball):
        self.reached_after = reached_after
        self.closest = closest
        self.robot = robot
        self.ball = ball

    @property
    def reached(self):
        return self.reached_after is not None

    def __str__(self):
        when = 'reached in %.1f s' % self.reached_after if self.reached else 'not reached'
        return ('%s, closest %.3f m; robot at (%.2f, %.2f), ball at (%.2f, %.2f)'
                % (when, self.closest, self.robot.position.x, self.robot.position.y,
                   self.ball.position.x, self.ball.position.y))


class ChaseRig:
    """Services of flatsim and ball_chaser, with the waits the tests need."""

    def __init__(self, needs_process_image=True, wall_timeout=60.0):
        for name in ('/gazebo/get_model_state', '/gazebo/set_model_state',
                     '/gazebo/pause_physics', '/gazebo/unpause_physics', COMMAND_SERVICE):
            rospy.wait_for_service(name, timeout=wall_timeout)
        self.get_state = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState, persistent=True)
        self.set_state = rospy.ServiceProxy('/gazebo/set_model_state', SetModelState, persistent=True)
        self.pause = rospy.ServiceProxy('/gazebo/pause_physics', Empty)
        self.unpause = rospy.ServiceProxy('/gazebo/unpause_physics', Empty)
        self.command_robot = rospy.ServiceProxy(COMMAND_SERVICE, DriveToTarget)
        self._wait_for_model(ROBOT, wall_timeout)
        if needs_process_image:
            self._wait_for_camera_subscriber(wall_timeout)

    def _wait_for_model(self, name, wall_timeout):
        deadline = time.monotonic() + wall_timeout
        while not self.get_state(model_name=name).success:
            if time.monotonic() > deadline:
                raise AssertionError('%s was not spawned within %.0f s' % (name, wall_timeout))
            time.sleep(0.1)

    def _wait_for_camera_subscriber(self, wall_timeout):
        master = rosgraph.Master(rospy.get_name())
        deadline = time.monotonic() + wall_timeout
        while True:
            _, subscribers, _ = master.getSystemState()
            if any(topic == CAMERA_TOPIC and '/process_image' in nodes for topic, nodes in subscribers):
                return
            if time.monotonic() > deadline:
                raise AssertionError('process_image did not subscribe to %s' % CAMERA_TOPIC)
            time.sleep(0.1)

    # -- state ----------------------------------------------------------------
    def pose(self, name):
        response = self.get_state(model_name=name)
        if not response.success:
            raise AssertionError('get_model_state %s: %s' % (name, response.status_message))
        return response.pose

    def distance(self):
        return planar_distance(self.pose(ROBOT), self.pose(BALL))

    def move(self, name, x, y, z=0.0, yaw=0.0):
        response = self.set_state(ModelState(model_name=name, pose=make_pose(x, y, z, yaw),
                                             twist=Twist()))
        if not response.success:
            raise AssertionError('set_model_state %s: %s' % (name, response.status_message))

    def move_ball(self, x, y):
        self.move(BALL, x, y, BALL_Z)

    def run_for(self, sim_seconds):
        """Let sim time run for sim_seconds (physics must be unpaused)."""
        start = rospy.get_time()
        guard = time.monotonic() + WALL_GUARD_S
        while rospy.get_time() - start < sim_seconds:
            if time.monotonic() > guard:
                raise AssertionError('sim time stopped advancing')
            time.sleep(0.01)

    # -- scenarios ------------------------------------------------------------
    def reset(self, robot_xy_yaw, ball_xy):
        """Stop the robot, let process_image see no ball (so its last command is a
        stop and any new sight of the ball is sent), then place robot and ball.
        Physics is left paused."""
        self.pause()
        self.command_robot(0.0, 0.0)
        self.move_ball(*HIDDEN_BALL_XY)
        self.unpause()
        self.run_for(SETTLE_S)
        self.pause()
        self.command_robot(0.0, 0.0)
        x, y, yaw = robot_xy_yaw
        self.move(ROBOT, x, y, yaw=yaw)
        if ball_xy is not None:
            self.move_ball(*ball_xy)

    def chase(self, timeout=CHASE_TIMEOUT_S, reach=REACH_M, on_poll=None):
        """Unpause and wait until the robot is within reach of the ball.

        on_poll(elapsed_sim_s) is called on each poll, so a test can move the
        ball mid-run. Returns a ChaseResult; physics stays unpaused.
        """
        self.unpause()
        start = rospy.get_time()
        guard = time.monotonic() + WALL_GUARD_S
        closest = float('inf')
        while True:
            robot, ball = self.pose(ROBOT), self.pose(BALL)
            elapsed = rospy.get_time() - start
            gap = planar_distance(robot, ball)
            closest = min(closest, gap)
            if gap <= reach:
                return ChaseResult(elapsed, closest, robot, ball)
            if elapsed > timeout or time.monotonic() > guard:
                return ChaseResult(None, closest, robot, ball)
            if on_poll is not None:
                on_poll(elapsed)
            time.sleep(0.005)
