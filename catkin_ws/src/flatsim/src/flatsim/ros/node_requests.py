"""What the simulator node does when asked: the topics it takes (clicked_point, each robot's
drive commands), its ~set_lockstep service, and the changes Gazebo's API makes
(flatsim.ros.gazebo_api)."""
import rospy
from std_srvs.srv import SetBoolResponse

from flatsim.errors import FlatsimError
from flatsim.loading.config import RobotSpec
from flatsim.names import logged_name
from flatsim.pose import Pose
from flatsim.ros.robot_io import RobotIo
from flatsim.studio.chase import DriveCommand
from flatsim.world import entities
from flatsim.world.drive import InvalidCommand


class NodeRequests:
    """FlatsimNode's topics in, its service and Gazebo's API changes; FlatsimNode
    (flatsim.ros.node) sets up the state they use."""

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
