"""Conversions between flatsim's plain values and ROS messages.

Message classes import without a master, so these are unit-tested directly;
only the node module touches rospy.
"""
import math
import struct

import genpy
import numpy as np
from geometry_msgs.msg import Pose as PoseMsg
from geometry_msgs.msg import Point, Quaternion, Transform, TransformStamped, Twist
from nav_msgs.msg import Odometry
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import CameraInfo, Image, JointState, LaserScan

from flatsim.errors import FlatsimError
from flatsim.pose import Pose, matrix_to_rpy


def stamp(sim_time):
    return genpy.Time.from_sec(sim_time)


def clock_msg(sim_time):
    return Clock(clock=stamp(sim_time))


def quaternion_from_rpy(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return Quaternion(
        x=sr * cp * cy - cr * sp * sy,
        y=cr * sp * cy + sr * cp * sy,
        z=cr * cp * sy - sr * sp * cy,
        w=cr * cp * cy + sr * sp * sy)


def rpy_from_quaternion(q):
    # Scaled by the largest part first: squaring parts near 1e155 or beyond would overflow.
    largest = max(abs(q.x), abs(q.y), abs(q.z), abs(q.w))
    if not math.isfinite(largest) or largest == 0.0:
        return 0.0, 0.0, 0.0
    x, y, z, w = q.x / largest, q.y / largest, q.z / largest, q.w / largest
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if norm < 1e-9:
        return 0.0, 0.0, 0.0
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    rot = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
           [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
           [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    return matrix_to_rpy(np.array(rot))


def pose_msg(pose):
    return PoseMsg(position=Point(x=pose.x, y=pose.y, z=pose.z),
                   orientation=quaternion_from_rpy(pose.roll, pose.pitch, pose.yaw))


def pose_from_msg(msg):
    roll, pitch, yaw = rpy_from_quaternion(msg.orientation)
    return Pose(msg.position.x, msg.position.y, msg.position.z, roll, pitch, yaw)


def requested_pose(msg):
    """pose_from_msg for a pose that a request asks for; FlatsimError for a quaternion that
    is not four finite numbers, which has no rotation to give. An all-zero quaternion is
    no rotation, as gazebo_ros's normalizing makes it."""
    q = msg.orientation
    if not all(math.isfinite(v) for v in (q.x, q.y, q.z, q.w)):
        raise FlatsimError('orientation (%g, %g, %g, %g) is not a quaternion of finite numbers'
                           % (q.x, q.y, q.z, q.w))
    return pose_from_msg(msg)


def twist_msg(vx, vy, wz):
    msg = Twist()
    msg.linear.x, msg.linear.y, msg.angular.z = vx, vy, wz
    return msg


def transform_msg(sim_time, parent, child, pose):
    msg = TransformStamped()
    msg.header.stamp = stamp(sim_time)
    msg.header.frame_id = parent
    msg.child_frame_id = child
    msg.transform = Transform()
    msg.transform.translation.x = pose.x
    msg.transform.translation.y = pose.y
    msg.transform.translation.z = pose.z
    msg.transform.rotation = quaternion_from_rpy(pose.roll, pose.pitch, pose.yaw)
    return msg


def odometry_msg(sim_time, frame, child_frame, pose, body_twist, covariance=(0.0, 0.0, 0.0),
                 twist_covariance=False):
    """body_twist is (vx, vy, wz) in the child frame, as gazebo_ros reports it.

    The pose covariance diagonal (x, y, yaw) is always set; skid steer also
    copies it onto the twist, diff drive leaves the twist covariance zero.
    """
    msg = Odometry()
    msg.header.stamp = stamp(sim_time)
    msg.header.frame_id = frame
    msg.child_frame_id = child_frame
    msg.pose.pose = pose_msg(pose)
    msg.twist.twist = twist_msg(*body_twist)
    cov_x, cov_y, cov_yaw = covariance
    diagonal = [cov_x, cov_y, 0.0, 0.0, 0.0, cov_yaw]
    for i, value in enumerate(diagonal):
        msg.pose.covariance[i * 7] = value
        if twist_covariance:
            msg.twist.covariance[i * 7] = value
    return msg


def joint_state_msg(sim_time, names, positions, velocities):
    msg = JointState()
    msg.header.stamp = stamp(sim_time)
    msg.name = list(names)
    msg.position = [float(p) for p in positions]
    msg.velocity = [float(v) for v in velocities]
    return msg


_HEADER_FIELDS = struct.Struct('<3I')
_LENGTH = struct.Struct('<I')
_SIZE = struct.Struct('<2I')
_STEP = struct.Struct('<BI')


class PixelImage(Image):
    """sensor_msgs/Image that keeps its pixels as the numpy array they were rendered into.

    The generated serialize() writes data through struct.pack after the caller's
    tobytes(): two extra copies of every camera frame on its way to the wire.
    This one writes the header fields itself and the pixels straight from the
    array into rospy's buffer. data still reads as bytes, for code in this process.
    """
    __slots__ = ('pixels',)

    def __init__(self, pixels):
        super().__init__()
        self.pixels = np.ascontiguousarray(pixels)

    @property
    def data(self):
        return self.pixels.tobytes()

    @data.setter
    def data(self, value):
        self.pixels = np.frombuffer(bytes(value), dtype=np.uint8)

    def serialize(self, buff):
        header = self.header
        buff.write(_HEADER_FIELDS.pack(header.seq, header.stamp.secs, header.stamp.nsecs))
        encoded = header.frame_id.encode('utf-8')
        buff.write(_LENGTH.pack(len(encoded)) + encoded)
        buff.write(_SIZE.pack(self.height, self.width))
        encoded = self.encoding.encode('utf-8')
        buff.write(_LENGTH.pack(len(encoded)) + encoded)
        buff.write(_STEP.pack(self.is_bigendian, self.step))
        buff.write(_LENGTH.pack(self.pixels.nbytes))
        buff.write(memoryview(self.pixels).cast('B'))


def image_msg(sim_time, frame_id, pixels, encoding):
    msg = PixelImage(pixels)
    msg.header.stamp = stamp(sim_time)
    msg.header.frame_id = frame_id
    msg.height, msg.width = pixels.shape[:2]
    msg.encoding = encoding
    msg.is_bigendian = 0
    msg.step = msg.width * (pixels.shape[2] if pixels.ndim == 3 else 1)
    return msg


def camera_info_msg(sim_time, frame_id, info):
    msg = CameraInfo()
    msg.header.stamp = stamp(sim_time)
    msg.header.frame_id = frame_id
    msg.width = int(info['width'])
    msg.height = int(info['height'])
    msg.distortion_model = info['distortion_model']
    msg.D = [float(v) for v in info['D']]
    msg.K = [float(v) for v in info['K']]
    msg.R = [float(v) for v in info['R']]
    msg.P = [float(v) for v in info['P']]
    return msg


def laser_scan_msg(sim_time, frame_id, fields, ranges, scan_time):
    msg = LaserScan()
    msg.header.stamp = stamp(sim_time)
    msg.header.frame_id = frame_id
    msg.angle_min = fields['angle_min']
    msg.angle_max = fields['angle_max']
    msg.angle_increment = fields['angle_increment']
    msg.range_min = fields['range_min']
    msg.range_max = fields['range_max']
    msg.scan_time = scan_time
    msg.time_increment = 0.0
    msg.ranges = ranges.tolist()
    return msg
