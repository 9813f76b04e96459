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
      "move" then "stop" from one callback stops).
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
"""
import collections
import math
import sys
import threading
import time

import numpy
import rosgraph
import rospy
import rospy.impl.simtime
from rosgraph_msgs.msg import Clock
from geometry_msgs.msg import PointStamped, Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, JointState, LaserScan
from std_srvs.srv import SetBool, SetBoolResponse
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from flatsim import settings
from flatsim.errors import FlatsimError
from flatsim.loading.config import RobotSpec
from flatsim.loading.sdf_world import MAX_STEP_SIZE, MIN_STEP_SIZE, load_world
from flatsim.names import logged_name
from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg, prompt_init, second_server
from flatsim.ros.controllers import ControlIo
from flatsim.ros.gazebo_api import GazeboApi
from flatsim.ros.lockstep import DEFAULT_QUIET_S, Lockstep
from flatsim.ros.markers import build_specs, marker_array_msg
from flatsim.ros.overhead import OverheadView, moving_indices
from flatsim.ros.wire import publish_directly
from flatsim.sensors.camera import keep_freed_memory
from flatsim.sensors.lidar import scan_msg_fields
from flatsim.sensors.precompile import compile_kernels
from flatsim.studio.chase import DriveCommand
from flatsim.world import entities
from flatsim.world.drive import InvalidCommand
from flatsim.world.physics import MAX_SPEED, MAX_SPIN
from flatsim.world.sim import Simulation

class RobotIo:
    """The publishers and subscriber that one robot's plugins ask for."""

    def __init__(self, node, robot):
        self.robot = robot
        drive = robot.spec.drive
        self.odom_pub = self.tf_pub = self.joint_pub = self.cmd_sub = None
        if drive is not None:
            self.cmd_sub = rospy.Subscriber(drive.command_topic, Twist, node.on_cmd_vel,
                                            callback_args=robot, queue_size=1)
            if drive.publish_odometry:
                self.odom_pub = rospy.Publisher(drive.odometry_topic, Odometry, queue_size=10)
            if drive.publish_tf:
                self.tf_pub = rospy.Publisher('/tf', TFMessage, queue_size=100)
            if drive.publish_wheel_joint_state:
                self.joint_pub = rospy.Publisher('joint_states', JointState, queue_size=10)
        self.control_io = ControlIo(node, robot) if robot.control is not None else None
        self.sensor_pubs = {}
        for slot in robot.sensors:
            cfg = slot.config
            if slot.kind == 'camera':
                self.sensor_pubs[id(slot)] = (
                    rospy.Publisher(cfg.image_topic, Image, queue_size=1),
                    rospy.Publisher(cfg.info_topic, CameraInfo, queue_size=1))
            else:
                self.sensor_pubs[id(slot)] = (rospy.Publisher(cfg.topic, LaserScan, queue_size=1),)

    def close(self):
        if self.control_io is not None:
            self.control_io.close()
        for handle in [self.odom_pub, self.tf_pub, self.joint_pub, self.cmd_sub]:
            if handle is not None:
                handle.unregister()
        for pubs in self.sensor_pubs.values():
            for pub in pubs:
                pub.unregister()


# FlatsimNode(studio=START_STUDIO): the node starts its studio itself.
START_STUDIO = object()


class FlatsimNode:
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

    def setup_views(self):
        """The world in rviz, the overhead picture and click-to-place."""
        self.world_frame = rospy.get_param('~world_frame', 'odom')
        rate = float(rospy.get_param('~world_markers_rate', 10.0))
        self.world_markers_period = 1.0 / rate if rate > 0 else 0.0
        self.next_world_markers = 0.0
        self.marker_visuals = None
        self.marker_layout = None
        self.world_markers_pub = rospy.Publisher(
            '~world_markers', MarkerArray, queue_size=2, latch=True,
            subscriber_listener=_WholeWorldOnSubscribe(self))
        self.clicked_point_model = rospy.get_param('~clicked_point_model', '')
        self.clicked_point_sub = rospy.Subscriber('clicked_point', PointStamped,
                                                  self.on_clicked_point, queue_size=1)
        rate = float(rospy.get_param('~overhead_rate', 5.0))
        self.overhead_period = 1.0 / rate if rate > 0 else 0.0
        self.next_overhead = 0.0
        self.overhead = OverheadView(
            resolution=float(rospy.get_param('~overhead_resolution', 0.02)),
            cone_length=float(rospy.get_param('~overhead_cone_length', 3.0)))
        self.overhead_pub = rospy.Publisher('~overhead/image_raw', Image, queue_size=1)
        self.last_scans = {}
        with self.lock:
            self.world_markers_pub.publish(self.whole_world_markers())

    # -- main loop --------------------------------------------------------
    def run(self):
        """Step until shutdown; an unexpected error ends the node instead of freezing time."""
        try:
            self._step_loop()
        except Exception as error:  # noqa: BLE001 - anything here must stop the node visibly
            # Publishing on topics that shutdown has already closed is how a normal exit ends.
            if rospy.core.is_shutdown_requested():
                return
            rospy.logfatal('flatsim: stepping stopped: %r', error)
            rospy.signal_shutdown('stepping stopped: %r' % error)
            raise

    def _step_loop(self):
        self.stepping = True
        # Sim time must never be zero on /clock, or nodes wait for time to start.
        self.publish_clock()
        wall_start, sim_start = time.monotonic(), self.sim.time
        pacing_factor = self.real_time_factor
        while not rospy.is_shutdown():
            with self.lock:
                paused = self.sim.paused
                if not paused:
                    try:
                        self.sim.step()
                    except FlatsimError as error:
                        self.on_diverged(error)
                    self.publish_outputs()
                self.run_readers()
            # Outside the lock, so that the answer (and pause, reset) can come in.
            self.lockstep.hold()
            if paused:
                time.sleep(0.01)
                wall_start, sim_start = time.monotonic(), self.sim.time
                continue
            if self.real_time_factor != pacing_factor:
                # set_physics_properties changed the pace: measure it from now on.
                pacing_factor = self.real_time_factor
                wall_start, sim_start = time.monotonic(), self.sim.time
            if self.real_time_factor > 0:
                lag = (self.sim.time - sim_start) / self.real_time_factor - (time.monotonic() - wall_start)
                if lag > 0:
                    time.sleep(lag)
                elif lag < -0.5:
                    # Too slow to keep up: do not try to catch up in a burst later.
                    wall_start, sim_start = time.monotonic(), self.sim.time

    def read_between_steps(self, read, wait=0.05):
        """read() under the lock, run by the stepping loop between two steps.

        At full speed the loop takes the lock again microseconds after it lets it go, so a
        thread waiting for it is woken and sent back to sleep thousands of times a second,
        which costs the loop more than the read itself. Handed to the loop, the read costs
        one check per step. If the loop does not come round within wait seconds (a lockstep
        hold, a slow frame), or does not run yet, the read takes the lock itself.
        """
        if not self.stepping:
            with self.lock:
                return read()
        job = _Read(read)
        self.readers.append(job)
        if not job.done.wait(wait):
            with self.lock:
                job.run()
        return job.result()

    def run_readers(self):
        while self.readers:
            self.readers.popleft().run()

    def on_diverged(self, error):
        """Bodies pushed past what the solver can hold: the world starts over, and if it
        keeps diverging physics stops with one message instead of a reset every step."""
        recovery = self.sim.recover(error)
        if recovery.dropped_wrenches:
            rospy.logwarn('flatsim: dropped the wrenches on %s, which pushed it past what physics '
                          'holds (apply them again with /gazebo/apply_body_wrench)',
                          ', '.join(logged_name(body) for body in recovery.dropped_wrenches))
        if recovery.stopped:
            rospy.logerr('flatsim: %s again and again: physics paused; delete or move the model, '
                         'or clear the wrenches that push into it (/gazebo/clear_body_wrenches), '
                         'then call /gazebo/unpause_physics', error)
        else:
            rospy.logerr_throttle(1.0, 'flatsim: %s; the world starts over' % error)

    def report_slowed(self):
        if self.sim.physics.slowed:
            rospy.logwarn_throttle(5.0, 'flatsim: %s slowed to flatsim\'s limits (%g m/s, %g rad/s)'
                                   % (', '.join(sorted(self.sim.physics.slowed)), MAX_SPEED, MAX_SPIN))
            self.sim.physics.slowed.clear()

    def publish_clock(self):
        # /clock never says 0: nodes using sim time wait for a non-zero time.
        msg = rosmsg.clock_msg(max(self.sim.time, self.sim.step_size))
        self.clock_pub.publish(msg)
        if self.keeps_own_time:
            rospy.rostime._set_rostime(msg.clock)

    def publish_outputs(self):
        now = self.sim.time
        due = self.sim.due_sensors()
        if now + 1e-9 >= self.next_clock or due:
            self.publish_clock()
            self.next_clock = now + self.clock_period
        for io in self.robot_io.values():
            self.publish_drive(io, now)
            if io.control_io is not None:
                io.control_io.publish()
        for slot in due:
            self.publish_sensor(slot, now)
        self.gazebo.publish_states(now)
        self.report_slowed()
        self.publish_world_markers(now)
        self.publish_overhead(now)

    def publish_drive(self, io, now):
        robot, drive = io.robot, io.robot.spec.drive
        # The drive keeps the plugin's own updateRate clock and says when it updated.
        if drive is None or not robot.drive.publish_due:
            return
        pose, body_twist = robot.drive.odometry(self.sim.model_pose(robot.name),
                                                self.sim.model_twist(robot.name))
        if io.odom_pub is not None:
            io.odom_pub.publish(rosmsg.odometry_msg(
                now, drive.odometry_frame, drive.robot_base_frame, pose, body_twist,
                drive.covariance, twist_covariance=drive.plugin == 'skid_steer'))
        if io.tf_pub is not None:
            io.tf_pub.publish(TFMessage(transforms=[rosmsg.transform_msg(
                now, drive.odometry_frame, drive.robot_base_frame, pose)]))
        if io.joint_pub is not None:
            names, positions, velocities = robot.drive.wheel_states()
            io.joint_pub.publish(rosmsg.joint_state_msg(now, names, positions, velocities))

    def publish_sensor(self, slot, now):
        io = self.robot_io.get(slot.robot.name)
        if io is None:
            return
        pubs = io.sensor_pubs[id(slot)]
        # The overhead picture and the studio draw lidar hits, so they keep the lidar scanning too.
        drawn = slot.kind == 'laser' and (self.studio_scans or self.overhead_pub.get_num_connections())
        if not drawn and not any(pub.get_num_connections() for pub in pubs):
            return
        cfg = slot.config
        frame = cfg.frame_name
        if slot.kind == 'camera':
            image_pub, info_pub = pubs
            if image_pub.get_num_connections():
                pixels = self.sim.sense(slot)
                if self.lockstep.enabled and io.cmd_sub is not None and io.cmd_sub.get_num_connections():
                    # Before publishing: the answer may come before publish() returns.
                    self.lockstep.frame_sent(slot.robot.name)
                image_pub.publish(rosmsg.image_msg(now, frame, pixels, slot.impl.encoding()))
            if info_pub.get_num_connections():
                info_pub.publish(rosmsg.camera_info_msg(now, frame, slot.impl.info()))
        else:
            ranges = self.sim.sense(slot)
            eye = self.sim.sensor_pose(slot)
            self.last_scans[id(slot)] = (ranges, slot.impl.angles, (eye.x, eye.y, eye.yaw))
            if pubs[0].get_num_connections():
                pubs[0].publish(rosmsg.laser_scan_msg(now, frame, scan_msg_fields(cfg), ranges,
                                                      slot.period))

    def whole_world_markers(self, for_everyone=True):
        """Every visual of the world.

        for_everyone: the array goes to all subscribers, so it starts with
        DELETEALL if models came or went since the last such array.
        """
        self.sim.sync_moving_prims()
        visuals = self.sim.scene.select(visual=True)
        changed = False
        if for_everyone:
            changed = self.marker_visuals is not None and not numpy.array_equal(
                visuals, self.marker_visuals)
            self.marker_visuals = visuals
            self.marker_layout = self.sim.layout_version
        return marker_array_msg(build_specs(self.sim.scene), self.world_frame,
                                clear_first=changed)

    def publish_world_markers(self, now):
        if not self.world_markers_period or now + 1e-9 < self.next_world_markers:
            return
        self.next_world_markers = now + self.world_markers_period
        if not self.world_markers_pub.get_num_connections():
            return
        # Models came or went, or a static one was moved by hand: the whole world again.
        if (not numpy.array_equal(self.sim.scene.select(visual=True), self.marker_visuals)
                or self.sim.layout_version != self.marker_layout):
            self.world_markers_pub.publish(self.whole_world_markers())
            return
        moving = moving_indices(self.sim)
        if moving:
            self.sim.sync_moving_prims()
            self.world_markers_pub.publish(marker_array_msg(
                build_specs(self.sim.scene, moving), self.world_frame))

    def publish_overhead(self, now):
        if not self.overhead_period or now + 1e-9 < self.next_overhead:
            return
        self.next_overhead = now + self.overhead_period
        if not self.overhead_pub.get_num_connections():
            return
        scans = [self.last_scans[id(slot)] for robot in self.sim.robots()
                 for slot in robot.sensors if id(slot) in self.last_scans]
        image = self.overhead.render(self.sim, scans)
        self.overhead_pub.publish(rosmsg.image_msg(now, self.world_frame, image, 'rgb8'))

    # -- topics and services ------------------------------------------------
    def on_clicked_point(self, msg):
        frame = msg.header.frame_id.lstrip('/')
        if frame and frame != self.world_frame:
            rospy.logwarn('flatsim: clicked point is in frame %r, not the world frame %r; '
                          'set rviz\'s fixed frame to %s to place %s',
                          logged_name(frame), self.world_frame, self.world_frame,
                          self.clicked_point_model or 'the ball')
            return
        with self.lock:
            try:
                name = self.clicked_point_model or entities.the_ball(entities.ball_names(self.sim))
                pose = self.sim.model_pose(name)
                self.sim.set_model_state(name, Pose(msg.point.x, msg.point.y, pose.z,
                                                    yaw=pose.yaw))
            except FlatsimError as error:
                rospy.logwarn('flatsim: cannot place %s at the clicked point: %s%s',
                              self.clicked_point_model or 'the ball', error,
                              '' if self.clicked_point_model else
                              ' (set ~clicked_point_model to the model to move)')
                return
        rospy.loginfo('flatsim: moved %s to (%.2f, %.2f)', name, msg.point.x, msg.point.y)

    def on_cmd_vel(self, msg, robot):
        with self.lock:
            refused = ''
            try:
                robot.drive.set_command(msg.linear.x, msg.angular.z, msg.linear.y)
            except InvalidCommand as error:
                refused = str(error)
                rospy.logwarn_throttle(5.0, 'flatsim: %s: %s' % (robot.name, error))
            self.record_command(robot, msg, refused)
        # Even a refused command is the controller's answer to the last frame.
        self.lockstep.command_arrived(robot.name)

    def record_command(self, robot, msg, refused=''):
        """Keep a drive command (Twist) for the studio's chase view while one is open; call it
        holding the lock."""
        log = self.command_log
        if log is not None:
            sender = (getattr(msg, '_connection_header', None) or {}).get('callerid', '')
            log.add(DriveCommand(self.sim.time, robot.name, msg.linear.x, msg.angular.z, sender,
                                 refused))

    # -- what Gazebo's API changes (flatsim.ros.gazebo_api), under the lock -------
    def add_model(self, name, loaded, pose, origin=None):
        """Put a loaded robot (RobotSpec) or world model (sdf_world.Model) into the world.

        origin (a ModelOrigin) says where it came from, for Save World As; by default a spawn.
        """
        if isinstance(loaded, RobotSpec):
            robot = self.sim.spawn_robot(name, loaded, pose, origin)
            # It may have taken the place of a robot saved in the world file.
            self.close_robot_io(name)
            self.robot_io[name] = RobotIo(self, robot)
        else:
            self.sim.add_world_model(loaded, pose * loaded.pose, origin)

    def publish_ball_names(self):
        """Call without holding the lock: setting a parameter waits for the master."""
        with self.lock:
            names = entities.ball_names(self.sim)
        rospy.set_param('~ball_names', names)

    def remove_model(self, name):
        self.sim.delete_model(name)
        self.close_robot_io(name)

    def close_robot_io(self, name):
        io = self.robot_io.pop(name, None)
        if io is not None:
            for slot in io.robot.sensors:
                self.last_scans.pop(id(slot), None)
            io.close()
            self.lockstep.forget(name)

    def pause(self):
        """Under lockstep, return once the last frame is answered (or its wait ran out), so
        that no command is on its way that a reset or a placement after the pause could meet."""
        with self.lock:
            self.sim.paused = True
        self.lockstep.settle(wall_timeout=self.lockstep.max_wait)

    def step_paused(self, count):
        """Advance count steps while paused, publishing as the loop does; False if not paused."""
        with self.lock:
            if not self.sim.paused:
                return False
            for _ in range(count):
                self.sim.paused = False
                try:
                    self.sim.step()
                except FlatsimError as error:
                    self.on_diverged(error)
                finally:
                    self.sim.paused = True
                self.publish_outputs()
        return True

    def reset_world(self):
        with self.lock:
            self.sim.reset_world()
        self.lockstep.interrupt()

    def reset_time(self):
        with self.lock:
            self.sim.reset_time()
            self.last_scans.clear()
            if self.command_log is not None:
                self.command_log.clear()
            self.next_clock = self.next_world_markers = self.next_overhead = 0.0
            self.gazebo.next_states = 0.0
        self.lockstep.interrupt()

    def set_real_time_factor(self, factor):
        self.real_time_factor = factor

    def on_set_lockstep(self, req):
        self.lockstep.enabled = bool(req.data)
        self.lockstep.interrupt()
        if self.lockstep.enabled:
            self.lockstep.new_controllers()
        state = 'on' if self.lockstep.enabled else 'off'
        # The parameter tells the truth to whoever reads it later.
        rospy.set_param('~lockstep', self.lockstep.enabled)
        rospy.loginfo('flatsim: lockstep %s', state)
        return SetBoolResponse(success=True, message='lockstep %s' % state)


class _Read:
    """A read handed to the stepping loop; run() once, by whichever thread gets to it first."""

    def __init__(self, read):
        self.read = read
        self.done = threading.Event()
        self.claimed = threading.Lock()
        self.value = self.error = None

    def run(self):
        if not self.claimed.acquire(blocking=False):
            return
        try:
            self.value = self.read()
        except Exception as error:  # noqa: BLE001 - handed back to the reader's thread
            self.error = error
        self.done.set()

    def result(self):
        self.done.wait()
        if self.error is not None:
            raise self.error
        return self.value


class _WholeWorldOnSubscribe(rospy.SubscribeListener):
    """Sends a new ~world_markers subscriber the whole world.

    Updates between changes carry only the moving markers, so the latched
    message alone may hold just the ball.
    """

    def __init__(self, node):
        super().__init__()
        self.node = node

    def peer_subscribe(self, topic_name, topic_publish, peer_publish):
        # peer_publish skips the publisher's own lock, yet shares its buffer
        # with publish(); take both locks in the order the main loop does.
        publisher = getattr(self.node, 'world_markers_pub', None)
        if publisher is None:
            return  # still starting: the first whole-world array goes to everyone
        impl = publisher.impl
        with self.node.lock:
            markers = self.node.whole_world_markers(for_everyone=False)
            impl.acquire()
            try:
                peer_publish(markers)
            finally:
                impl.release()


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
