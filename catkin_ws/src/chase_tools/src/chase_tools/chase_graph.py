"""What chase_demo and evaluate share while a launched chase comes up and runs."""
import math
import os
import threading
import time
import xmlrpc.client

import rosgraph
import rospkg
import rospy
from nav_msgs.msg import Odometry

from chase_tools.procs import wait_until
from chase_tools.reach import centre_gap

# After a reset, odometry from before it may still be on its way, stamped later
# than this; the new run's first message is stamped within it.
NEW_RUN_STAMP_S = 0.5


def default_world_file():
    """my_robot's chase_house.world, the world the course chase runs in."""
    return os.path.join(rospkg.RosPack().get_path('my_robot'), 'worlds', 'chase_house.world')


def wait_for_service(name, launches, wall_timeout=60.0):
    """True once the service answers; False if a launch dies or the time runs out first."""
    def served():
        try:
            rospy.wait_for_service(name, timeout=1.0)
            return True
        except rospy.ROSException:
            return False
    return wait_until(served, [launches], wall_timeout, poll_s=0.0)


def chaser_ready(master, camera_topic, ignored_subscribers=()):
    """True once drive_bot serves its service and process_image subscribes to the camera.

    ignored_subscribers: other nodes on the camera topic (a throttle, say).
    """
    _, subscribers, services = master.getSystemState()
    return (any(name == '/ball_chaser/command_robot' for name, _ in services)
            and any(name == camera_topic and set(nodes) - set(ignored_subscribers)
                    for name, nodes in subscribers))


def planar_gap(a, b):
    """Distance in the ground plane between two geometry_msgs/Pose."""
    return math.hypot(a.position.x - b.position.x, a.position.y - b.position.y)


# Wall seconds the simulator has to list its connections (XML-RPC getBusInfo), far more than it takes.
BUS_INFO_S = 5.0


def lockstep_ready(master, camera_topic, command_topic='/cmd_vel', simulator='/flatsim',
                   chaser='/process_image', driver='/drive_bot', stale=frozenset()):
    """True once the simulator itself is connected both ways: its camera to the chaser,
    and the driver's commands to it.

    The master knows a node subscribes before the connection is made; a frame sent
    before then is lost, and under lockstep a command that arrives unannounced
    comes at a time that depends on the scheduler. stale: the simulator's ids of
    camera connections to an earlier node of the chaser's name, which it keeps until
    its next frame fails on them (camera_connections).
    """
    links = simulator_links(master, simulator)
    try:
        driver_uri = master.lookupNode(driver)
    except (OSError, xmlrpc.client.Error, rosgraph.MasterException):
        return False
    return (bool(camera_connections(links, camera_topic, chaser) - set(stale))
            and any(direction == 'i' and topic == command_topic and endpoint == driver_uri
                    for _id, direction, topic, endpoint in links))


def simulator_links(master, simulator='/flatsim'):
    """The simulator's connections, as (id, direction, topic, endpoint); [] if it does not say."""
    from chase_tools.grading.probe import ProbeError, node_proxy
    try:
        # Bounded: whatever answers under the simulator's name answers when it likes.
        code, _, connections = node_proxy(master.lookupNode(simulator), BUS_INFO_S).getBusInfo('/chase_tools')
    except (OSError, xmlrpc.client.Error, rosgraph.MasterException, ProbeError):
        return []
    if code != 1:
        return []
    return [(link_id, direction, topic, endpoint)
            for link_id, endpoint, direction, _transport, topic, *_ in connections]


def camera_connections(links, camera_topic, chaser):
    """The ids of the simulator's connections (simulator_links) that send its camera to chaser."""
    return {link_id for link_id, direction, topic, endpoint in links
            if direction == 'o' and topic == camera_topic and endpoint == chaser}


class ChaseWatch:
    """Follows the robot's odometry toward a ball that stands where it was placed.

    Within reach is chase_tools.reach's centre rule: the robot's origin within reach
    of the ball's centre. Odometry is stamped with sim time and comes at the drive
    plugin's own rate, so the first stamp at which the robot is within reach does not depend on
    how fast anything ran: under lockstep the same placement gives the same time
    to the ball every time. The robot's odometry must be ground truth
    (odometrySource world, as my_robot's is), and the ball is taken to stay
    where it was put: the robot can only touch it from within reach.
    """

    def __init__(self, odom_topic='/odom', keep_trace=False):
        self._cond = threading.Condition()
        self.ball = None
        self.done = True
        self.keep_trace = keep_trace
        self.trace = []
        self.subscriber = rospy.Subscriber(odom_topic, Odometry, self._on_odom, queue_size=10000)

    def begin(self, ball_xy, reach, timeout):
        """Start watching a new run (call it before unpausing): sim time must start near 0."""
        with self._cond:
            self.ball = ball_xy
            self.reach = reach
            self.timeout = timeout
            self.started = False
            self.done = False
            self.reached_at = None
            self.closest = math.inf
            self.last = None  # (stamp, gap) of the latest message
            self.trace = []   # with keep_trace: (stamp ns, x, y, qz, qw) of every message

    def _on_odom(self, msg):
        stamp = msg.header.stamp.to_sec()
        with self._cond:
            if self.done:
                return
            if not self.started:
                if stamp > NEW_RUN_STAMP_S:
                    return
                self.started = True
            position = msg.pose.pose.position
            if self.keep_trace:
                orientation = msg.pose.pose.orientation
                self.trace.append((msg.header.stamp.to_nsec(), position.x, position.y,
                                   orientation.z, orientation.w))
            gap = centre_gap((position.x, position.y), self.ball)
            self.closest = min(self.closest, gap)
            self.last = (stamp, gap)
            if gap <= self.reach:
                self.reached_at = stamp
                self.done = True
            elif stamp > self.timeout:
                self.done = True
            self._cond.notify_all()

    def wait(self, wall_timeout, alive=lambda: True, poll_s=0.5):
        """True once the run is decided (reached, or out of sim time); False if alive()
        turns false or the wall time runs out first."""
        deadline = time.monotonic() + wall_timeout
        with self._cond:
            while not self.done:
                remaining = deadline - time.monotonic()
                if remaining <= 0 or not alive():
                    return False
                self._cond.wait(min(poll_s, remaining))
        return True

    def progress(self):
        """(stamp, gap) of the latest odometry of this run, or None."""
        with self._cond:
            return self.last


# The simulator's model services and topic, in one place: Gazebo's names and
# gazebo_msgs types, which flatsim serves.
SIM_NAMESPACE = '/gazebo'
MODEL_STATES_TOPIC = SIM_NAMESPACE + '/model_states'
# The course robot's camera, which process_image subscribes to.
CAMERA_TOPIC = '/camera/rgb/image_raw'
# flatsim's own, beyond Gazebo's API: the world file it loaded (its ~world_name),
# and lockstep (std_srvs/SetBool).
WORLD_FILE_PARAM = '/flatsim/world_name'
LOCKSTEP_SERVICE = '/flatsim/set_lockstep'


def model_states_type():
    """The message type of MODEL_STATES_TOPIC."""
    from gazebo_msgs.msg import ModelStates
    return ModelStates


def sim_service(name):
    """The full name of one of the simulator's services: get_model_state, pause_physics, ..."""
    return '%s/%s' % (SIM_NAMESPACE, name)


class SimControl:
    """The simulator's model services, called from a rospy node.

    Calls retry once: on a loaded machine a single call now and then fails to connect.
    """

    def __init__(self):
        from gazebo_msgs.srv import DeleteModel, GetModelState, SetModelState
        from std_srvs.srv import Empty
        self._get = rospy.ServiceProxy(sim_service('get_model_state'), GetModelState)
        self._set = rospy.ServiceProxy(sim_service('set_model_state'), SetModelState)
        self._delete = rospy.ServiceProxy(sim_service('delete_model'), DeleteModel)
        self._pause = rospy.ServiceProxy(sim_service('pause_physics'), Empty)
        self._unpause = rospy.ServiceProxy(sim_service('unpause_physics'), Empty)
        self._reset = rospy.ServiceProxy(sim_service('reset_simulation'), Empty)

    @staticmethod
    def _call(proxy, *args, attempts=2):
        for attempt in range(attempts):
            try:
                return proxy(*args)
            except rospy.ServiceException:
                if attempt == attempts - 1:
                    raise
                rospy.sleep(0.0)

    def pose(self, name):
        """(geometry_msgs/Pose, geometry_msgs/Twist) of a model; None if there is no such model."""
        answer = self._call(self._get, name, '')
        return (answer.pose, answer.twist) if answer.success else None

    def place(self, name, pose):
        """Put a model at a flatsim.pose.Pose, at rest; raises FlatsimError if refused."""
        from gazebo_msgs.msg import ModelState
        from flatsim.errors import FlatsimError
        from flatsim.ros import messages as rosmsg
        answer = self._call(self._set, ModelState(model_name=name, pose=rosmsg.pose_msg(pose),
                                                  twist=rosmsg.twist_msg(0.0, 0.0, 0.0)))
        if not answer.success:
            raise FlatsimError(answer.status_message)

    def delete(self, name):
        answer = self._call(self._delete, name)
        return answer.success

    def pause(self):
        self._call(self._pause)

    def unpause(self):
        self._call(self._unpause)

    def reset(self):
        """Everything back to where the world file and the spawns put it; sim time back to 0."""
        self._call(self._reset)

    def time_step(self):
        """The physics step, in sim seconds."""
        from gazebo_msgs.srv import GetPhysicsProperties
        return self._call(rospy.ServiceProxy(sim_service('get_physics_properties'),
                                             GetPhysicsProperties)).time_step

    def set_real_time_factor(self, factor):
        """Sim seconds per wall second; 0 runs as fast as possible (Gazebo's max_update_rate 0)."""
        from gazebo_msgs.srv import GetPhysicsProperties, SetPhysicsProperties
        now = self._call(rospy.ServiceProxy(sim_service('get_physics_properties'), GetPhysicsProperties))
        answer = self._call(rospy.ServiceProxy(sim_service('set_physics_properties'), SetPhysicsProperties),
                            now.time_step, factor / now.time_step, now.gravity, now.ode_config)
        return answer.success

    def set_lockstep(self, on):
        """flatsim's lockstep (sim time waits for the controller after each frame); False if
        the simulator does not offer it."""
        from std_srvs.srv import SetBool
        try:
            rospy.wait_for_service(LOCKSTEP_SERVICE, timeout=1.0)
        except rospy.ROSException:
            return False
        return self._call(rospy.ServiceProxy(LOCKSTEP_SERVICE, SetBool), on).success


class PlacedRuns:
    """Chases from given placements on one launched world: each run starts from a reset.

    A run pauses the world (under lockstep the pause waits for the answer to the
    last frame), resets the simulation (time back to 0), places the robot and the
    ball, unpauses and watches the odometry until the robot is within reach or
    the sim time is up, then pauses again. The same placement therefore gives
    the same run whatever ran before it.
    """

    def __init__(self, robot='my_robot', ball='white_ball', odom_topic='/odom', keep_trace=False):
        self.robot = robot
        self.ball = ball
        self.sim = SimControl()
        self.pause, self.unpause, self.reset = self.sim.pause, self.sim.unpause, self.sim.reset
        self.place = self.sim.place
        self.watch = ChaseWatch(odom_topic, keep_trace)

    def run(self, robot_xy_yaw, ball_xy, reach, timeout, wall_timeout, alive=lambda: True):
        """(decided, reached_at, closest): reached_at is the sim time to the ball, or None."""
        from flatsim.pose import Pose
        self.pause()
        self.reset()
        ball_z = self.sim.pose(self.ball)[0].position.z
        x, y, yaw = robot_xy_yaw
        self.place(self.robot, Pose(x, y, 0.0, yaw=yaw))
        self.place(self.ball, Pose(ball_xy[0], ball_xy[1], ball_z))
        self.watch.begin(ball_xy, reach, timeout)
        self.unpause()
        try:
            decided = self.watch.wait(wall_timeout, alive)
        finally:
            try:
                self.pause()
            except (rospy.ServiceException, rospy.ROSException):
                pass  # the simulator is gone: alive() has said so already
        return decided, self.watch.reached_at, self.watch.closest
