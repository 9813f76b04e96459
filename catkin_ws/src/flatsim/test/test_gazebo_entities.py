"""Gazebo's entities, wrench jobs and step changes in flatsim's world, without ROS."""
import math
import os
import subprocess

import pytest

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import parse_sdf_models, parse_world
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world import entities
from flatsim.world.sim import Simulation
from flatsim.world.wrench import WrenchJob
from test_articulation import arm, arm_xml  # noqa: F401 (arm_xml is a fixture)
from conftest import MY_ROBOT_XACRO
from test_sim import _ball_model, table_world


@pytest.fixture(scope='module')
def robot_spec():
    return load_robot(expand_xacro(str(MY_ROBOT_XACRO)), name='my_robot')


@pytest.fixture
def sim(robot_spec):
    sim = Simulation(parse_world(table_world()))
    sim.spawn_robot('my_robot', robot_spec, Pose(-2.0, 0.0, 0.0, yaw=math.pi / 2))
    return sim


def test_fixed_joints_lump_links_into_their_parent_as_gazebos_urdf_import_does(robot_spec):
    bodies = [name for name, _ in entities.robot_bodies(robot_spec)]
    assert bodies == ['robot_footprint', 'left_wheel', 'right_wheel']


def test_entities_by_model_scoped_link_or_bare_link_name(sim):
    assert entities.find_entity(sim, 'my_robot') == entities.Entity('my_robot')
    wheel = entities.find_entity(sim, 'my_robot::left_wheel')
    assert (wheel.model, wheel.link) == ('my_robot', 'left_wheel')
    assert entities.find_entity(sim, 'left_wheel') == wheel
    assert entities.find_entity(sim, 'my_robot::chassis') is None  # lumped away
    assert entities.find_entity(sim, 'table::leg_2').offset.x == pytest.approx(-0.47)
    assert entities.find_entity(sim, '') is None


def test_a_link_moves_with_its_model_and_has_the_lever_velocity(sim):
    wheel = entities.find_entity(sim, 'my_robot::left_wheel')
    pose = entities.entity_pose(sim, wheel)
    # Facing +y, the robot's left is -x.
    assert pose.x < -2.05 and pose.y == pytest.approx(0.0, abs=0.2)
    sim.set_model_state('my_robot', Pose(-2.0, 0.0, 0.0, yaw=math.pi / 2), (0.0, 0.0, 1.0))
    linear, angular = entities.entity_twist(sim, wheel)
    assert angular == (0.0, 0.0, 1.0)
    assert linear[1] == pytest.approx(pose.x + 2.0)  # w x r with r along -x


def test_a_wrench_acts_from_its_start_for_its_duration_and_is_then_dropped(sim):
    sim.set_step_size(0.01)
    sim.wrenches.add(WrenchJob('ball::link', 'ball', (0.0, 0.0), (1.0, 0.0, 5.0), (0.0, 0.0, 0.0),
                               start=0.1, duration=0.2))
    for _ in range(10):
        sim.step()
    assert sim.model_twist('ball')[0] == 0.0  # not yet started
    for _ in range(25):
        sim.step()
    # 1 N on 0.5 kg in 21 steps of 0.01 s (both ends included), less 0.25 s of rolling resistance.
    assert sim.model_twist('ball')[0] == pytest.approx(21 * 0.01 * 2.0 - 0.2 * 0.25, rel=0.01)
    assert sim.wrenches.jobs == []


def test_a_wrench_with_a_negative_duration_lasts_until_cleared(sim):
    sim.wrenches.add(WrenchJob('ball::link', 'ball', (0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 0.0),
                               start=0.0, duration=-1.0))
    for _ in range(500):
        sim.step()
    assert len(sim.wrenches.jobs) == 1 and sim.model_twist('ball')[1] > 1.0
    sim.wrenches.clear('ball::link')
    assert sim.wrenches.jobs == []
    with pytest.raises(FlatsimError, match="finite numbers"):
        sim.wrenches.add(WrenchJob('ball::link', 'ball', (0.0, 0.0), (math.nan, 0.0, 0.0),
                                   (0.0, 0.0, 0.0), 0.0, 1.0))


def test_a_new_step_size_keeps_time_continuous_and_bad_ones_are_refused(sim):
    for _ in range(100):
        sim.step()
    assert sim.time == pytest.approx(0.2)
    sim.set_step_size(0.001)
    sim.step()
    assert sim.time == pytest.approx(0.201)
    for bad in (1e300, 1e-300, 0.0, -0.001, math.nan, math.inf):
        with pytest.raises(FlatsimError, match='step size must be between'):
            sim.set_step_size(bad)
    assert sim.step_size == 0.001


def test_world_models_keep_their_links_in_the_model_frame():
    world = parse_world('<sdf version="1.6"><world name="w">%s</world></sdf>'
                        % _ball_model('my_ball', 1.0, 2.0))
    assert world.models[0].links == [('link', Pose())]


def test_set_model_configuration_moves_ros_control_joints_and_passes_over_unknown_ones(arm_xml):
    sim, robot, _ = arm(arm_xml, start=False)
    unknown = entities.set_joint_positions(sim, 'simple_arm', {'joint_1': 0.5, 'joint_2': -0.25,
                                                               'no_such_joint': 1.0})
    assert unknown == ['no_such_joint']
    assert robot.control.joint_positions() == pytest.approx({'joint_1': 0.5, 'joint_2': -0.25})
    # get_link_state and link_states see the links where the joints put them.
    link_1 = entities.find_entity(sim, 'simple_arm::link_1')
    assert entities.entity_pose(sim, link_1).yaw == pytest.approx(0.5)
    link_2 = entities.find_entity(sim, 'simple_arm::link_2')
    assert entities.entity_pose(sim, link_2).pitch == pytest.approx(-0.25)
    with pytest.raises(FlatsimError, match='not a finite number'):
        entities.set_joint_positions(sim, 'simple_arm', {'joint_1': float('nan')})
    assert robot.control.joint_positions()['joint_1'] == pytest.approx(0.5)


def test_set_model_configuration_refuses_robots_without_ros_control_joints(sim):
    with pytest.raises(FlatsimError, match='ros_control robots only'):
        entities.set_joint_positions(sim, 'my_robot', {'left_wheel_hinge': 1.0})


def test_the_ball_is_the_one_pushable_sphere_whatever_its_name(sim):
    # table_world's ball is called 'ball'; tables, walls and robots are not balls.
    assert entities.ball_names(sim) == ['ball']
    assert entities.the_ball(entities.ball_names(sim)) == 'ball'
    sim.add_world_model(parse_sdf_models('<sdf version="1.6">%s</sdf>'
                                         % _ball_model('my_ball', 1.0, -1.0))[0][0])
    with pytest.raises(FlatsimError, match=r'2 balls \(ball, my_ball\); name the one to move'):
        entities.the_ball(entities.ball_names(sim))
    sim.delete_model('ball')
    sim.delete_model('my_ball')
    with pytest.raises(FlatsimError, match='no ball'):
        entities.the_ball(entities.ball_names(sim))


def test_move_model_takes_an_optional_model_name():
    from flatsim.nodes.move_model import parse_args
    assert vars(parse_args(['2', '-1.5'])) == {'model': '', 'x': 2.0, 'y': -1.5, 'yaw': 0.0}
    assert vars(parse_args(['-1', '2', '0.5'])) == {'model': '', 'x': -1.0, 'y': 2.0, 'yaw': 0.5}
    assert vars(parse_args(['my_ball', '1', '2'])) == {'model': 'my_ball', 'x': 1.0, 'y': 2.0,
                                                       'yaw': 0.0}


@pytest.mark.parametrize('argv', [['white_ball', 'inf', '0'], ['inf', '0'], ['white_ball', '0', 'nan'],
                                  ['white_ball', '0', '0', 'inf']])
def test_move_model_refuses_a_place_or_heading_that_is_not_finite(argv, capsys):
    from flatsim.nodes.move_model import parse_args
    with pytest.raises(SystemExit) as stopped:
        parse_args(argv)
    assert stopped.value.code == 2
    assert 'is not a finite number' in capsys.readouterr().err


def test_move_model_with_inf_ends_in_one_clear_line_before_it_looks_for_a_master():
    # As the user types it; no master is needed to say what is wrong with the numbers.
    done = subprocess.run(['rosrun', 'flatsim', 'move_model', 'white_ball', 'inf', '0'],
                          capture_output=True, text=True, timeout=60,
                          env=dict(os.environ, ROS_MASTER_URI='http://localhost:9'))
    assert done.returncode == 2
    assert done.stderr.splitlines()[-1] == "move_model: error: argument x: 'inf' is not a finite number"
    assert 'Traceback' not in done.stderr
