"""`rosrun flatsim inspect`: what it says about an arm, its joints, ros_control and controllers."""
import os
import subprocess

import pytest
import yaml

from flatsim.inspect_cli import main

HERE = os.path.dirname(os.path.abspath(__file__))
SRC = os.path.join(HERE, '..', '..')
ARM = os.path.join(SRC, 'simple_arm', 'urdf', 'simple_arm.urdf.xacro')
ARM_CONTROLLERS = os.path.join(SRC, 'simple_arm', 'config', 'controllers.yaml')
SLIDER_ARM = os.path.join(HERE, 'fixtures', 'robots', 'slider_arm.urdf.xacro')
WORLD = os.path.join(HERE, 'fixtures', 'worlds', 'shapes.world')


def inspect(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def lines_of(out, start):
    return [line.strip() for line in out.splitlines() if line.strip().startswith(start)]


def write_yaml(tmp_path, params):
    path = tmp_path / 'controllers.yaml'
    path.write_text(yaml.safe_dump(params))
    return str(path)


def test_the_arm_its_joints_and_its_ros_control_namespace(capsys):
    code, out, _ = inspect(capsys, '--robot', ARM)
    assert code == 0
    assert 'robot simple_arm: root link world (fixed to the world), 5 links' in out
    assert lines_of(out, 'joint_1:') == [
        'joint_1: continuous, axis (0, 0, 1), base_link -> link_1; no position limits, effort 30 N*m, '
        'velocity 1 rad/s, soft limits -2..0.5 rad (k_position 15, k_velocity 10)']
    assert lines_of(out, 'joint_2:')[0].startswith('joint_2: continuous, axis (0, 1, 0), link_1 -> link_2;')
    assert lines_of(out, 'camera_joint:') == ['camera_joint: fixed, link_2 -> camera_link']
    assert ('ros_control: libgazebo_ros_control.so, namespace /simple_arm, robot_description, '
            'control period every physics step; services /simple_arm/controller_manager/*') in out
    assert lines_of(out, 'joint_1_transmission:') == [
        'joint_1_transmission: joint_1 on EffortJointInterface, mechanical reduction 1']
    assert 'controllers: loaded at run time from the parameters under /simple_arm' in out


def test_a_floor_is_named_as_ground_and_a_box_as_a_body_robots_push(capsys):
    building = os.path.join(HERE, 'fixtures', 'worlds', 'building_floor.world')
    code, out, _ = inspect(capsys, '--world', building)
    assert code == 0
    assert lines_of(out, 'ground:') == [
        'ground: house::Floor_0_Collision, its top 0.100 m up: robots drive on it']
    assert lines_of(out, 'model unit_box:') == [
        'model unit_box: a body robots push, 1 kg, friction mu 1 (slides against 9.8 N) at (-4.00, 3.00)']
    assert 'physics: step 0.0020 s, 4 static colliders from 1 static models' in out


def test_revolute_and_prismatic_limits_in_their_units(capsys):
    code, out, _ = inspect(capsys, '--robot', SLIDER_ARM, '--xacro-arg', 'slide_interface:=Velocity')
    assert code == 0
    assert lines_of(out, 'shoulder:') == [
        'shoulder: revolute, axis (0, 0, 1), base_link -> link_a; position -1..1 rad, effort 20 N*m, '
        'velocity 1.5 rad/s']
    assert lines_of(out, 'slide:') == [
        'slide: prismatic, axis (1, 0, 0), link_a -> link_b; position 0..0.4 m, effort 50 N, velocity 0.3 m/s']
    assert lines_of(out, 'slide_transmission:') == [
        'slide_transmission: slide on VelocityJointInterface, mechanical reduction 1']


def test_the_course_controllers_with_their_joints_gains_and_topics(capsys):
    code, out, _ = inspect(capsys, '--robot', ARM, '--controllers', ARM_CONTROLLERS)
    assert code == 0
    assert 'controllers in %s, under /simple_arm:' % ARM_CONTROLLERS in out
    assert lines_of(out, 'joint_state_controller:') == [
        'joint_state_controller: joint_state_controller/JointStateController, publish_rate 50 Hz -> '
        '/simple_arm/joint_states (JointStateInterface)']
    assert lines_of(out, 'joint_1_position_controller:') == [
        'joint_1_position_controller: effort_controllers/JointPositionController on joint_1 '
        '(EffortJointInterface); /simple_arm/joint_1_position_controller/command (std_msgs/Float64) -> '
        '/simple_arm/joint_1_position_controller/state (control_msgs/JointControllerState); '
        'pid p 100, i 0.01, d 10 (i has no effect without i_clamp)']


def test_controllers_that_would_not_load_get_the_controller_managers_error(capsys, tmp_path):
    path = write_yaml(tmp_path, {'slider_arm': {
        'bogus': {'type': 'effort_controllers/NoSuchController', 'joint': 'shoulder'},
        'wrong_interface': {'type': 'effort_controllers/JointPositionController', 'joint': 'slide',
                            'pid': {'p': 10}},
        'clamped': {'type': 'effort_controllers/JointPositionController', 'joint': 'shoulder',
                    'pid': {'p': 10, 'i': 1, 'i_clamp': 2}},
        'not_a_controller': {'joint': 'shoulder'},
    }})
    code, out, _ = inspect(capsys, '--robot', SLIDER_ARM, '--xacro-arg', 'slide_interface:=Position',
                           '--controllers', path)
    assert code == 0
    assert lines_of(out, 'bogus:') == [
        "bogus: cannot be loaded: Could not load controller 'bogus' because controller type "
        "'effort_controllers/NoSuchController' does not exist. Use 'rosservice call "
        "controller_manager/list_controller_types' to get the available types"]
    assert lines_of(out, 'wrong_interface:')[0].endswith(
        "Could not find resource 'slide' in 'hardware_interface::EffortJointInterface'. "
        "Initializing controller 'wrong_interface' failed")
    assert lines_of(out, 'clamped:')[0].endswith('pid p 10, i 1, d 0, i_clamp -2..2')
    assert not lines_of(out, 'not_a_controller')


def test_a_file_without_the_robots_namespace_says_where_it_looked(capsys, tmp_path):
    path = write_yaml(tmp_path, {'joint_state_controller': {
        'type': 'joint_state_controller/JointStateController', 'publish_rate': 50}})
    code, out, _ = inspect(capsys, '--robot', ARM, '--controllers', path)
    assert code == 0
    assert ('controllers in %s: nothing under /simple_arm (top-level keys: joint_state_controller); '
            'loaded at the root namespace, it gives the spawner in /simple_arm no controllers' % path) in out


@pytest.mark.parametrize('argv, message', [
    (['--world', WORLD, '--controllers', ARM_CONTROLLERS],
     'inspect: --controllers needs a --robot with the gazebo_ros_control plugin'),
    (['--robot', ARM, '--controllers', '/nonexistent/controllers.yaml'],
     'inspect: cannot read /nonexistent/controllers.yaml: No such file or directory'),
])
def test_bad_arguments_get_a_clear_error(capsys, argv, message):
    code, out, err = inspect(capsys, *argv)
    assert code == 1 and out == ''
    assert err.strip() == message


def test_broken_yaml_is_named(capsys, tmp_path):
    path = tmp_path / 'broken.yaml'
    path.write_text('simple_arm: [unclosed\n')
    code, _, err = inspect(capsys, '--robot', ARM, '--controllers', str(path))
    assert code == 1 and err.startswith('inspect: %s is not YAML:' % path)


def test_rosrun_runs_it():
    # Each package once on the path, however other tests extended it, or rosrun asks which one.
    paths = dict.fromkeys(os.path.realpath(p) for p in os.environ['ROS_PACKAGE_PATH'].split(os.pathsep) if p)
    env = dict(os.environ, ROS_PACKAGE_PATH=os.pathsep.join(paths))
    result = subprocess.run(['rosrun', 'flatsim', 'inspect', '--robot', ARM, '--controllers', ARM_CONTROLLERS],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, timeout=120,
                            check=False, env=env)
    assert result.returncode == 0, result.stderr
    assert 'joint_2_position_controller: effort_controllers/JointPositionController on joint_2' in result.stdout


FRONT_WHEELER = os.path.join(HERE, 'fixtures', 'robots', 'front_wheels_no_casters.urdf')
MY_ROBOT = os.path.join(SRC, 'my_robot', 'urdf', 'my_robot.xacro')


def test_a_robot_with_its_wheels_at_the_front_and_no_casters_gets_a_warning_with_the_numbers(capsys):
    code, out, _ = inspect(capsys, '--robot', FRONT_WHEELER)
    assert code == 0
    assert lines_of(out, 'warning: stability:') == [
        'warning: stability: may tip over: centre of mass (0.033, 0.000) m of 12.00 kg is 0.167 m outside '
        'the support line (no polygon) (0.200, -0.175) (0.200, 0.175) of left_wheel, right_wheel '
        '(margin -0.167 m; a stable design keeps it at least 0.02 m inside)']


@pytest.mark.parametrize('drive', ['diff', 'skid'])
def test_the_projects_robot_stands_without_a_warning(capsys, drive):
    code, out, _ = inspect(capsys, '--robot', MY_ROBOT, '--xacro-arg', 'drive:=%s' % drive)
    assert code == 0
    assert 'warning' not in out
    [line] = lines_of(out, 'stability:')
    assert line.startswith('stability: stable: centre of mass (0.00')


def test_an_arm_fixed_to_the_world_is_not_judged(capsys):
    _code, out, _ = inspect(capsys, '--robot', ARM)
    assert 'stability' not in out


def test_the_stability_example_in_the_simulator_doc_prints_what_the_doc_shows():
    top = os.path.realpath(os.path.join(SRC, '..', '..'))
    with open(os.path.join(top, 'docs', 'simulator.md'), encoding='utf-8') as handle:
        section = handle.read().split('## Stability', 1)[1].split('\n## ', 1)[0]
    [command] = [line for line in section.splitlines() if line.startswith('rosrun flatsim inspect')]
    [shown] = [line.strip() for line in section.splitlines() if line.strip().startswith('warning: stability:')]
    paths = dict.fromkeys(os.path.realpath(p) for p in os.environ['ROS_PACKAGE_PATH'].split(os.pathsep) if p)
    env = dict(os.environ, ROS_PACKAGE_PATH=os.pathsep.join(paths))
    result = subprocess.run(command.split(), cwd=top, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            timeout=120, check=False, env=env)
    assert result.returncode == 0, result.stderr
    assert lines_of(result.stdout, 'warning: stability:') == [shown]
