import math
import shutil
from pathlib import Path

import pytest

from flatsim.errors import FlatsimError, ModelFileError
from flatsim.loading.urdf_robot import expand_xacro, link_pose, load_robot, ros_resolve, tf_resolve
from flatsim.pose import Pose

FIXTURES = Path(__file__).parent / 'fixtures' / 'robots'

# A course-shaped robot: footprint -> chassis (box) with two wheel hinges, a camera and a lidar link.
BODY = """
  <link name="robot_footprint"/>
  <joint name="footprint_joint" type="fixed">
    <parent link="robot_footprint"/><child link="chassis"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/>
  </joint>
  <link name="chassis">
    <inertial><mass value="15"/></inertial>
    <collision><origin xyz="0 0 0"/><geometry><box size="0.4 0.2 0.1"/></geometry></collision>
  </link>
  <link name="left_wheel">
    <inertial><mass value="5"/></inertial>
    <collision><origin xyz="0 0 0" rpy="0 1.5707963267948966 1.5707963267948966"/>
      <geometry><cylinder radius="0.1" length="0.05"/></geometry></collision>
  </link>
  <joint name="left_wheel_hinge" type="continuous">
    <parent link="chassis"/><child link="left_wheel"/>
    <origin xyz="0 0.15 0"/><axis xyz="0 1 0"/>
  </joint>
  <link name="right_wheel">
    <inertial><mass value="5"/></inertial>
    <collision><origin xyz="0 0 0" rpy="0 1.5707963267948966 1.5707963267948966"/>
      <geometry><cylinder radius="0.1" length="0.05"/></geometry></collision>
  </link>
  <joint name="right_wheel_hinge" type="continuous">
    <parent link="chassis"/><child link="right_wheel"/>
    <origin xyz="0 -0.15 0"/><axis xyz="0 1 0"/>
  </joint>
  <link name="camera"/>
  <joint name="camera_joint" type="fixed">
    <parent link="chassis"/><child link="camera"/><origin xyz="0.2 0 0.05"/>
  </joint>
  <link name="hokuyo"/>
  <joint name="hokuyo_joint" type="fixed">
    <parent link="chassis"/><child link="hokuyo"/><origin xyz="0.15 0 0.1"/>
  </joint>
"""

DIFF_DRIVE = """
  <gazebo>
    <plugin name="differential_drive_controller" filename="libgazebo_ros_diff_drive.so">
      {extra}
      <leftJoint>left_wheel_hinge</leftJoint>
      <rightJoint>right_wheel_hinge</rightJoint>
    </plugin>
  </gazebo>
"""

CAMERA = """
  <gazebo reference="camera">
    <sensor type="{sensor_type}" name="camera1">
      {sensor_extra}
      <camera name="head">{camera_extra}</camera>
      <plugin name="camera_controller" filename="{filename}">{plugin_extra}</plugin>
    </sensor>
  </gazebo>
"""

LASER = """
  <gazebo reference="hokuyo">
    <sensor type="{sensor_type}" name="head_hokuyo_sensor">
      {sensor_extra}
      <ray>{ray}</ray>
      <plugin name="laser_controller" filename="{filename}">{plugin_extra}</plugin>
    </sensor>
  </gazebo>
"""


def robot(*parts, body=BODY, name='test_bot'):
    return '<?xml version="1.0"?>\n<robot name="%s">%s%s\n</robot>\n' % (name, body, ''.join(parts))


def diff_drive(extra=''):
    return DIFF_DRIVE.format(extra=extra)


def camera(sensor_type='camera', filename='libgazebo_ros_camera.so', sensor_extra='', camera_extra='',
           plugin_extra=''):
    return CAMERA.format(sensor_type=sensor_type, filename=filename, sensor_extra=sensor_extra,
                         camera_extra=camera_extra, plugin_extra=plugin_extra)


def laser(sensor_type='ray', filename='libgazebo_ros_laser.so', sensor_extra='', ray='',
          plugin_extra=''):
    return LASER.format(sensor_type=sensor_type, filename=filename, sensor_extra=sensor_extra, ray=ray,
                        plugin_extra=plugin_extra)


def subjects(spec):
    return ' | '.join(str(skipped) for skipped in spec.skipped)


# Links, joints, poses ------------------------------------------------------------

def test_links_joints_root_and_mass():
    spec = load_robot(robot())
    assert spec.name == 'test_bot'
    assert spec.root_link == 'robot_footprint'
    assert set(spec.links) == {'robot_footprint', 'chassis', 'left_wheel', 'right_wheel', 'camera', 'hokuyo'}
    assert spec.mass == pytest.approx(25.0)
    hinge = spec.joints['left_wheel_hinge']
    assert (hinge.kind, hinge.parent, hinge.child) == ('continuous', 'chassis', 'left_wheel')
    assert hinge.axis == (0.0, 1.0, 0.0)
    assert spec.links['chassis'].collisions == [('box', Pose(), (0.4, 0.2, 0.1))]
    assert spec.drive is None and spec.cameras == [] and spec.lasers == []


def test_spawn_name_overrides_urdf_name():
    assert load_robot(robot(), name='my_robot').name == 'my_robot'


def test_link_pose_composes_joint_origins_from_the_root():
    body = """
      <link name="base"/>
      <link name="arm"/>
      <link name="tip"/>
      <joint name="a" type="fixed"><parent link="base"/><child link="arm"/>
        <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint>
      <joint name="b" type="continuous"><parent link="arm"/><child link="tip"/>
        <origin xyz="2 0 0.5"/></joint>
    """
    spec = load_robot(robot(body=body))
    pose = link_pose(spec, 'tip')
    assert (pose.x, pose.y, pose.z) == pytest.approx((1.0, 2.0, 0.5))
    assert pose.yaw == pytest.approx(math.pi / 2)
    assert link_pose(spec, 'base') == Pose()
    with pytest.raises(FlatsimError, match='no link'):
        link_pose(spec, 'nowhere')


def test_errors_name_the_part_after_the_first_of_a_link():
    body = """
      <link name="base">
        <collision name="body"><geometry><box size="1 1 1"/></geometry></collision>
        <collision name="bumper"><geometry/></collision>
      </link>
    """
    with pytest.raises(FlatsimError, match='link base collision bumper'):
        load_robot(robot(body=body))


# Footprint -------------------------------------------------------------------------

def test_footprint_is_the_hull_of_chassis_and_wheels():
    spec = load_robot(robot())
    # Chassis 0.4 x 0.2; wheels r=0.1 (x from -0.1 to 0.1), 0.05 wide, centred at y=+-0.15.
    expected = {(0.2, 0.1), (-0.2, 0.1), (-0.2, -0.1), (0.2, -0.1),
                (0.1, 0.175), (-0.1, 0.175), (-0.1, -0.175), (0.1, -0.175)}
    assert len(spec.footprint) == len(expected)
    for point in spec.footprint:
        assert min(math.dist(point, corner) for corner in expected) < 1e-9
    area = 0.5 * sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1)
                     in zip(spec.footprint, spec.footprint[1:] + spec.footprint[:1]))
    assert area == pytest.approx(0.4 * 0.2 + 2 * 0.2 * 0.075 + 4 * 0.5 * 0.1 * 0.075)


def test_footprint_follows_rotated_joints_and_spheres():
    body = """
      <link name="base"/>
      <link name="plate"><collision><origin xyz="0.5 0 0"/>
        <geometry><box size="0.2 0.1 0.1"/></geometry></collision></link>
      <joint name="turned" type="fixed"><parent link="base"/><child link="plate"/>
        <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/></joint>
      <link name="ball"><collision><geometry><sphere radius="0.25"/></geometry></collision></link>
      <joint name="b" type="fixed"><parent link="base"/><child link="ball"/></joint>
    """
    spec = load_robot(robot(body=body))
    xs = [x for x, _ in spec.footprint]
    ys = [y for _, y in spec.footprint]
    # The plate's centre lands at (1, 0.5) and, turned by 90 degrees, spans x 0.95..1.05, y 0.4..0.6.
    assert max(xs) == pytest.approx(1.05)
    assert max(ys) == pytest.approx(0.6)
    assert min(xs) == pytest.approx(-0.25)
    assert min(ys) == pytest.approx(-0.25)


def test_mesh_collision_is_skipped_and_counts_as_its_origin():
    body = """
      <link name="base"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
        <visual><geometry><mesh filename="package://x/body.stl"/></geometry></visual></link>
      <link name="far"><collision><origin xyz="0.1 0 0"/>
        <geometry><mesh filename="package://x/wheel.stl"/></geometry></collision></link>
      <joint name="j" type="continuous"><parent link="base"/><child link="far"/><origin xyz="0.9 0 0"/></joint>
    """
    spec = load_robot(robot(body=body))
    assert spec.links['far'].collisions == []
    assert max(x for x, _ in spec.footprint) == pytest.approx(1.0)
    assert 'wheel.stl' in subjects(spec) and 'body.stl' in subjects(spec)


def test_robot_without_collisions_gets_a_small_square():
    spec = load_robot(robot(body='<link name="only"/>'))
    corners = [(-0.05, -0.05), (-0.05, 0.05), (0.05, -0.05), (0.05, 0.05)]
    assert len(spec.footprint) == 4
    for point, corner in zip(sorted(spec.footprint), corners):
        assert point == pytest.approx(corner)
    assert 'no collision geometry' in subjects(spec)


# Diff drive -------------------------------------------------------------------------

def test_diff_drive_reads_course_tags_with_whitespace_and_numeric_booleans():
    extra = """
      <legacyMode>false</legacyMode>
      <updateRate>
         10 </updateRate>
      <wheelSeparation> 0.4 </wheelSeparation>
      <wheelDiameter>0.2</wheelDiameter>
      <wheelAcceleration>1.5</wheelAcceleration>
      <torque>10</torque>
      <wheelTorque>7</wheelTorque>
      <commandTopic>cmd_vel</commandTopic>
      <odometryTopic>odom</odometryTopic>
      <odometryFrame>odom</odometryFrame>
      <robotBaseFrame>robot_footprint</robotBaseFrame>
      <odometrySource>encoder</odometrySource>
      <publishWheelTF>true</publishWheelTF>
      <publishWheelJointState>TRUE</publishWheelJointState>
      <publishTf>1</publishTf>
      <publishOdomTF>false</publishOdomTF>
    """
    drive = load_robot(robot(diff_drive(extra))).drive
    assert drive.plugin == 'diff_drive'
    assert drive.left_joints == ['left_wheel_hinge'] and drive.right_joints == ['right_wheel_hinge']
    assert (drive.wheel_separation, drive.wheel_diameter) == (0.4, 0.2)
    assert (drive.wheel_acceleration, drive.wheel_torque, drive.update_rate) == (1.5, 7.0, 10.0)
    assert (drive.command_topic, drive.odometry_topic) == ('cmd_vel', 'odom')
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom', 'robot_footprint')
    assert drive.odometry_source == 'encoder'
    assert drive.publish_odometry is True
    assert drive.publish_tf is False
    assert drive.publish_wheel_tf is True and drive.publish_wheel_joint_state is True


def test_diff_drive_defaults_are_gazebo_ros_defaults():
    drive = load_robot(robot(diff_drive())).drive
    assert (drive.wheel_separation, drive.wheel_diameter) == (0.34, 0.15)
    assert (drive.wheel_acceleration, drive.wheel_torque, drive.update_rate) == (0.0, 5.0, 100.0)
    assert drive.robot_base_frame == 'base_footprint'
    assert drive.odometry_source == 'world'
    assert drive.publish_odometry and drive.publish_tf
    assert not drive.publish_wheel_tf and not drive.publish_wheel_joint_state


def test_publish_tf_false_turns_off_odometry_and_tf():
    drive = load_robot(robot(diff_drive('<publishTf>0</publishTf>'))).drive
    assert drive.publish_odometry is False and drive.publish_tf is False


def test_gazebo_ros_boolean_tags_ignore_1_and_0_like_gazebo_ros():
    spec = load_robot(robot(diff_drive('<publishWheelTF>1</publishWheelTF>')))
    assert spec.drive.publish_wheel_tf is False
    assert 'publishWheelTF' in subjects(spec)


def test_bad_odometry_source_falls_back_to_world():
    spec = load_robot(robot(diff_drive('<odometrySource>gps</odometrySource>')))
    assert spec.drive.odometry_source == 'world'
    assert 'odometrySource' in subjects(spec)


def test_drive_naming_missing_joints_leaves_the_robot_static():
    plugin = DIFF_DRIVE.replace('left_wheel_hinge', 'front_left_hinge').format(extra='')
    spec = load_robot(robot(plugin))
    assert spec.drive is None
    assert 'there is no joint front_left_hinge' in subjects(spec)


def test_drive_on_fixed_joint_is_skipped():
    plugin = DIFF_DRIVE.replace('left_wheel_hinge', 'camera_joint').format(extra='')
    spec = load_robot(robot(plugin))
    assert spec.drive is None
    assert 'camera_joint is fixed' in subjects(spec)


# Skid steer -------------------------------------------------------------------------

SKID_BODY = BODY.replace('left_wheel_hinge', 'front_left_hinge').replace(
    'right_wheel_hinge', 'front_right_hinge') + """
  <link name="rear_left_wheel"/>
  <joint name="rear_left_hinge" type="continuous"><parent link="chassis"/><child link="rear_left_wheel"/>
    <origin xyz="-0.1 0.15 0"/></joint>
  <link name="rear_right_wheel"/>
  <joint name="rear_right_hinge" type="continuous"><parent link="chassis"/><child link="rear_right_wheel"/>
    <origin xyz="-0.1 -0.15 0"/></joint>
"""


def skid_steer(extra=''):
    return """
  <gazebo>
    <plugin name="skid" filename="libgazebo_ros_skid_steer_drive.so">
      <leftFrontJoint>front_left_hinge</leftFrontJoint>
      <rightFrontJoint>front_right_hinge</rightFrontJoint>
      <leftRearJoint>rear_left_hinge</leftRearJoint>
      <rightRearJoint>rear_right_hinge</rightRearJoint>
      %s
    </plugin>
  </gazebo>""" % extra


def test_skid_steer_reads_four_joints_and_its_own_tags():
    extra = """<wheelSeparation>5</wheelSeparation><wheelDiameter>0.2</wheelDiameter>
      <torque>20</torque><wheelTorque>99</wheelTorque><broadcastTF>1</broadcastTF>
      <covariance_x>0.001</covariance_x><covariance_y>0.002</covariance_y><covariance_yaw>0.03</covariance_yaw>
      <updateRate>50</updateRate><robotBaseFrame>robot_footprint</robotBaseFrame>"""
    drive = load_robot(robot(skid_steer(extra), body=SKID_BODY)).drive
    assert drive.plugin == 'skid_steer'
    assert drive.left_joints == ['front_left_hinge', 'rear_left_hinge']
    assert drive.right_joints == ['front_right_hinge', 'rear_right_hinge']
    assert (drive.wheel_separation, drive.wheel_diameter, drive.wheel_torque) == (5.0, 0.2, 20.0)
    assert drive.publish_tf is True
    assert drive.covariance == (0.001, 0.002, 0.03)
    assert drive.update_rate == 50.0
    assert drive.robot_base_frame == 'robot_footprint'


def test_skid_steer_defaults():
    drive = load_robot(robot(skid_steer(), body=SKID_BODY)).drive
    assert (drive.wheel_separation, drive.wheel_diameter, drive.wheel_torque) == (0.4, 0.15, 5.0)
    assert drive.publish_tf is False
    assert drive.covariance == (0.0001, 0.0001, 0.01)
    assert (drive.command_topic, drive.odometry_topic, drive.update_rate) == ('cmd_vel', 'odom', 100.0)


# Camera -----------------------------------------------------------------------------

COURSE_CAMERA = dict(
    sensor_extra='<pose>0.01 0 0.02 0 0 0</pose><update_rate>30.0</update_rate>',
    camera_extra="""<horizontal_fov>1.3962634</horizontal_fov>
        <image><width>800</width><height>600</height><format>B8G8R8</format></image>
        <clip><near>0.02</near><far>300</far></clip>""",
    plugin_extra="""<updateRate>10.0</updateRate><cameraName>camera</cameraName>
        <imageTopicName>rgb/image_raw</imageTopicName><cameraInfoTopicName>rgb/camera_info</cameraInfoTopicName>
        <frameName>camera</frameName><hackBaseline>0.07</hackBaseline><distortionK1>0.1</distortionK1>
        <distortionT2>0.2</distortionT2>""")


def test_camera_reads_sensor_and_plugin():
    spec = load_robot(robot(camera(**COURSE_CAMERA)))
    (cam,) = spec.cameras
    assert (cam.sensor_name, cam.link, cam.plugin) == ('camera1', 'camera', 'camera')
    assert cam.pose == Pose(0.01, 0.0, 0.02, 0.0, 0.0, 0.0)
    assert (cam.update_rate, cam.plugin_update_rate) == (30.0, 10.0)
    assert (cam.width, cam.height, cam.hfov, cam.image_format) == (800, 600, 1.3962634, 'B8G8R8')
    assert (cam.near, cam.far) == (0.02, 300.0)
    assert (cam.image_topic, cam.info_topic) == ('camera/rgb/image_raw', 'camera/rgb/camera_info')
    assert cam.frame_name == 'camera'
    assert cam.hack_baseline == 0.07
    assert cam.distortion == (0.1, 0.0, 0.0, 0.2, 0.0)


def test_camera_defaults():
    (cam,) = load_robot(robot(camera())).cameras
    assert (cam.width, cam.height, cam.hfov, cam.image_format) == (320, 240, 1.047, 'R8G8B8')
    assert (cam.near, cam.far, cam.update_rate) == (0.1, 100.0, 0.0)
    assert (cam.image_topic, cam.info_topic, cam.frame_name) == ('image_raw', 'camera_info', '')


def test_openni_kinect_depth_sensor_is_an_rgb_camera():
    spec = load_robot(robot(camera(
        sensor_type='depth', filename='libgazebo_ros_openni_kinect.so',
        sensor_extra='<update_rate>20.0</update_rate>',
        camera_extra='<horizontal_fov>1.047</horizontal_fov><image><width>640</width><height>480</height></image>',
        plugin_extra='<cameraName>camera</cameraName><imageTopicName>rgb/image_raw</imageTopicName>'
                     '<depthImageTopicName>depth/image_raw</depthImageTopicName>'
                     '<frameName>camera_link_optical</frameName>')))
    (cam,) = spec.cameras
    assert cam.plugin == 'openni_kinect'
    assert (cam.width, cam.height, cam.hfov, cam.update_rate) == (640, 480, 1.047, 20.0)
    assert cam.image_topic == 'camera/rgb/image_raw'
    # GazeboRosCameraUtils::Load runs after the plugin's ir/ defaults and resets them.
    assert cam.info_topic == 'camera/camera_info'
    assert cam.frame_name == 'camera_link_optical'


def test_camera_with_a_laser_plugin_is_skipped():
    spec = load_robot(robot(camera(filename='libgazebo_ros_laser.so')))
    assert spec.cameras == [] and spec.lasers == []
    assert 'camera1' in subjects(spec)


def test_sensor_without_ros_plugin_is_skipped():
    spec = load_robot(robot(camera(filename='libCameraPlugin.so')))
    assert spec.cameras == []
    assert 'libCameraPlugin.so' in subjects(spec)


# Laser ------------------------------------------------------------------------------

COURSE_RAY = """<scan><horizontal><samples>720</samples><resolution>1</resolution>
    <min_angle>-1.570796</min_angle><max_angle>1.570796</max_angle></horizontal></scan>
    <range><min>0.10</min><max>30.0</max><resolution>0.01</resolution></range>
    <noise><type>gaussian</type><mean>0.0</mean><stddev>0.01</stddev></noise>"""


def test_laser_reads_scan_range_noise_and_names():
    spec = load_robot(robot(laser(sensor_extra='<pose>0 0 0.05 0 0 0</pose><update_rate>40</update_rate>',
                                  ray=COURSE_RAY,
                                  plugin_extra='<topicName>/scan</topicName><frameName>hokuyo</frameName>')))
    (scan,) = spec.lasers
    assert (scan.sensor_name, scan.link) == ('head_hokuyo_sensor', 'hokuyo')
    assert scan.pose == Pose(0, 0, 0.05, 0, 0, 0)
    assert (scan.update_rate, scan.samples) == (40.0, 720)
    assert (scan.min_angle, scan.max_angle) == (-1.570796, 1.570796)
    assert (scan.range_min, scan.range_max, scan.range_resolution) == (0.1, 30.0, 0.01)
    assert (scan.noise_mean, scan.noise_stddev) == (0.0, 0.01)
    assert (scan.topic, scan.frame_name) == ('/scan', 'hokuyo')


def test_relative_laser_topic_stays_relative():
    (scan,) = load_robot(robot(laser(ray=COURSE_RAY, plugin_extra='<topicName>scan</topicName>'))).lasers
    assert scan.topic == 'scan'


def test_gpu_laser_on_gpu_ray_sensor():
    (scan,) = load_robot(robot(laser(sensor_type='gpu_ray', filename='libgazebo_ros_gpu_laser.so',
                                     ray=COURSE_RAY, plugin_extra='<topicName>/scan</topicName>'))).lasers
    assert (scan.topic, scan.samples) == ('/scan', 720)


def test_laser_defaults_and_resolution_multiplies_samples():
    ray = '<scan><horizontal><samples>100</samples><resolution>2</resolution></horizontal></scan>'
    (scan,) = load_robot(robot(laser(ray=ray))).lasers
    assert scan.samples == 200
    assert (scan.min_angle, scan.max_angle, scan.range_min, scan.range_max) == (0.0, 0.0, 0.0, 0.0)
    assert (scan.noise_stddev, scan.topic, scan.frame_name) == (0.0, '/world', 'world')


# Namespacing ------------------------------------------------------------------------

def test_robot_namespace_prefixes_topics_and_frames_like_gazebo_ros():
    ns = '<robotNamespace>robot1</robotNamespace>'
    spec = load_robot(robot(
        diff_drive(ns + '<robotBaseFrame>robot_footprint</robotBaseFrame>'),
        camera(plugin_extra=ns + '<cameraName>camera</cameraName><imageTopicName>rgb/image_raw</imageTopicName>'
                                 '<frameName>camera</frameName>'),
        laser(ray=COURSE_RAY, plugin_extra=ns + '<topicName>/scan</topicName><frameName>hokuyo</frameName>')))
    drive, (cam,), (scan,) = spec.drive, spec.cameras, spec.lasers
    assert (drive.command_topic, drive.odometry_topic) == ('robot1/cmd_vel', 'robot1/odom')
    assert (drive.odometry_frame, drive.robot_base_frame) == ('robot1/odom', 'robot1/robot_footprint')
    assert drive.tf_prefix == 'robot1'
    assert (cam.image_topic, cam.info_topic) == ('robot1/camera/rgb/image_raw', 'robot1/camera/camera_info')
    assert cam.frame_name == 'robot1/camera'
    assert (scan.topic, scan.frame_name) == ('/scan', 'robot1/hokuyo')


def test_root_namespace_makes_names_absolute_and_global_frames_drop_the_slash():
    spec = load_robot(robot(
        diff_drive('<robotNamespace>/</robotNamespace><odometryFrame>/odom</odometryFrame>'),
        laser(ray=COURSE_RAY, plugin_extra='<robotNamespace>/</robotNamespace><topicName>scan</topicName>'
                                           '<frameName>/hokuyo</frameName>')))
    assert (spec.drive.command_topic, spec.drive.odometry_frame) == ('/cmd_vel', 'odom')
    assert (spec.lasers[0].topic, spec.lasers[0].frame_name) == ('/scan', 'hokuyo')


def test_empty_robot_namespace_means_the_model_name():
    spec = load_robot(robot(diff_drive('<robotNamespace></robotNamespace>')), name='rover')
    assert spec.drive.command_topic == 'rover/cmd_vel'


def test_spawn_namespace_applies_to_plugins_without_their_own():
    spec = load_robot(robot(diff_drive(), laser(ray=COURSE_RAY, plugin_extra='<topicName>scan</topicName>')),
                      robot_namespace='/team')
    assert spec.drive.command_topic == '/team/cmd_vel'
    assert spec.lasers[0].topic == '/team/scan'
    assert spec.drive.odometry_frame == 'team/odom'


def test_skid_steer_namespaces_topics_but_not_frames():
    drive = load_robot(robot(skid_steer('<robotNamespace>robot2</robotNamespace>'), body=SKID_BODY)).drive
    assert (drive.command_topic, drive.odometry_topic) == ('robot2/cmd_vel', 'robot2/odom')
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom', 'base_footprint')


def test_name_helpers():
    assert ros_resolve('', 'scan') == 'scan'
    assert ros_resolve('ns/', 'cmd_vel') == 'ns/cmd_vel'
    assert ros_resolve('//', 'cmd_vel') == '/cmd_vel'
    assert ros_resolve('ns', '/scan') == '/scan'
    assert tf_resolve('', '/world') == 'world'
    assert tf_resolve('/robot', 'base') == 'robot/base'


# Skips and errors -------------------------------------------------------------------

def test_unknown_plugins_are_named_and_ignored():
    spec = load_robot(robot("""
      <gazebo><plugin name="ackermansteer" filename="libackermansteer.so"><wheelbase>0.3</wheelbase></plugin></gazebo>
      <gazebo><plugin name="p3d" filename="libgazebo_ros_p3d.so"/></gazebo>
      <gazebo><plugin name="gazebo_ros_control" filename="libgazebo_ros_control.so"/></gazebo>"""))
    assert spec.drive is None
    assert 'libackermansteer.so' in subjects(spec) and 'libgazebo_ros_p3d.so' in subjects(spec)
    # ros_control is simulated: without transmissions it has no joints, and namespaces by model name.
    assert spec.ros_control.transmissions == [] and spec.ros_control.robot_namespace == spec.name


def test_second_drive_plugin_is_skipped():
    spec = load_robot(robot(diff_drive('<wheelSeparation>0.5</wheelSeparation>'), diff_drive()))
    assert spec.drive.wheel_separation == 0.5
    assert 'already has a drive plugin' in subjects(spec)


def test_gazebo_reference_to_no_link_is_skipped():
    spec = load_robot(robot('<gazebo reference="wheel_mount"><material>Gazebo/Black</material></gazebo>',
                            '<gazebo reference="left_wheel_hinge"><provideFeedback>true</provideFeedback></gazebo>'))
    assert 'wheel_mount' in subjects(spec)
    assert 'left_wheel_hinge' not in subjects(spec)


def test_sensor_on_missing_link_is_skipped():
    spec = load_robot(robot(camera().replace('reference="camera"', 'reference="camera_link"')))
    assert spec.cameras == []
    assert 'camera_link' in subjects(spec)


def test_joint_naming_missing_link_is_an_error_with_its_line():
    text = robot(body='<link name="a"/>\n<joint name="j" type="fixed">\n'
                      '<parent link="a"/><child link="ghost"/></joint>')
    with pytest.raises(ModelFileError, match=r"robot.urdf:\d+: joint j names child link 'ghost'") as err:
        load_robot(text, source='robot.urdf')
    assert err.value.line == 3


def test_malformed_xml_reports_the_line():
    with pytest.raises(ModelFileError, match='malformed XML') as err:
        load_robot('<robot name="x">\n<link name="a">\n</robot>')
    assert err.value.line == 3


def test_non_numbers_name_the_tag():
    with pytest.raises(ModelFileError, match='wheelSeparation.*wide'):
        load_robot(robot(diff_drive('<wheelSeparation>wide</wheelSeparation>')))
    with pytest.raises(ModelFileError, match='box size'):
        load_robot(robot(body='<link name="a"><collision><geometry><box size="1 x 1"/></geometry></collision></link>'))
    with pytest.raises(ModelFileError, match='image/width'):
        load_robot(robot(camera(camera_extra='<image><width>800.5</width></image>')))


def test_tree_errors():
    with pytest.raises(ModelFileError, match='one root'):
        load_robot(robot(body='<link name="a"/><link name="b"/>'))
    with pytest.raises(ModelFileError, match='child of two joints'):
        load_robot(robot(body='<link name="a"/><link name="b"/><link name="c"/>'
                              '<joint name="x" type="fixed"><parent link="a"/><child link="c"/></joint>'
                              '<joint name="y" type="fixed"><parent link="b"/><child link="c"/></joint>'))
    with pytest.raises(ModelFileError, match='expected a <robot>'):
        load_robot('<sdf version="1.6"/>')


# Xacro ------------------------------------------------------------------------------

@pytest.fixture
def fixture_package(tmp_path, monkeypatch):
    package = tmp_path / 'fixture_bot'
    shutil.copytree(FIXTURES / 'fixture_bot', package)
    (package / 'package.xml').write_text(
        '<package format="2"><name>fixture_bot</name><version>0.0.0</version>'
        '<description>test robot</description><maintainer email="a@example.com">a</maintainer>'
        '<license>BSD</license></package>')
    monkeypatch.setenv('ROS_PACKAGE_PATH', str(tmp_path))
    return package


def test_expand_xacro_resolves_find_properties_macros_and_args(fixture_package):
    path = fixture_package / 'urdf' / 'fixture_bot.urdf.xacro'
    spec = load_robot(expand_xacro(path, {'image_topic': 'front/image'}), source=str(path))
    assert spec.drive.wheel_separation == pytest.approx(0.25)
    assert spec.drive.wheel_diameter == pytest.approx(0.2)
    assert spec.drive.left_joints == ['left_wheel_hinge']
    (cam,) = spec.cameras
    assert cam.image_topic == 'camera/front/image'
    assert cam.hfov == pytest.approx(math.radians(80))
    assert link_pose(spec, 'left_wheel').y == pytest.approx(0.125)
    assert spec.mass == pytest.approx(12.0)
    default = load_robot(expand_xacro(path))
    assert default.cameras[0].image_topic == 'camera/rgb/image_raw'


def test_expand_xacro_errors_are_model_file_errors(fixture_package, tmp_path):
    broken = tmp_path / 'broken.xacro'
    broken.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro"><link name="${undefined_value}"/></robot>')
    with pytest.raises(ModelFileError, match='xacro failed'):
        expand_xacro(broken)
    missing = tmp_path / 'needs_missing_package.xacro'
    missing.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro">'
                       '<xacro:include filename="$(find no_such_package)/x.xacro"/></robot>')
    with pytest.raises(ModelFileError, match='no_such_package'):
        expand_xacro(missing)
