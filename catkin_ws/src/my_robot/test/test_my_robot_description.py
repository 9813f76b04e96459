"""The robot description: both drive layouts expand, pass check_urdf, stand on
the ground, and carry plugin parameters that agree with their own geometry."""
import math
import pathlib
import shutil
import subprocess

import pytest

PACKAGE_DIR = pathlib.Path(__file__).resolve().parent.parent
DRIVES = ('diff', 'skid')
WHEEL_JOINTS = {
    'diff': {'leftJoint': 'left_wheel_hinge', 'rightJoint': 'right_wheel_hinge'},
    'skid': {'leftFrontJoint': 'left_front_wheel_hinge', 'rightFrontJoint': 'right_front_wheel_hinge',
             'leftRearJoint': 'left_rear_wheel_hinge', 'rightRearJoint': 'right_rear_wheel_hinge'},
}
DRIVE_PLUGIN = {'diff': 'libgazebo_ros_diff_drive.so', 'skid': 'libgazebo_ros_skid_steer_drive.so'}


def numbers(text):
    return [float(v) for v in text.split()]


def by_name(root, tag):
    return {e.get('name'): e for e in root.findall(tag)}


def origin(element):
    found = element.find('origin')
    if found is None:
        return [0.0] * 3, [0.0] * 3
    return numbers(found.get('xyz', '0 0 0')), numbers(found.get('rpy', '0 0 0'))


def drive_plugin(root, drive):
    plugins = [p for g in root.findall('gazebo') if g.get('reference') is None
               for p in g.findall('plugin') if p.get('filename') == DRIVE_PLUGIN[drive]]
    assert len(plugins) == 1
    return {child.tag: child.text.strip() for child in plugins[0]}


def sensor(root, link):
    sensors = [s for g in root.findall('gazebo') if g.get('reference') == link for s in g.findall('sensor')]
    assert len(sensors) == 1
    return sensors[0]


def wheel_cylinder(root, joint_name):
    link = by_name(root, 'link')[by_name(root, 'joint')[joint_name].find('child').get('link')]
    shapes = [(c.find('geometry/cylinder'), origin(c)[1]) for c in link.findall('collision') + link.findall('visual')]
    assert shapes and all(cyl is not None for cyl, _ in shapes)
    radii = {float(cyl.get('radius')) for cyl, _ in shapes}
    assert len(radii) == 1, 'collision and visual radii differ'
    # The cylinder's own axis is z; rolled a quarter turn it lies along the joint's y axis.
    assert all(rpy == pytest.approx([math.pi / 2, 0, 0]) for _, rpy in shapes)
    return radii.pop()


def footprint_height(root):
    joint = by_name(root, 'joint')['robot_footprint_joint']
    assert joint.get('type') == 'fixed'
    assert (joint.find('parent').get('link'), joint.find('child').get('link')) == ('robot_footprint', 'chassis')
    return origin(joint)[0][2]


@pytest.mark.parametrize('drive', DRIVES)
def test_description_passes_check_urdf(drive, expanded_urdf, tmp_path):
    if shutil.which('check_urdf') is None:
        pytest.fail('check_urdf (Debian package liburdfdom-tools) is not installed')
    urdf = tmp_path / ('my_robot_%s.urdf' % drive)
    urdf.write_text(expanded_urdf(drive))
    result = subprocess.run(['check_urdf', str(urdf)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, check=False)
    assert result.returncode == 0, result.stdout
    assert 'root Link: robot_footprint has 1 child(ren)' in result.stdout


def test_unknown_drive_is_refused_by_name(run_xacro):
    result = run_xacro('drive:=tank')
    assert result.returncode != 0
    assert 'drive_arg_must_be_diff_or_skid' in result.stderr


@pytest.mark.parametrize('drive', DRIVES)
def test_course_links_and_joints_exist(drive, urdf_root):
    root = urdf_root(drive)
    joints = by_name(root, 'joint')
    wheel_joints = set(WHEEL_JOINTS[drive].values())
    assert {n for n, j in joints.items() if j.get('type') == 'continuous'} == wheel_joints
    for name in ('camera_joint', 'hokuyo_joint'):
        assert joints[name].get('type') == 'fixed'
        assert joints[name].find('parent').get('link') == 'chassis'
    assert joints['camera_joint'].find('child').get('link') == 'camera'
    assert joints['hokuyo_joint'].find('child').get('link') == 'hokuyo'
    for name in wheel_joints:
        assert numbers(joints[name].find('axis').get('xyz')) == [0, 1, 0]
    chassis = by_name(root, 'link')['chassis']
    assert chassis.find('collision/geometry/box') is not None


def test_diff_robot_has_two_wheels_named_as_in_the_course(urdf_root):
    links = set(by_name(urdf_root('diff'), 'link'))
    assert links == {'robot_footprint', 'chassis', 'left_wheel', 'right_wheel', 'camera', 'hokuyo'}


@pytest.mark.parametrize('drive', DRIVES)
def test_wheel_parameters_match_the_wheels(drive, urdf_root):
    root = urdf_root(drive)
    params = drive_plugin(root, drive)
    joints = by_name(root, 'joint')
    assert {k: params[k] for k in WHEEL_JOINTS[drive]} == WHEEL_JOINTS[drive]
    radii = {wheel_cylinder(root, params[k]) for k in WHEEL_JOINTS[drive]}
    assert len(radii) == 1
    assert float(params['wheelDiameter']) == pytest.approx(2 * radii.pop(), abs=1e-12)
    ys = {k: origin(joints[params[k]])[0][1] for k in WHEEL_JOINTS[drive]}
    left = [y for k, y in ys.items() if k.startswith('left')]
    right = [y for k, y in ys.items() if k.startswith('right')]
    for y_left, y_right in zip(left, right):
        assert y_left > 0 > y_right
        assert float(params['wheelSeparation']) == pytest.approx(y_left - y_right, abs=1e-12)


@pytest.mark.parametrize('drive', DRIVES)
def test_wheels_and_casters_touch_the_ground(drive, urdf_root):
    root = urdf_root(drive)
    chassis_z = footprint_height(root)
    joints = by_name(root, 'joint')
    for joint_name in WHEEL_JOINTS[drive].values():
        axle_z = chassis_z + origin(joints[joint_name])[0][2]
        assert axle_z - wheel_cylinder(root, joint_name) == pytest.approx(0, abs=1e-12)
    casters = [c for c in by_name(root, 'link')['chassis'].findall('collision')
               if c.find('geometry/sphere') is not None]
    assert len(casters) == (2 if drive == 'diff' else 0)
    for caster in casters:
        radius = float(caster.find('geometry/sphere').get('radius'))
        assert chassis_z + origin(caster)[0][2] - radius == pytest.approx(0, abs=1e-12)


def test_diff_drive_plugin_settings(urdf_root):
    params = drive_plugin(urdf_root('diff'), 'diff')
    expected = {
        'commandTopic': 'cmd_vel', 'odometryTopic': 'odom', 'odometryFrame': 'odom',
        'robotBaseFrame': 'robot_footprint', 'odometrySource': 'world', 'publishTf': 'true',
        'publishOdomTF': 'true', 'publishWheelTF': 'false', 'publishWheelJointState': 'true',
    }
    assert {k: params.get(k) for k in expected} == expected
    assert float(params['updateRate']) == 50
    assert float(params['wheelTorque']) > 0
    assert float(params['wheelAcceleration']) > 0


def test_skid_steer_plugin_settings(urdf_root):
    params = drive_plugin(urdf_root('skid'), 'skid')
    expected = {
        'commandTopic': 'cmd_vel', 'odometryTopic': 'odom', 'odometryFrame': 'odom',
        'robotBaseFrame': 'robot_footprint', 'broadcastTF': 'true',
    }
    assert {k: params.get(k) for k in expected} == expected
    assert float(params['torque']) > 0


@pytest.mark.parametrize('drive', DRIVES)
def test_camera_publishes_the_course_topics(drive, urdf_root):
    cam = sensor(urdf_root(drive), 'camera')
    assert cam.get('type') == 'camera'
    assert float(cam.findtext('update_rate')) == 30
    assert cam.find('camera').get('name') == 'head'
    assert float(cam.findtext('camera/horizontal_fov')) == pytest.approx(1.3962634)
    assert (cam.findtext('camera/image/width'), cam.findtext('camera/image/height'),
            cam.findtext('camera/image/format')) == ('800', '800', 'R8G8B8')
    assert (float(cam.findtext('camera/clip/near')), float(cam.findtext('camera/clip/far'))) == (0.02, 300)
    plugin = cam.find('plugin')
    assert plugin.get('filename') == 'libgazebo_ros_camera.so'
    topic = '/%s/%s' % (plugin.findtext('cameraName'), plugin.findtext('imageTopicName'))
    info = '/%s/%s' % (plugin.findtext('cameraName'), plugin.findtext('cameraInfoTopicName'))
    assert (topic, info) == ('/camera/rgb/image_raw', '/camera/rgb/camera_info')
    assert plugin.findtext('frameName') == 'camera'


@pytest.mark.parametrize('drive', DRIVES)
def test_laser_matches_the_hokuyo_settings(drive, urdf_root):
    laser = sensor(urdf_root(drive), 'hokuyo')
    assert laser.get('type') == 'ray'
    assert float(laser.findtext('update_rate')) == 40
    horizontal = laser.find('ray/scan/horizontal')
    assert int(horizontal.findtext('samples')) == 720
    assert float(horizontal.findtext('min_angle')) == pytest.approx(-math.pi / 2, abs=1e-12)
    assert float(horizontal.findtext('max_angle')) == pytest.approx(math.pi / 2, abs=1e-12)
    assert [float(laser.findtext('ray/range/' + k)) for k in ('min', 'max', 'resolution')] == [0.10, 30.0, 0.01]
    noise = laser.find('ray/noise')
    assert (noise.findtext('type'), float(noise.findtext('mean')), float(noise.findtext('stddev'))) == \
        ('gaussian', 0.0, 0.01)
    plugin = laser.find('plugin')
    assert plugin.get('filename') == 'libgazebo_ros_laser.so'
    assert (plugin.findtext('topicName'), plugin.findtext('frameName')) == ('/scan', 'hokuyo')


@pytest.mark.parametrize('drive', DRIVES)
def test_sensors_sit_on_the_front_and_top_of_the_chassis(drive, urdf_root):
    root = urdf_root(drive)
    links, joints = by_name(root, 'link'), by_name(root, 'joint')
    length, _, height = numbers(links['chassis'].find('collision/geometry/box').get('size'))
    camera_size = numbers(links['camera'].find('collision/geometry/box').get('size'))[0]
    assert origin(joints['camera_joint'])[0][0] == pytest.approx(length / 2 + camera_size / 2)
    laser_height = numbers(links['hokuyo'].find('collision/geometry/box').get('size'))[2]
    assert origin(joints['hokuyo_joint'])[0][2] == pytest.approx(height / 2 + laser_height / 2)
    mesh = links['hokuyo'].find('visual/geometry/mesh').get('filename')
    assert mesh == 'package://my_robot/meshes/hokuyo.dae'
    assert (PACKAGE_DIR / 'meshes' / 'hokuyo.dae').is_file()


@pytest.mark.parametrize('drive', DRIVES)
def test_inertia_follows_from_the_shapes(drive, urdf_root):
    links = by_name(urdf_root(drive), 'link')
    for name, link in links.items():
        if name == 'robot_footprint':
            continue
        mass = float(link.find('inertial/mass').get('value'))
        inertia = link.find('inertial/inertia')
        ixx, iyy, izz = (float(inertia.get(k)) for k in ('ixx', 'iyy', 'izz'))
        shape = link.find('collision/geometry')[0]
        if shape.tag == 'box':
            x, y, z = numbers(shape.get('size'))
            expected = [mass * (y * y + z * z) / 12, mass * (x * x + z * z) / 12, mass * (x * x + y * y) / 12]
        else:
            r, h = float(shape.get('radius')), float(shape.get('length'))
            side = mass * (3 * r * r + h * h) / 12
            expected = [side, side, mass * r * r / 2]
        assert [ixx, iyy, izz] == pytest.approx(expected, rel=1e-12), name
