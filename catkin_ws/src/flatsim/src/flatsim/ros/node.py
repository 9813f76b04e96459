"""flatsim: the simulator node, standing in for gazebo_ros's gzserver.

Parameters:
  ~world_name (str, ''): SDF .world file to load; empty for an empty world.
  ~paused (bool, false): start with physics paused (unpause with ~unpause_physics).
  ~real_time_factor (float, 1.0): sim seconds per wall second, 0.001 to 1000; 0 runs as fast
      as possible. Any other value ends the node with an error that says so.
  ~step_size (float, 0.002 s): fixed physics step.
  ~seed (int, 0): seed of the sensor noise, 0 to 4294967295 (as Gazebo's --seed); any other
      value ends the node with an error that says so.
  ~lockstep (bool, false): after each camera frame, hold sim time until the
      robot's controller reacts on the drive's command topic (flatsim.ros.lockstep);
      ~set_lockstep turns it on or off while running.
  ~lockstep_max_wait (float, 1.0 s of wall time): the longest hold for one frame.
  ~lockstep_min_wait (float, 0.005 s of wall time): the hold for a controller
      that has never reacted.
  ~lockstep_quiet (float, 0.01 s of wall time): once a frame is answered, the hold goes on
      until the controller has sent no further command for this long (or for twice its
      longest follow-up so far), so that the frame's last command is the one in effect (a
      "move" then "stop" from one callback stops). A controller whose last 10 answers each
      had the same number of commands is waited for to that many instead; one that has not
      yet answered 10 frames, for ten times this long.
  ~clock_period (float, 0.01 s of sim time): how often /clock is published
      between sensor updates (it is also published before every sensor message).
  ~model_states_rate (float, 50 Hz of sim time): rate of gazebo/model_states and
      gazebo/link_states while subscribed (Gazebo publishes them every step).
  ~world_frame (str, 'odom'): frame of ~world_markers and ~overhead/image_raw. Odometry is
      ground truth (odometrySource world), so the world frame coincides with odom.
  ~world_markers_rate (float, 10 Hz of sim time): how often the moving models' markers
      (balls) are republished while someone subscribes; 0 publishes only the whole world.
  ~clicked_point_model (str, ''): the model that clicked_point moves; empty: the world's
      ball, whatever its name (its one pushable sphere; with several, a warning names them).
  ~overhead_rate (float, 5 Hz of sim time): rate of ~overhead/image_raw while subscribed.
  ~overhead_resolution (float, 0.02 m per pixel): scale of the overhead picture.
  ~overhead_cone_length (float, 3.0 m): how far each camera's view cone is drawn.
  ~studio (bool, true): serve the studio, Gazebo's window as a web page (flatsim.studio),
      on 127.0.0.1 behind a per-run token; gzclient opens it. A simulator started before
      its master answers serves it at once, with the ~studio parameters of its command line.
  ~studio_first (bool, false): on a running master, start the studio before loading the
      world, so that a browser loads the page meanwhile (the gazebo and gzserver commands set
      it); otherwise the studio starts once the world steps, so that the robot's first sensor
      frames do not wait for the web server's imports.
  ~studio_port (int, 0): its TCP port; 0 takes a free one.
  ~studio_rate (float, 40 Hz of wall time): how often model poses go to open pages.
  ~studio_save_over_world (bool, false): the studio's File > Save World writes over
      ~world_name, and may write in its folder (the gazebo and gzserver commands set it, as
      their WORLD is the user's own file); otherwise Save World asks for a file first.

Arguments: --debug logs at debug level.

A node of the same name that already runs on the master is left alone: this
one says what a second gzserver says and exits with status 255 without
registering (flatsim.ros.second_server).

Topics: /clock; per robot, what its <gazebo> plugins name (cmd_vel, odom, /tf,
joint_states, camera image and camera_info, scan); ~world_markers
(visualization_msgs/MarkerArray, latched, and sent whole to every new subscriber);
~overhead/image_raw (sensor_msgs/Image rgb8, top down). Subscribes to clicked_point
(geometry_msgs/PointStamped, rviz's Publish Point tool): the click moves
~clicked_point_model there, at rest. Keeps the parameter ~ball_names (the world's balls,
for move_model) up to date.
Gazebo's own topics and services live under gazebo/ (flatsim.ros.gazebo_api).
Service ~set_lockstep (std_srvs/SetBool) turns lockstep on or off; turned on, it waits
for each controller as for a new one (call it again after starting the controllers afresh).

The node's stepping loop is in flatsim.ros.node_loop, what it publishes in
flatsim.ros.node_outputs, what it does when asked in flatsim.ros.node_requests.
"""
import collections
import math
import sys
import threading
import time

import rosgraph
import rospy
import rospy.impl.simtime
from rosgraph_msgs.msg import Clock
from std_srvs.srv import SetBool

from flatsim import settings
from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import MAX_STEP_SIZE, MIN_STEP_SIZE, load_world
from flatsim.ros import prompt_init, second_server
from flatsim.ros.gazebo_api import GazeboApi
from flatsim.ros.lockstep import DEFAULT_QUIET_S, Lockstep
from flatsim.ros.node_loop import NodeLoop
from flatsim.ros.node_outputs import NodeOutputs
from flatsim.ros.node_requests import NodeRequests
from flatsim.ros.robot_io import RobotIo
from flatsim.ros.wire import publish_directly
from flatsim.sensors.camera import keep_freed_memory
from flatsim.sensors.precompile import compile_kernels
from flatsim.world.sim import Simulation


# FlatsimNode(studio=START_STUDIO): the node starts its studio itself.
START_STUDIO = object()


class FlatsimNode(NodeLoop, NodeOutputs, NodeRequests):
    def __init__(self, studio=START_STUDIO):
        """studio: the RunningStudio that main() started before the master answered (or None
        if it did not start one); by default the node starts it (see ~studio_first)."""
        self.lock = threading.RLock()
        try:
            # Before anything starts: a value flatsim cannot run with ends it with one line.
            self.real_time_factor = settings.real_time_factor(
                rospy.get_param('~real_time_factor', 1.0))
            self.seed = settings.seed(rospy.get_param('~seed', 0))
        except FlatsimError:
            if studio not in (START_STUDIO, None):
                studio.stop()
            raise
        self.keeps_own_time = keep_own_time()
        self.clock_period = float(rospy.get_param('~clock_period', 0.01))
        world_name = self.world_name = rospy.get_param('~world_name', '')
        self.readers = collections.deque()   # reads waiting for the stepping loop
        self.stepping = False                 # the stepping loop runs (and takes the readers)
        # Without a studio from main(): started now, or by start_studio() once the world steps.
        self.studio_pending = (studio is START_STUDIO
                               and not bool(rospy.get_param('~studio_first', False)))
        if studio is START_STUDIO and not self.studio_pending:
            from flatsim.ros.studio_world import start_studio
            studio = start_studio(world_name)
        self.studio = None if studio is START_STUDIO else studio
        if self.studio is not None:
            self.studio.attach(self)
        try:
            self._load(world_name)
        except Exception:
            if self.studio is not None:
                self.studio.stop()
            raise

    def _load(self, world_name):
        world = load_world(world_name) if world_name else None
        # The file as read (its lights, physics, gui...), for Save World As.
        self.world = world
        self.sim = Simulation(world, step_size=_step_size_param(), seed=self.seed)
        self.sim.paused = bool(rospy.get_param('~paused', False))
        self.lockstep = Lockstep(enabled=bool(rospy.get_param('~lockstep', False)),
                                 max_wait=float(rospy.get_param('~lockstep_max_wait', 1.0)),
                                 min_wait=float(rospy.get_param('~lockstep_min_wait', 0.005)),
                                 quiet=float(rospy.get_param('~lockstep_quiet', DEFAULT_QUIET_S)))
        for skipped in self.sim.skipped:
            rospy.logwarn('flatsim %s %s', skipped.verb, skipped)
        self.robot_io = {}
        self.studio_scans = False   # an open page draws the lidars' rays
        self.command_log = None     # a chase view is open: the drive commands robots get
        self.publish_ball_names()
        self.next_clock = 0.0
        self.clock_pub = rospy.Publisher('/clock', Clock, queue_size=10)
        self.setup_views()
        # Gazebo's services answer as soon as they are registered: a spawn waits for the lock
        # until the robots saved in the world file have theirs, or both would make its topics.
        with self.lock:
            self.gazebo = GazeboApi(self, world)
            for robot in self.sim.robots():
                # Robots saved in the world file run as if spawned.
                self.robot_io[robot.name] = RobotIo(self, robot)
        self.lockstep_service = rospy.Service('~set_lockstep', SetBool, self.on_set_lockstep)
        rospy.on_shutdown(self.lockstep.interrupt)
        rospy.loginfo('flatsim: world %s, step %.4f s, real-time factor %s%s%s',
                      world_name or '(empty)', self.sim.step_size,
                      self.real_time_factor or 'as fast as possible',
                      ', lockstep' if self.lockstep.enabled else '',
                      ', paused' if self.sim.paused else '')

    def open_studio(self):
        """Pages waiting for the world are shown it: call once the world is loaded."""
        if self.studio is not None:
            self.studio.open()

    def start_studio(self):
        """Start the studio on the loaded world, when it is pending (see ~studio_first)."""
        # Imported here: its web server's imports (aiohttp) cost a tenth of a second, which
        # a launch's first camera frame no longer waits for.
        from flatsim.ros.studio_world import start_studio
        studio = start_studio(self.world_name)
        if studio is None:
            return
        try:
            studio.attach(self)
            studio.open()
        except RuntimeError:
            # The node shut down while the studio started: its event loop has closed.
            if rospy.core.is_shutdown_requested():
                return
            raise
        self.studio = studio


def _step_size_param():
    step = float(rospy.get_param('~step_size', 0.002))
    bounded = min(max(step, MIN_STEP_SIZE), MAX_STEP_SIZE) if math.isfinite(step) else 0.002
    if bounded != step:
        rospy.logwarn('flatsim: ~step_size %g s is outside the %g to %g s flatsim steps; using %g s',
                      step, MIN_STEP_SIZE, MAX_STEP_SIZE, bounded)
    return bounded


def keep_own_time():
    """Under /use_sim_time, stop reading /clock and let publish_clock set rospy's time.

    The simulator makes sim time: reading its own /clock back over TCP, as rospy
    does for every node under /use_sim_time, cost it a tenth of its time at full
    speed. Returns whether rospy's time is now this node's to keep.
    """
    clock_sub = getattr(rospy.impl.simtime, '_clock_sub', None)
    if clock_sub is None:
        return False
    clock_sub.unregister()
    rospy.impl.simtime._clock_sub = None
    return True


def wait_for_master():
    """Wait for the ROS master, as rospy's registration does, instead of failing to set
    the private parameters: `gazebo WORLD` starts the simulator beside a new roscore."""
    told = False
    while not rosgraph.is_master_online():
        if not told:
            print('flatsim: waiting for the ROS master at %s' % rosgraph.get_master_uri(), flush=True)
            told = True
        time.sleep(0.05)


def main():
    debug = '--debug' in rospy.myargv()
    studio = START_STUDIO
    if not rosgraph.is_master_online():
        # `gazebo WORLD` starts roscore beside the simulator: the page loads meanwhile. (No
        # other simulator can run on a master that is not up yet.)
        from flatsim.ros.studio_world import start_studio
        params = rospy.client.load_command_line_node_params(sys.argv)
        studio = start_studio(params.get('world_name', ''), params)
    wait_for_master()
    # Before registering: registering would shut down a simulator already running under this name.
    refused = second_server.refusal('flatsim', sys.argv)
    if refused:
        if studio not in (START_STUDIO, None):
            studio.stop()
        print(refused, file=sys.stderr, flush=True)
        raise SystemExit(second_server.EXIT_STATUS)
    prompt_init.init_node('flatsim', log_level=rospy.DEBUG if debug else rospy.INFO)
    publish_directly()
    # Camera frames allocate megabytes each; kept, freed memory serves the next frame.
    keep_freed_memory()
    try:
        node = FlatsimNode(studio)
    except FlatsimError as error:
        rospy.logfatal('flatsim: %s', error)
        raise SystemExit(1) from None
    # Pages see the world from now on, while the kernels load.
    node.open_studio()
    # Stepping runs beside the main thread: rospy's SIGINT handler runs in the
    # main thread, and if that thread were inside publish() holding rospy's
    # topic locks, the shutdown it starts would wait on them forever.
    stepper = threading.Thread(target=node.run, name='flatsim-step', daemon=True)
    stepper.start()
    if node.studio_pending:
        # Beside the stepping, so that the robot's first frames do not wait for it; the
        # page loads in the time the browser takes to start anyway.
        threading.Thread(target=node.start_studio, name='flatsim-studio', daemon=True).start()
    # Loaded here rather than at the first frame, which would wait for them just the same:
    # a user who cannot write the cache beside the sources compiles them (seconds) into
    # their own, and the world runs meanwhile until a sensor needs them.
    if compile_kernels():
        rospy.loginfo('flatsim: compiled the sensor kernels (./setup.sh does this ahead)')
    rospy.spin()
    stepper.join(timeout=5.0)
