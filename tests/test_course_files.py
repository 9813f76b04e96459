"""`rosrun chase_tools course_files DEST`: the files the course downloads, offline.

The course's robot (tests/fixtures/course_my_robot, typed from the lessons'
specifications) with those files in the places the course gives runs in
flatsim and publishes the course's topics."""
import os
import pathlib
import re
import shutil
import stat
import subprocess
import xml.etree.ElementTree as ET

import pytest

from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation
from rosproc import RosSystem, wait_until

ROOT = pathlib.Path(__file__).resolve().parent.parent
MY_ROBOT = ROOT / 'catkin_ws' / 'src' / 'my_robot'
COURSE_DIR = ROOT / 'catkin_ws' / 'src' / 'chase_tools' / 'course'
SCRIPT = ROOT / 'catkin_ws' / 'src' / 'chase_tools' / 'scripts' / 'course_files'
COURSE_ROBOT = ROOT / 'tests' / 'fixtures' / 'course_my_robot'
COURSE_MD = ROOT / 'docs' / 'course.md'
COURSE_TOPICS = ('/cmd_vel', '/odom', '/camera/rgb/image_raw', '/camera/rgb/camera_info', '/scan')


def course_files(*args, env=None):
    return subprocess.run([str(SCRIPT)] + [str(a) for a in args], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True, timeout=60, check=False, env=env)


def rosrun_env():
    # Each package once on the path, however other tests extended it, or rosrun asks which one.
    paths = dict.fromkeys(os.path.realpath(p) for p in os.environ['ROS_PACKAGE_PATH'].split(os.pathsep) if p)
    return dict(os.environ, ROS_PACKAGE_PATH=os.pathsep.join(paths))


def course_package(tmp_path):
    """The course's my_robot with the two files where the course says to put them."""
    package = tmp_path / 'src' / 'my_robot'
    shutil.copytree(COURSE_ROBOT, package)
    result = course_files(tmp_path / 'downloads')
    assert result.returncode == 0, result.stderr
    (package / 'meshes').mkdir()
    shutil.move(str(tmp_path / 'downloads' / 'hokuyo.dae'), str(package / 'meshes'))
    shutil.move(str(tmp_path / 'downloads' / 'my_robot.gazebo'), str(package / 'urdf'))
    return package


def test_the_command_the_course_doc_gives_writes_both_files_and_says_where_the_course_puts_them(tmp_path):
    commands = re.findall(r'^(rosrun chase_tools course_files \S+)', COURSE_MD.read_text(), re.MULTILINE)
    assert commands, 'docs/course.md gives no rosrun chase_tools course_files command'
    dest = tmp_path / 'course_files'
    argv = commands[0].split()[:-1] + [str(dest)]
    result = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            timeout=60, check=False, env=rosrun_env())
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in dest.iterdir()) == ['hokuyo.dae', 'my_robot.gazebo']
    assert (dest / 'hokuyo.dae').read_bytes() == (COURSE_DIR / 'hokuyo.dae').read_bytes()
    assert result.stdout.splitlines() == [
        'wrote %s  (the course downloads it to my_robot/meshes/hokuyo.dae)' % (dest / 'hokuyo.dae'),
        'wrote %s  (the course downloads it to my_robot/urdf/my_robot.gazebo)' % (dest / 'my_robot.gazebo')]


def test_the_gazebo_file_holds_the_courses_three_plugins_with_its_names():
    root = ET.parse(str(COURSE_DIR / 'my_robot.gazebo')).getroot()
    drive = root.find("gazebo/plugin[@filename='libgazebo_ros_diff_drive.so']")
    assert {child.tag: child.text for child in drive if child.tag in (
        'leftJoint', 'rightJoint', 'commandTopic', 'odometryTopic', 'robotBaseFrame')} == {
        'leftJoint': 'left_wheel_hinge', 'rightJoint': 'right_wheel_hinge', 'commandTopic': 'cmd_vel',
        'odometryTopic': 'odom', 'robotBaseFrame': 'robot_footprint'}
    camera = root.find("gazebo[@reference='camera']/sensor[@type='camera']")
    assert camera.get('name') == 'camera1'
    assert camera.find('plugin').get('filename') == 'libgazebo_ros_camera.so'
    assert camera.find('plugin/frameName').text == 'camera_link'
    laser = root.find("gazebo[@reference='hokuyo']/sensor[@type='ray']")
    assert laser.find('plugin').get('filename') == 'libgazebo_ros_laser.so'
    assert (laser.find('plugin/topicName').text, laser.find('plugin/frameName').text) == ('/scan', 'hokuyo')


def test_the_course_robot_with_the_files_loads_in_flatsim_with_the_courses_topics(tmp_path, monkeypatch):
    package = course_package(tmp_path)
    monkeypatch.setenv('ROS_PACKAGE_PATH', '%s:%s' % (package.parent, os.environ['ROS_PACKAGE_PATH']))
    spec = load_robot(expand_xacro(str(package / 'urdf' / 'my_robot.xacro')), name='my_robot')
    robot = Simulation(None).spawn_robot('my_robot', spec, Pose())
    drive = spec.drive
    assert (drive.command_topic, drive.odometry_topic, drive.robot_base_frame) == ('cmd_vel', 'odom', 'robot_footprint')
    assert (drive.left_joints, drive.right_joints) == (['left_wheel_hinge'], ['right_wheel_hinge'])
    assert (drive.wheel_separation, drive.wheel_diameter) == (0.4, 0.2)
    sensors = {slot.kind: slot.config for slot in robot.sensors}
    assert (sensors['camera'].sensor_name, sensors['camera'].image_topic, sensors['camera'].frame_name) == (
        'camera1', 'camera/rgb/image_raw', 'camera_link')
    assert (sensors['laser'].topic, sensors['laser'].frame_name) == ('/scan', 'hokuyo')
    assert not [item for item in spec.skipped if 'plugin' in str(item)], spec.skipped


def test_the_course_robot_with_the_files_publishes_the_courses_topics(tmp_path):
    package = course_package(tmp_path)
    env = dict(rosrun_env())
    env['ROS_PACKAGE_PATH'] = '%s:%s' % (package.parent, env['ROS_PACKAGE_PATH'])
    with RosSystem(tmp_path, env=env) as ros:
        ros.launch('world', str(package / 'launch' / 'world.launch'))

        def course_topics_up():
            state = ros.graph.master().getSystemState()
            published = {topic for topic, _nodes in state[0]}
            subscribed = {topic for topic, _nodes in state[1]}
            return {'/odom', '/camera/rgb/image_raw', '/camera/rgb/camera_info', '/scan'} <= published \
                and '/cmd_vel' in subscribed
        assert wait_until(course_topics_up, 60.0), ros.log_tail('world')


def test_files_already_there_are_kept_unless_forced(tmp_path):
    (tmp_path / 'my_robot.gazebo').write_text('mine')
    result = course_files(tmp_path)
    assert result.returncode == 1 and result.stdout == ''
    assert result.stderr.strip() == ('course_files: %s already exists; nothing was copied (add --force '
                                     'to replace it)' % (tmp_path / 'my_robot.gazebo'))
    assert (tmp_path / 'my_robot.gazebo').read_text() == 'mine'
    assert not (tmp_path / 'hokuyo.dae').exists()
    result = course_files('--force', tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / 'my_robot.gazebo').read_bytes() == (COURSE_DIR / 'my_robot.gazebo').read_bytes()


def test_a_link_in_dest_is_replaced_not_written_through(tmp_path):
    elsewhere = tmp_path / 'elsewhere.txt'
    elsewhere.write_text('keep me')
    dest = tmp_path / 'dest'
    dest.mkdir()
    (dest / 'hokuyo.dae').symlink_to(elsewhere)
    result = course_files('--force', dest)
    assert result.returncode == 0, result.stderr
    assert elsewhere.read_text() == 'keep me'
    assert not (dest / 'hokuyo.dae').is_symlink()


def test_a_missing_dest_is_made(tmp_path):
    result = course_files(tmp_path / 'a' / 'b')
    assert result.returncode == 0, result.stderr
    assert (tmp_path / 'a' / 'b' / 'hokuyo.dae').is_file()


def test_a_file_as_dest_gets_a_clear_error(tmp_path):
    target = tmp_path / 'file'
    target.write_text('')
    result = course_files(target)
    assert result.returncode == 1 and result.stdout == ''
    assert result.stderr.strip() == 'course_files: %s is a file, not a folder; give a folder to copy into' % target


@pytest.mark.skipif(os.geteuid() == 0, reason='root writes into any folder')
def test_an_unwritable_dest_gets_a_clear_error(tmp_path):
    locked = tmp_path / 'locked'
    locked.mkdir()
    locked.chmod(stat.S_IRUSR | stat.S_IXUSR)
    try:
        result = course_files(locked)
        made = course_files(locked / 'inside')
    finally:
        locked.chmod(stat.S_IRWXU)
    assert result.returncode == 1
    assert result.stderr.strip() == 'course_files: cannot write %s: Permission denied' % (locked / 'hokuyo.dae')
    assert made.returncode == 1
    assert made.stderr.strip() == 'course_files: cannot make the folder %s: Permission denied' % (locked / 'inside')


def test_no_dest_gets_the_usage():
    result = course_files()
    assert result.returncode == 2
    assert result.stderr.startswith('usage: course_files [-h] [--force] DEST')


def test_a_folder_no_one_can_write_into_gets_a_clear_error():
    # /proc refuses new files even to root, so this runs as any user.
    result = course_files('/proc/1')
    assert result.returncode == 1 and result.stdout == ''
    assert result.stderr.startswith('course_files: cannot write /proc/1/hokuyo.dae: ')
    assert len(result.stderr.splitlines()) == 1
