"""What no chase does, told from what the grader saw: a robot that moves faster than it could
drive, and models moved through the simulator's API by another node than the grader; and what
a world launch asks of the simulator, as the grader takes it from the sandbox. Pure."""
import json
import types

import pytest

from chase_tools.grading import launchread, trials
from chase_tools.grading.trials import Move, first_jump, moves_not_made_by

PERIOD = 0.02          # s of sim time between two model states (flatsim's default 50 Hz)


def driving(speed, seconds, start=(0.0, 0.0)):
    """Model-state rows (t, x, y, yaw, ball x, ball y) of a robot driving along x."""
    return [(i * PERIOD, start[0] + speed * i * PERIOD, start[1], 0.0, 3.0, 0.0)
            for i in range(int(seconds / PERIOD) + 1)]


def test_a_robot_that_drives_at_its_commanded_speed_never_jumps():
    commands = [(0.0, 0.8, 0.3)]
    assert first_jump(driving(0.8, 5.0), commands, PERIOD) is None


def test_a_robot_that_drives_faster_than_any_command_allows_jumps():
    jump = first_jump(driving(6.0, 1.0), [(0.0, 0.5, 0.0)], PERIOD)
    assert jump is not None and jump.time == PERIOD
    assert jump.bound == trials.TELEPORT_MIN_SPEED + 0.5


def test_a_fast_command_raises_the_bound():
    assert first_jump(driving(6.0, 1.0), [(0.0, 6.0, 0.0)], PERIOD) is None


def test_a_teleport_between_two_states_is_found_where_it_happened_and_described():
    rows = driving(0.5, 1.0) + [(1.0 + PERIOD, 2.65, 0.0, 0.0, 3.0, 0.0)]
    jump = first_jump(rows, [(0.0, 0.5, 0.0)], PERIOD)
    assert jump is not None and abs(jump.time - (1.0 + PERIOD)) < 1e-9
    assert abs(jump.distance - (2.65 - 0.5)) < 1e-6
    text = jump.describe('my_robot')
    assert text.startswith('my_robot moved 2.15 m in 0.020 s of sim time at 1.02 s')
    assert 'faster than it could drive (at most 1.5 m/s)' in text


def test_states_whose_clock_lags_count_at_least_a_states_period_apart():
    # Two states stamped alike by a clock that lags: the robot drove one period between them.
    rows = [(0.0, 0.0, 0.0, 0.0, 3.0, 0.0), (0.0, 0.02, 0.0, 0.0, 3.0, 0.0),
            (0.04, 0.04, 0.0, 0.0, 3.0, 0.0)]
    assert first_jump(rows, [(0.0, 1.0, 0.0)], PERIOD) is None


def test_a_robot_at_rest_that_settles_by_millimetres_does_not_jump():
    rows = [(0.0, 0.0, 0.0, 0.0, 3.0, 0.0), (PERIOD, 0.004, 0.003, 0.0, 3.0, 0.0)]
    assert first_jump(rows, [], PERIOD) is None


def test_moves_by_another_node_and_beyond_the_graders_own_count_are_not_the_graders():
    own = [Move(0.0, '/grade_probe', '/gazebo/set_model_state', 'my_robot'),
           Move(0.0, '/grade_probe', '/gazebo/set_model_state', 'white_ball')]
    other = Move(0.5, '/hostile_1_2', '/gazebo/set_model_state', 'my_robot')
    forged = Move(0.7, '/grade_probe', '/gazebo/apply_body_wrench', 'my_robot::base_link')
    assert moves_not_made_by(own, '/grade_probe', 2) == []
    assert moves_not_made_by(own + [other], '/grade_probe', 2) == [other]
    assert moves_not_made_by(own + [forged], '/grade_probe', 2) == [forged]
    assert other.describe() == '/hostile_1_2 moved my_robot through /gazebo/set_model_state at 0.50 s'


# -- what a world launch asks of the simulator (launchread) ---------------------------------

def document(**fields):
    return json.dumps(dict({'simulators': [], 'claims': [], 'use_sim_time': True}, **fields)).encode()


def test_the_world_is_flatsims_world_name_or_the_world_file_gzserver_is_given():
    flatsim = {'node': '/flatsim', 'package': 'flatsim', 'type': 'simulator',
               'params': {'world_name': '/w/office.world', 'paused': False}, 'args': []}
    gzserver = {'node': '/gazebo', 'package': 'gazebo_ros', 'type': 'gzserver', 'params': {},
                'args': ['-e', 'ode', '/w/house.world']}
    read = launchread.parse(document(simulators=[flatsim, gzserver]))
    assert [launchread.world_of(entry) for entry in read['simulators']] == ['/w/office.world',
                                                                            '/w/house.world']
    assert read['simulators'][0]['params'] == {'world_name': '/w/office.world', 'paused': False}


def test_only_plain_short_values_of_a_launchs_parameters_reach_the_grader():
    entry = {'node': '/flatsim', 'package': 'flatsim', 'type': 'simulator', 'args': [],
             'params': {'seed': 3, 'nested': {'a': 1}, 'list': [1], 'long': 'x' * 100000}}
    read = launchread.parse(document(simulators=[entry]))
    assert read['simulators'][0]['params'] == {'seed': 3}


@pytest.mark.parametrize('data', [b'\xff', b'[]', b'{"simulators": 3}',
                                  b'{"simulators": [{"node": 7}]}', b'{"simulators": [1]}',
                                  b'{"simulators": [], "claims": [{"node": []}]}'])
def test_a_document_of_another_shape_is_refused_with_a_reason(data):
    with pytest.raises(launchread.LaunchReadError):
        launchread.parse(data)


def test_a_document_nested_past_its_shape_is_refused_before_it_is_read(monkeypatch):
    """Python's JSON reader recurses a level at a time: a document of 100,000 levels, which the
    sandbox may write, is refused without reading it, not with an error from deep inside it."""
    def no_reading(text):
        raise AssertionError('json.loads was called')
    deep = ('{"simulators": [], "claims": %s}' % ('[' * 100000 + ']' * 100000)).encode()
    monkeypatch.setattr(launchread, 'json', types.SimpleNamespace(loads=no_reading))
    with pytest.raises(launchread.LaunchReadError, match='nested deeper than 8 levels'):
        launchread.parse(deep)


def test_a_node_under_a_simulators_name_that_is_no_simulator_is_a_claim():
    read = launchread.parse(document(claims=[{'node': '/flatsim', 'package': 'ball_chaser',
                                              'type': 'hostile.py'}]))
    assert read['claims'] == [{'node': '/flatsim', 'package': 'ball_chaser', 'type': 'hostile.py'}]
