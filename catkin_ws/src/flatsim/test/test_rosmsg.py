"""Message conversions: poses survive the round trip and frames follow gazebo_ros."""
import math

import numpy as np
import pytest

from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg


@pytest.mark.parametrize('pose', [
    Pose(1.0, -2.0, 0.3, 0.0, 0.0, 0.0),
    Pose(0.5, 0.5, 0.0, 0.0, 0.0, 3.0),
    Pose(0.0, 0.0, 1.0, 0.2, -0.4, -2.5),
])
def test_pose_round_trip(pose):
    back = rosmsg.pose_from_msg(rosmsg.pose_msg(pose))
    assert np.allclose(back.matrix(), pose.matrix(), atol=1e-9)


def test_yaw_quaternion_is_about_z():
    q = rosmsg.quaternion_from_rpy(0.0, 0.0, math.pi / 2)
    assert (q.x, q.y) == pytest.approx((0.0, 0.0))
    assert (q.z, q.w) == pytest.approx((math.sqrt(0.5), math.sqrt(0.5)))


def test_zero_quaternion_reads_as_no_rotation():
    # rosservice call with only a position leaves the quaternion all zeros.
    msg = rosmsg.pose_msg(Pose(1.0, 2.0, 0.0))
    msg.orientation.w = 0.0
    assert rosmsg.pose_from_msg(msg).yaw == 0.0


def test_odometry_twist_covariance_only_when_asked():
    diff = rosmsg.odometry_msg(1.5, 'odom', 'robot_footprint', Pose(1, 2, 0, 0, 0, 0.5),
                               (0.3, 0.0, 0.1), (1e-5, 1e-5, 1e-3))
    skid = rosmsg.odometry_msg(1.5, 'odom', 'base_link', Pose(), (0.3, 0.0, 0.1),
                               (1e-4, 1e-4, 1e-2), twist_covariance=True)
    assert diff.header.frame_id == 'odom' and diff.child_frame_id == 'robot_footprint'
    assert diff.header.stamp.to_sec() == pytest.approx(1.5)
    assert diff.pose.covariance[0] == 1e-5 and diff.pose.covariance[35] == 1e-3
    assert not any(diff.twist.covariance)
    assert skid.twist.covariance[35] == 1e-2
    assert diff.twist.twist.linear.x == 0.3 and diff.twist.twist.angular.z == 0.1


def test_image_message_has_tight_rows():
    pixels = np.zeros((4, 6, 3), dtype=np.uint8)
    pixels[1, 2] = (255, 0, 0)
    msg = rosmsg.image_msg(2.0, 'camera', pixels, 'rgb8')
    assert (msg.height, msg.width, msg.step, msg.encoding) == (4, 6, 18, 'rgb8')
    assert msg.data[1 * 18 + 2 * 3] == 255
    mono = rosmsg.image_msg(2.0, 'camera', np.zeros((4, 6), dtype=np.uint8), 'mono8')
    assert mono.step == 6


def test_an_image_serializes_to_the_bytes_of_the_generated_message():
    from io import BytesIO
    from sensor_msgs.msg import Image
    pixels = np.arange(4 * 6 * 3, dtype=np.uint8).reshape(4, 6, 3)
    fast = rosmsg.image_msg(2.25, 'caméra', pixels, 'rgb8')
    fast.header.seq = 7
    plain = Image(header=fast.header, height=4, width=6, encoding='rgb8', is_bigendian=0, step=18,
                  data=pixels.tobytes())
    ours, theirs = BytesIO(), BytesIO()
    fast.serialize(ours)
    plain.serialize(theirs)
    assert ours.getvalue() == theirs.getvalue()
    back = Image()
    back.deserialize(ours.getvalue())
    assert back.data == pixels.tobytes() and back.header.frame_id == 'caméra'
