"""RobotIo: the publishers and subscriber that one robot's <gazebo> plugins ask the simulator
node (flatsim.ros.node) for."""
import rospy
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image, JointState, LaserScan
from tf2_msgs.msg import TFMessage

from flatsim.ros.controllers import ControlIo


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
