"""What the simulator node publishes as the world steps: /clock, each robot's odometry, tf,
joint states and sensors, and the whole world for rviz (~world_markers, the overhead picture)."""
import numpy
import rospy
from geometry_msgs.msg import PointStamped
from sensor_msgs.msg import Image
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from flatsim.ros import messages as rosmsg
from flatsim.ros.markers import build_specs, marker_array_msg
from flatsim.ros.overhead import OverheadView, moving_indices
from flatsim.sensors.lidar import scan_msg_fields


class NodeOutputs:
    """FlatsimNode's topics out; FlatsimNode (flatsim.ros.node) sets up the state they use."""

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
