"""A second world launch on a master that already runs one, as with Gazebo.

Some students' ball_chaser.launch includes their world.launch, and their
README says to run `roslaunch ball_chaser ball_chaser.launch` on its own; a
student who follows the course starts world.launch first anyway. With Gazebo
the second gzserver cannot take its port and exits, the second spawn_model is
refused, and the first world runs on with the chaser's nodes driving its robot.

The student's packages are the grader's fixture submission built in an
overlay, as in a student's ~/catkin_ws.
"""
import os
import re
import sys

import pytest

from overlay import Overlay
from rosproc import Probe, RosSystem, run_forked, wait_until

SUBMISSIONS = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, 'catkin_ws', 'src',
                           'chase_tools', 'test', 'fixtures', 'submissions')
sys.path.insert(0, SUBMISSIONS)
import variants  # noqa: E402

REACH_M = 0.45
CHASE_SIM_S = 60.0
WALL_CAP_S = 120.0
GAZEBO_REFUSAL = 'There is probably another Gazebo process running.'
# gzserver's status when it cannot start its server.
SIMULATOR_EXIT = re.compile(r'process has died \[pid \d+, exit code 255, cmd \S+/flatsim/simulator ')


@pytest.fixture(scope='module')
def student_workspace(tmp_path_factory):
    """An overlay holding a student's my_robot and a ball_chaser whose launch includes world.launch."""
    top = tmp_path_factory.mktemp('student')
    path = variants.compose('py_chaser_includes_world', top)
    world = os.path.join(path, 'my_robot', 'launch', 'world.launch')
    with open(world) as stream:
        text = stream.read()
    # No display here; a required rviz would end the launch.
    text, count = re.subn(r'\s*<node name="rviz"[^>]*/>', '', text)
    assert count == 1
    with open(world, 'w') as stream:
        stream.write(text)
    ws = Overlay(top / 'catkin_ws')
    for package in ('my_robot', 'ball_chaser'):
        ws.add(os.path.join(path, package))
    result = ws.build()
    assert result.returncode == 0, result.stdout[-4000:]
    return ws


def chase_reaches_the_ball(graph):
    probe = Probe(graph.master_uri)
    try:
        reached = probe.wait_sim(lambda: probe.gap() <= REACH_M, CHASE_SIM_S, WALL_CAP_S)
        assert reached, 'still %.2f m from the ball after %g s of sim time' % (probe.gap(), CHASE_SIM_S)
    finally:
        probe.close()


def robot_spawned(graph):
    probe = Probe(graph.master_uri)
    try:
        return wait_until(lambda: _has_model(probe, 'my_robot'), WALL_CAP_S)
    finally:
        probe.close()


def _has_model(probe, name):
    try:
        return probe.model_state(name) is not None
    except RuntimeError:
        return False


def test_a_ball_chaser_launch_that_includes_world_launch_joins_the_running_world(student_workspace,
                                                                                tmp_path):
    with RosSystem(tmp_path, env=student_workspace.env()) as ros:
        ros.launch('world', 'my_robot', 'world.launch')
        ros.graph.wait_for_service('/gazebo/get_model_state')
        assert run_forked(robot_spawned, ros.graph), ros.log_tail('world')
        simulator = ros.graph.node_pid('/flatsim')

        ros.launch('chaser', 'ball_chaser', 'ball_chaser.launch')
        ros.graph.wait_for_node('/process_image')

        def refused():
            log = ros.log_tail('chaser', 20000)
            return (SIMULATOR_EXIT.search(log) is not None and 'Spawn service failed. Exiting.' in log)
        assert wait_until(refused, WALL_CAP_S), ros.log_tail('chaser')
        log = ros.log_tail('chaser', 20000)
        assert ('[Err] [flatsim] EXCEPTION: Unable to start server[/flatsim is already running '
                'on the ROS master' in log), log
        assert GAZEBO_REFUSAL in log
        assert 'Spawn status: SpawnModel: Failure - entity already exists.' in log
        # The first world, its simulator and its launch run on; so does the second launch.
        assert ros.alive('world') and ros.alive('chaser'), ros.log_tail('world')
        assert ros.graph.node_pid('/flatsim') == simulator
        # The chaser's nodes drive the first world's robot to its ball.
        run_forked(chase_reaches_the_ball, ros.graph)
        assert ros.alive('world') and ros.alive('chaser')


def test_a_second_my_robot_world_launch_ends_and_leaves_the_first_world_running(tmp_path):
    """my_robot's world.launch makes flatsim required: the second launch ends with its flatsim."""
    with RosSystem(tmp_path) as ros:
        world = ('my_robot', 'world.launch', 'gui:=false')
        ros.launch('world', *world)
        ros.graph.wait_for_service('/gazebo/get_model_state')
        assert run_forked(robot_spawned, ros.graph), ros.log_tail('world')
        simulator = ros.graph.node_pid('/flatsim')
        ros.launch('second', *world)
        assert ros.wait_exit('second', WALL_CAP_S), ros.log_tail('second')
        log = ros.log_tail('second', 20000)
        assert SIMULATOR_EXIT.search(log) and GAZEBO_REFUSAL in log, log
        assert ros.alive('world') and ros.graph.node_pid('/flatsim') == simulator
        # As docs/simulator.md says: the second launch's robot_state_publisher took the name, and went.
        assert ros.graph.node_pid('/robot_state_publisher') is None
