"""Joint motion and ros_control without ROS: the course arm, a pendulum, limits and bad input."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest
import yaml

from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world.controllers import Pid
from flatsim.world.sim import Simulation

SRC = os.path.normpath(os.path.join(os.path.dirname(__file__), '..', '..'))
ARM = os.path.join(SRC, 'simple_arm', 'urdf', 'simple_arm.urdf.xacro')
CONTROLLERS = os.path.join(SRC, 'simple_arm', 'config', 'controllers.yaml')
# From (0, 0) to safe_move(1.57, 1.57), in sim time, as README.md's lessons section says.
README_SETTLE_TIMES_S = (1.65, 1.43)


@pytest.fixture(scope='module')
def arm_xml():
    # Only for the expansion: a changed path would leak into every later test's rosrun.
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv('ROS_PACKAGE_PATH', SRC + os.pathsep + os.environ.get('ROS_PACKAGE_PATH', ''))
        return expand_xacro(ARM)


def arm(arm_xml, start=True):
    sim = Simulation()
    robot = sim.spawn_robot('simple_arm', load_robot(arm_xml, name='simple_arm'), Pose())
    params = yaml.safe_load(open(CONTROLLERS))['simple_arm']
    manager = robot.control.manager
    if start:
        for name in params:
            assert manager.load(name, params[name]), manager.errors
        assert manager.switch(list(params), [], 2, sim.time)
    return sim, robot, params


def run(sim, seconds):
    for _ in range(int(round(seconds / sim.step_size))):
        sim.step()


def test_the_arm_swings_to_its_goal_within_the_velocity_limit_and_sags_under_gravity(arm_xml):
    sim, robot, _ = arm(arm_xml)
    controllers = robot.control.manager.controllers
    articulation = robot.control.articulation
    controllers['joint_1_position_controller'].set_command(1.57)
    controllers['joint_2_position_controller'].set_command(1.57)
    times, positions, fastest = [], [], 0.0
    for step in range(int(4.0 / sim.step_size)):
        sim.step()
        fastest = max(fastest, abs(articulation.velocity[0]))
        times.append(sim.time)
        positions.append(articulation.position.copy())
    # The soft limits (k_velocity 10) hold joint 1 to its 1 rad/s velocity limit.
    assert fastest == pytest.approx(1.0, abs=0.05)
    # p = 100 and no integral: joint 2 holds the horizontal link m g l / p past its goal.
    assert articulation.position[0] == pytest.approx(1.57, abs=1e-3)
    assert articulation.position[1] == pytest.approx(1.57 + 1.0 * 9.80665 * 0.375 / 100, abs=1e-3)
    assert np.abs(articulation.velocity).max() < 1e-3
    # The settle times the README states: from the last step more than 0.01 rad from rest.
    away = np.abs(np.array(positions) - articulation.position) > 0.01
    settled = [times[np.nonzero(away[:, joint])[0][-1] + 1] for joint in (0, 1)]
    assert settled == pytest.approx(README_SETTLE_TIMES_S, abs=0.05)
    assert (np.array(positions) <= articulation.position + 1e-3).all(), 'no overshoot'


def test_the_camera_follows_the_joints(arm_xml):
    sim, robot, _ = arm(arm_xml)
    up = sim.sensor_pose(robot.sensors[0])
    assert (up.x, up.y, up.z) == pytest.approx((0.0, 0.2, 1.85), abs=1e-6)
    assert up.pitch == pytest.approx(-math.pi / 2, abs=1e-6)
    robot.control.articulation.position[:] = (math.pi / 2, math.pi / 2)
    ahead = sim.sensor_pose(robot.sensors[0])
    assert (ahead.x, ahead.y, ahead.z) == pytest.approx((-0.2, 0.75, 1.1), abs=1e-6)
    assert ahead.pitch == pytest.approx(0.0, abs=1e-6)
    assert ahead.yaw == pytest.approx(math.pi / 2, abs=1e-6)


def test_a_released_joint_swings_as_a_pendulum_of_its_inertia(arm_xml):
    sim, robot, _ = arm(arm_xml, start=False)
    articulation = robot.control.articulation
    articulation.position[:] = (0.0, math.pi + 0.05)  # link_2 hanging down, nudged
    articulation.position_target[0] = 0.0                 # joint 1 held, as a position joint is
    crossings, previous = [], articulation.position[1] - math.pi
    while len(crossings) < 3 and sim.time < 10.0:
        sim.step()
        angle = articulation.position[1] - math.pi
        if previous < 0.0 <= angle:
            crossings.append(sim.time)
        previous = angle
    # Link_2 (1 kg box 0.2 x 0.2 x 0.75, about its end) plus the camera's 1e-5 kg: I / (m g l).
    inertia = 1.0 / 12 * (0.2 ** 2 + 0.75 ** 2) + 1.0 * 0.375 ** 2
    expected = 2 * math.pi * math.sqrt(inertia / (1.0 * 9.80665 * 0.375))
    assert crossings[2] - crossings[1] == pytest.approx(expected, rel=0.01)


def test_a_nan_command_gives_no_effort_and_a_finite_one_takes_over(arm_xml):
    sim, robot, _ = arm(arm_xml)
    controller = robot.control.manager.controllers['joint_1_position_controller']
    controller.set_command(float('nan'))
    run(sim, 0.1)
    assert robot.control.articulation.effort[0] == 0.0
    assert np.isfinite(robot.control.articulation.position).all()
    controller.set_command(0.5)
    run(sim, 2.0)
    assert robot.control.articulation.position[0] == pytest.approx(0.5, abs=0.01)


def test_a_target_too_large_to_track_gives_no_effort_and_the_joint_comes_to_rest(arm_xml):
    # joint_1 is continuous: at 1e308 the error no longer depends on where the joint is.
    sim, robot, _ = arm(arm_xml)
    controller = robot.control.manager.controllers['joint_1_position_controller']
    assert controller.untrackable(1e308) and controller.untrackable(-1e7)
    assert controller.untrackable(1e6) is None
    controller.set_command(1e308)
    run(sim, 0.5)
    controller.set_command(-1e308)
    run(sim, 0.1)
    assert robot.control.articulation.effort[0] == 0.0
    run(sim, 5.0)
    assert abs(robot.control.articulation.velocity[0]) < 0.01
    controller.set_command(0.5)
    run(sim, 2.0)
    assert math.remainder(robot.control.articulation.position[0] - 0.5, 2 * math.pi) == \
        pytest.approx(0.0, abs=0.01)


def test_controller_manager_refuses_bad_controllers_with_ros_controls_messages(arm_xml):
    sim, robot, params = arm(arm_xml, start=False)
    manager = robot.control.manager
    assert not manager.load('missing', None)
    assert 'because the type was not specified' in manager.errors[0]
    assert not manager.load('bogus', {'type': 'effort_controllers/Nope', 'joint': 'joint_1'})
    assert "controller type 'effort_controllers/Nope' does not exist" in manager.errors[0]
    assert not manager.load('camera', {'type': 'effort_controllers/JointPositionController',
                                       'joint': 'camera_joint', 'pid': {'p': 1.0}})
    assert "Could not find resource 'camera_joint' in 'hardware_interface::EffortJointInterface'" \
        in manager.errors[0]
    assert not manager.load('no_pid', {'type': 'effort_controllers/JointPositionController',
                                       'joint': 'joint_1'})
    assert 'No p gain specified for pid' in manager.errors[0]
    assert not manager.load('no_rate', {'type': 'joint_state_controller/JointStateController'})
    assert "Parameter 'publish_rate' not set" in manager.errors[0]
    assert manager.load('a', params['joint_1_position_controller'])
    assert manager.load('b', params['joint_1_position_controller'])
    assert not manager.switch(['a', 'b'], [], 2, 0.0)
    assert 'resource conflict' in manager.errors[-1]
    assert manager.switch(['a'], [], 2, 0.0)
    assert not manager.unload('a')
    assert 'still running' in manager.errors[0]
    assert not manager.switch(['nope'], [], 2, 0.0)
    assert manager.switch(['nope'], [], 1, 0.0)


def test_pid_integral_needs_i_clamp_as_in_control_toolbox():
    plain = Pid({'p': 0.0, 'i': 1.0}, 'pid')
    clamped = Pid({'p': 0.0, 'i': 1.0, 'i_clamp': 5.0}, 'pid')
    for _ in range(100):
        plain_out = plain.compute(1.0, 0.1)
        clamped_out = clamped.compute(1.0, 0.1)
    assert plain_out == 0.0
    assert clamped_out == pytest.approx(5.0)
    assert Pid({'p': 1.0}, 'pid').compute(float('nan'), 0.1) == 0.0


def test_a_joint_without_transmission_is_reported_and_left_out(arm_xml):
    xml = arm_xml.replace('<joint name="joint_2">', '<joint name="not_a_joint">', 1)
    spec = load_robot(xml, name='simple_arm')
    assert any('not_a_joint' in str(item) and 'not in the gazebo model' in str(item)
               for item in spec.skipped)
    sim = Simulation()
    robot = sim.spawn_robot('simple_arm', spec, Pose())
    assert robot.control.hw.names == ['joint_1']
    # Its controller gets ros_control's error; the other joint's still loads and moves.
    manager = robot.control.manager
    params = yaml.safe_load(open(CONTROLLERS))['simple_arm']
    assert not manager.load('joint_2_position_controller', params['joint_2_position_controller'])
    assert "Could not find resource 'joint_2' in 'hardware_interface::EffortJointInterface'" \
        in manager.errors[0]
    assert manager.load('joint_1_position_controller', params['joint_1_position_controller'])
    assert manager.switch(['joint_1_position_controller'], [], 2, sim.time)
    manager.controllers['joint_1_position_controller'].set_command(0.5)
    run(sim, 2.0)
    assert robot.control.articulation.position[0] == pytest.approx(0.5, abs=0.01)


RESET_A_FIXED_ARM = '''
import sys
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation
sim = Simulation()
robot = sim.spawn_robot('simple_arm', load_robot(sys.stdin.read(), name='simple_arm'), Pose(1.0, 2.0, 0.0, yaw=0.5))
for _ in range(10):
    sim.step()
sim.reset_world()
for _ in range(10):
    sim.step()
print('%.3f %.3f %.3f' % sim.physics.pose(robot.handle))
'''


def test_a_world_reset_keeps_a_robot_bolted_to_the_world_where_it_was_spawned(arm_xml):
    # In a process of its own: pymunk aborts the whole process on a bad body.
    result = subprocess.run([sys.executable, '-c', RESET_A_FIXED_ARM], input=arm_xml, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, timeout=120, check=False)
    assert result.returncode == 0, result.stdout
    assert result.stdout.split()[-3:] == ['1.000', '2.000', '0.500'], result.stdout
