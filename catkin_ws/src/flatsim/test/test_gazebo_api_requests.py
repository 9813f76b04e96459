"""Bad requests to Gazebo's API, answered by flatsim's handlers without a master: each
gets success False and a status message, or its log lines stay short, and the world
is left as it was."""
import json
import logging
import math
import threading
import types

import pytest
import rospy
from gazebo_msgs.msg import LinkState, ModelState
from gazebo_msgs.srv import (ApplyBodyWrench, GetModelState, SetLinkState, SetModelState,
                             SetPhysicsProperties, SpawnModel)
from geometry_msgs.msg import Point, Pose as PoseMsg, Quaternion

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import parse_world
from flatsim.loading.urdf_robot import expand_xacro
from flatsim.names import MAX_LOGGED_CHARS, logged_name
from flatsim.ros.gazebo_api import GazeboApi
from flatsim.ros.node import FlatsimNode
from flatsim.world.sim import Simulation
from flatsim.world.wrench import WrenchJob
from conftest import MY_ROBOT_XACRO
from test_sim import table_world

NOT_FINITE = [math.nan, math.inf, -math.inf]
BOX_SDF = ('<sdf version="1.6"><model name="box"><link name="link"><collision name="c"><geometry>'
           '<box><size>0.3 0.3 0.3</size></box></geometry></collision></link></model></sdf>')


class _Node:
    """The part of FlatsimNode that the handlers call."""

    def __init__(self, sim):
        self.sim = sim
        self.lock = threading.RLock()
        self.added = []
        self.real_time_factor = 1.0

    def add_model(self, name, loaded, pose, origin=None):
        self.added.append(name)

    def set_real_time_factor(self, factor):
        self.real_time_factor = factor

    def publish_ball_names(self):
        pass


@pytest.fixture
def sim():
    return Simulation(parse_world(table_world()))


@pytest.fixture
def api(sim):
    """GazeboApi's handlers over sim, without its publishers and services."""
    handlers = GazeboApi.__new__(GazeboApi)
    handlers.node = _Node(sim)
    handlers.sim = sim
    handlers.lock = handlers.node.lock
    handlers.get_model_state_counts = {}
    return handlers


@pytest.fixture
def rosout(caplog, monkeypatch):
    """The lines rospy logs, as rosout would write them. Its throttled logs read its clock,
    which init_node would start: here the wall clock stands in."""
    monkeypatch.setattr(rospy.rostime, '_rostime_initialized', True)
    caplog.set_level(logging.DEBUG, logger='rosout')
    return caplog


def pose_msg(x, y, orientation):
    return PoseMsg(position=Point(x, y, 0.1), orientation=Quaternion(*orientation))


# set_model_state, set_link_state and spawns: a quaternion of NaN or inf -----------

@pytest.mark.parametrize('bad', NOT_FINITE)
@pytest.mark.parametrize('part', range(4))
def test_set_model_state_refuses_a_quaternion_that_is_not_finite_and_leaves_the_model(api, sim, bad,
                                                                                      part):
    orientation = [0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)]
    orientation[part] = bad
    before = sim.model_pose('ball')
    response = api.set_model_state(SetModelState._request_class(model_state=ModelState(
        model_name='ball', pose=pose_msg(1.0, -1.0, orientation))))
    assert not response.success
    assert response.status_message.startswith('SetModelState: orientation')
    assert 'not a quaternion of finite numbers' in response.status_message
    assert sim.model_pose('ball') == before


def test_set_link_state_refuses_a_quaternion_that_is_not_finite(api, sim):
    before = sim.model_pose('ball')
    response = api.set_link_state(SetLinkState._request_class(link_state=LinkState(
        link_name='ball::link', pose=pose_msg(1.0, -1.0, (0.0, 0.0, math.inf, 1.0)))))
    assert not response.success
    assert response.status_message.startswith('SetLinkState: orientation')
    assert sim.model_pose('ball') == before


def test_a_spawn_refuses_an_initial_pose_whose_quaternion_is_not_finite(api):
    response = api.spawn_sdf_model(SpawnModel._request_class(
        model_name='box', model_xml=BOX_SDF, initial_pose=pose_msg(1.0, 1.0, (math.nan, 0, 0, 1))))
    assert not response.success
    assert response.status_message.startswith('SpawnModel: Failure - initial_pose orientation')
    assert api.node.added == []


def test_a_finite_quaternion_still_turns_the_model_and_an_all_zero_one_is_no_turn(api, sim):
    # Huge parts once overflowed the norm and read as no turn at all.
    for orientation, yaw in [((0.0, 0.0, 1e300, 1e300), math.pi / 2), ((0.0, 0.0, 0.0, 0.0), 0.0)]:
        response = api.set_model_state(SetModelState._request_class(model_state=ModelState(
            model_name='ball', pose=pose_msg(1.0, -1.0, orientation))))
        assert response.success
        assert sim.model_pose('ball').yaw == pytest.approx(yaw)


def test_a_spawn_with_a_finite_pose_is_still_placed(api):
    response = api.spawn_sdf_model(SpawnModel._request_class(
        model_name='box', model_xml=BOX_SDF, initial_pose=pose_msg(1.0, 1.0, (0, 0, 0, 1))))
    assert response.success and api.node.added == ['box']


# apply_body_wrench: a torque that overflows -------------------------------------------

def wrench_request(force, point, frame='', body='ball::link'):
    request = ApplyBodyWrench._request_class(body_name=body, reference_frame=frame)
    request.wrench.force.x, request.wrench.force.y = force
    request.reference_point = Point(*point)
    request.duration.secs = 1
    return request


@pytest.mark.parametrize('force, point, frame', [
    ((1e300, 1e300), (1e300, -1e300, 0.0), ''),
    ((1.7e308, 0.0), (0.0, 10.0, 0.0), ''),
    # Finite at the point, overflowing only once turned into the frame of the table's leg.
    ((1.7e308, 1.7e308), (0.0, 0.0, 0.0), 'table::leg_2'),
])
def test_a_wrench_whose_torque_overflows_is_refused_with_a_message(api, sim, force, point, frame):
    response = api.apply_body_wrench(wrench_request(force, point, frame))
    assert not response.success
    assert response.status_message.startswith('ApplyBodyWrench: the wrench overflows')
    assert sim.wrenches.jobs == []


def test_a_wrench_at_a_reference_point_is_still_taken(api, sim):
    response = api.apply_body_wrench(wrench_request((2.0, 0.0), (0.0, 0.5, 0.0)))
    assert response.success
    assert sim.wrenches.jobs[0].torque == (0.0, 0.0, -1.0)


def test_a_wrench_on_a_jointed_model_flatsim_holds_still_is_refused_saying_why(api):
    from test_sim_ground_and_bodies import JOINTED
    held = Simulation(parse_world(JOINTED))
    api.sim = api.node.sim = held
    response = api.apply_body_wrench(wrench_request((5.0, 0.0), (0.0, 0.0, 0.0), body='door::leaf'))
    assert not response.success
    assert response.status_message == (
        'ApplyBodyWrench: flatsim holds model door still: its 1 joint(s) would take its links '
        'apart, and flatsim moves a model as one rigid body in the plane')
    assert held.wrenches.jobs == []


# Long names in requests: log lines stay short ------------------------------------------

LONG_NAME = 'm' * 10 ** 7


def test_a_name_is_cut_for_the_log_and_its_length_said():
    assert logged_name('white_ball') == 'white_ball'
    shown = logged_name(LONG_NAME)
    assert shown == 'm' * MAX_LOGGED_CHARS + '... (10000000 characters)'


@pytest.mark.parametrize('call', [
    lambda api: api.get_model_state(GetModelState._request_class(model_name=LONG_NAME)),
    lambda api: api.set_model_state(SetModelState._request_class(model_state=ModelState(
        model_name=LONG_NAME, pose=pose_msg(0, 0, (0, 0, 0, 1))))),
    lambda api: api.set_model_state(SetModelState._request_class(model_state=ModelState(
        model_name='ball', reference_frame=LONG_NAME, pose=pose_msg(0, 0, (0, 0, 0, 1))))),
    lambda api: api.set_link_state(SetLinkState._request_class(link_state=LinkState(
        link_name=LONG_NAME, pose=pose_msg(0, 0, (0, 0, 0, 1))))),
    lambda api: api.apply_body_wrench(ApplyBodyWrench._request_class(body_name=LONG_NAME)),
    lambda api: api.delete_model(types.SimpleNamespace(model_name=LONG_NAME)),
    lambda api: api.get_model_properties(types.SimpleNamespace(model_name=LONG_NAME)),
    lambda api: api.set_model_configuration(types.SimpleNamespace(
        model_name=LONG_NAME, joint_names=[], joint_positions=[])),
], ids=['get_model_state', 'set_model_state', 'set_model_state_frame', 'set_link_state',
        'apply_body_wrench', 'delete_model', 'get_model_properties', 'set_model_configuration'])
def test_a_ten_million_character_name_is_cut_in_the_log(api, rosout, call):
    response = call(api)
    assert not response.success
    lines = [record.getMessage() for record in rosout.records]
    assert lines, 'the refusal is logged'
    assert all(len(line) < 1000 for line in lines), [len(line) for line in lines]
    assert any('(10000000 characters)' in line for line in lines)


# Physics that an endless wrench makes diverge -------------------------------------------

def endless_wrench(force=(0.0, 0.0, 0.0), torque=(0.0, 0.0, 0.0)):
    return WrenchJob(body='ball::link', model='ball', offset=(0.0, 0.0), force=force,
                     torque=torque, start=0.0, duration=-1.0)


def test_a_world_that_starts_over_drops_the_wrench_that_made_it_diverge(sim, rosout):
    sim.wrenches.add(endless_wrench(torque=(0.0, 0.0, 1.7e308)))
    node = types.SimpleNamespace(sim=sim)
    with pytest.raises(FlatsimError, match='physics diverged') as caught:
        sim.step()
    FlatsimNode.on_diverged(node, caught.value)
    assert sim.wrenches.jobs == []
    assert any('dropped the wrenches on ball::link' in record.getMessage()
               for record in rosout.records)
    for _ in range(100):
        sim.step()
    assert not sim.paused
    assert sim.model_pose('ball').x == pytest.approx(2.0)


def test_an_endless_huge_force_is_slowed_not_a_crash(sim):
    sim.wrenches.add(endless_wrench(force=(1e300, 0.0, 0.0)))
    for _ in range(5):
        sim.step()
    assert sim.model_twist('ball')[0] == pytest.approx(100.0)
    assert 'ball' in sim.physics.slowed


def test_physics_that_stops_says_to_clear_the_wrenches(sim, rosout):
    node = types.SimpleNamespace(sim=sim)
    for _ in range(3):
        sim.models['ball'].handle.body.velocity = (math.nan, 0.0)
        with pytest.raises(FlatsimError) as caught:
            sim.step()
        FlatsimNode.on_diverged(node, caught.value)
    assert sim.paused
    stopped = [record.getMessage() for record in rosout.records if 'physics paused' in record.getMessage()]
    assert len(stopped) == 1 and '/gazebo/clear_body_wrenches' in stopped[0]


# What a spawn's log says about a robot's clamped sensor rate ----------------------------

def test_a_clamped_sensor_rate_is_logged_as_adjusted_not_skipped(api, rosout, monkeypatch):
    monkeypatch.setenv('ROS_PACKAGE_PATH', str(MY_ROBOT_XACRO.parents[2]))
    urdf = expand_xacro(str(MY_ROBOT_XACRO)).replace('<update_rate>30</update_rate>',
                                                     '<update_rate>1e300</update_rate>', 1)
    spec, _ = api._load('urdf', SpawnModel._request_class(model_name='my_robot', model_xml=urdf))
    assert spec.cameras and spec.cameras[0].update_rate > 0
    lines = [record.getMessage() for record in rosout.records if '<update_rate>' in record.getMessage()]
    assert len(lines) == 1
    assert lines[0].startswith('flatsim: robot my_robot: adjusted sensor camera')
    assert 'the sensor is kept and updates at every step' in lines[0]
    assert 'skipped' not in lines[0]


# set_physics_properties: the pace it sets ------------------------------------------------

def physics_request(time_step, max_update_rate):
    request = SetPhysicsProperties._request_class(time_step=time_step, max_update_rate=max_update_rate)
    request.gravity.z = -9.8
    return request


@pytest.mark.parametrize('max_update_rate', [1e308, 1e-6])
def test_set_physics_properties_refuses_a_real_time_factor_flatsim_cannot_pace(api, sim,
                                                                               max_update_rate):
    response = api.set_physics_properties(physics_request(0.001, max_update_rate))
    assert not response.success
    assert response.status_message.startswith(
        'SetPhysicsProperties: the real-time factor (max_update_rate x time_step) must be 0 (as '
        'fast as possible) or 0.001 to 1000 sim seconds per wall second, got ')
    assert (sim.step_size, api.node.real_time_factor) == (0.002, 1.0)


def test_set_physics_properties_takes_zero_as_fast_as_possible_and_a_factor_in_range(api, sim):
    assert api.set_physics_properties(physics_request(0.001, 0.0)).success
    assert (sim.step_size, api.node.real_time_factor) == (0.001, 0.0)
    assert api.set_physics_properties(physics_request(0.001, 2000.0)).success
    assert api.node.real_time_factor == pytest.approx(2.0)


# ~model_moves: who moved what ------------------------------------------------------

class _Said:
    def __init__(self):
        self.messages = []

    def publish(self, msg):
        self.messages.append(json.loads(msg.data))


def test_each_model_moved_through_the_api_is_said_with_its_caller_and_a_refused_move_is_not(api, sim):
    api.moves_pub = _Said()
    handle = api.recording('set_model_state', api.set_model_state,
                           lambda req: req.model_state.model_name)
    request = SetModelState._request_class(model_state=ModelState(
        model_name='ball', pose=pose_msg(1.0, -1.0, (0.0, 0.0, 0.0, 1.0))))
    request._connection_header = {'callerid': '/mover'}
    assert handle(request).success
    missing = SetModelState._request_class(model_state=ModelState(model_name='nothing'))
    missing._connection_header = {'callerid': '/mover'}
    assert not handle(missing).success
    api.on_model_state_topic(_with_caller(ModelState(
        model_name='ball', pose=pose_msg(0.5, 0.5, (0.0, 0.0, 0.0, 1.0))), '/publisher'))
    wrench = api.recording('apply_body_wrench', api.apply_body_wrench, lambda req: req.body_name)
    push = ApplyBodyWrench._request_class(body_name='ball::link', reference_frame='world')
    push.wrench.force.x = 1.0
    push._connection_header = {'callerid': '/pusher'}
    assert wrench(push).success
    assert api.moves_pub.messages == [
        {'time': sim.time, 'by': '/mover', 'through': '/gazebo/set_model_state', 'target': 'ball'},
        {'time': sim.time, 'by': '/publisher', 'through': '/gazebo/set_model_state', 'target': 'ball'},
        {'time': sim.time, 'by': '/pusher', 'through': '/gazebo/apply_body_wrench',
         'target': 'ball::link'}]


def _with_caller(msg, caller):
    msg._connection_header = {'callerid': caller}
    return msg
