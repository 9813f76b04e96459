"""A revolute and a prismatic joint with limits, driven by each kind of ros_control controller.

slider_arm.urdf.xacro: shoulder (revolute about z, -1..1 rad, 20 N*m, 1.5 rad/s)
carries link_a; slide (prismatic along link_a, 0..0.4 m, 50 N, 0.3 m/s)
carries link_b (1 kg). Neither axis works against gravity. Commands beyond
the limits must end at the limits; no joint may pass a position limit or
push harder than its effort limit; and, as in Gazebo, a joint already faster
than its velocity limit gets no effort that would speed it up further (it is
not braked: the shoulder's turn can still fling the slide outwards).
"""
import os

import numpy as np
import pytest

from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation

SLIDER_ARM = os.path.join(os.path.dirname(__file__), 'fixtures', 'robots', 'slider_arm.urdf.xacro')
LOWER = np.array([-1.0, 0.0])
UPPER = np.array([1.0, 0.4])
EFFORT = np.array([20.0, 50.0])
VELOCITY = np.array([1.5, 0.3])


def slider_arm(shoulder, slide, controllers):
    urdf = expand_xacro(SLIDER_ARM, {'shoulder_interface': shoulder, 'slide_interface': slide})
    sim = Simulation()
    robot = sim.spawn_robot('slider_arm', load_robot(urdf, name='slider_arm'), Pose())
    manager = robot.control.manager
    for name, params in controllers.items():
        assert manager.load(name, params), manager.errors
    assert manager.switch(list(controllers), [], 2, sim.time), manager.errors
    assert robot.control.articulation.joints == ['shoulder', 'slide']
    return sim, robot, manager.controllers


def run(sim, robot, seconds):
    """Positions, velocities and applied efforts at every step, as (steps, 2) arrays."""
    articulation = robot.control.articulation
    positions, velocities, efforts = [], [], []
    for _ in range(int(round(seconds / sim.step_size))):
        sim.step()
        positions.append(articulation.position.copy())
        velocities.append(articulation.velocity.copy())
        efforts.append(np.asarray(articulation.effort, dtype=float).copy())
    return np.array(positions), np.array(velocities), np.array(efforts)


def assert_within_limits(positions, velocities, efforts):
    assert (positions >= LOWER - 1e-12).all() and (positions <= UPPER + 1e-12).all()
    assert (np.abs(efforts) <= EFFORT + 1e-9).all()
    too_fast = np.abs(velocities[:-1]) > VELOCITY
    pushing_on = np.sign(efforts[1:]) == np.sign(velocities[:-1])
    assert not (too_fast & pushing_on & (efforts[1:] != 0.0)).any()


def test_effort_position_controllers_stop_at_the_limits_of_commands_beyond_them():
    sim, robot, controllers = slider_arm('Effort', 'Effort', {
        'shoulder_controller': {'type': 'effort_controllers/JointPositionController', 'joint': 'shoulder',
                                'pid': {'p': 50.0, 'd': 5.0}},
        'slide_controller': {'type': 'effort_controllers/JointPositionController', 'joint': 'slide',
                             'pid': {'p': 500.0, 'd': 50.0}},
    })
    # One joint at a time, so that each runs into its own velocity limit on the way.
    controllers['slide_controller'].set_command(0.8)
    positions, velocities, efforts = run(sim, robot, 3.0)
    assert_within_limits(positions, velocities, efforts)
    assert positions[-1][1] == pytest.approx(UPPER[1], abs=1e-3)
    assert np.abs(velocities[:, 1]).max() == pytest.approx(VELOCITY[1], rel=0.1)
    controllers['shoulder_controller'].set_command(2.0)
    positions, velocities, efforts = run(sim, robot, 3.0)
    assert_within_limits(positions, velocities, efforts)
    assert positions[-1] == pytest.approx(UPPER, abs=1e-3)
    assert np.abs(velocities[:, 0]).max() == pytest.approx(VELOCITY[0], rel=0.1)
    controllers['shoulder_controller'].set_command(-2.0)
    controllers['slide_controller'].set_command(-0.5)
    positions, velocities, efforts = run(sim, robot, 4.0)
    assert_within_limits(positions, velocities, efforts)
    assert positions[-1] == pytest.approx(LOWER, abs=1e-3)


def test_position_controllers_move_no_faster_than_the_velocity_limit_and_stop_at_the_limits():
    sim, robot, controllers = slider_arm('Position', 'Position', {
        'shoulder_controller': {'type': 'position_controllers/JointPositionController', 'joint': 'shoulder'},
        'slide_controller': {'type': 'position_controllers/JointPositionController', 'joint': 'slide'},
    })
    controllers['shoulder_controller'].set_command(5.0)
    controllers['slide_controller'].set_command(0.8)
    positions, velocities, efforts = run(sim, robot, 2.0)
    assert (positions >= LOWER - 1e-12).all() and (positions <= UPPER + 1e-12).all()
    steps = np.abs(np.diff(positions, axis=0))
    assert (steps <= VELOCITY * sim.step_size + 1e-12).all()
    assert positions[-1] == pytest.approx(UPPER, abs=1e-9)
    # At the velocity limit, 1 rad takes 1/1.5 s and 0.4 m takes 0.4/0.3 s.
    arrival = np.argmax(positions >= UPPER - 1e-9, axis=0) * sim.step_size
    assert arrival == pytest.approx(UPPER / VELOCITY, abs=2 * sim.step_size)


def test_velocity_controllers_are_held_to_the_velocity_limit_until_the_hard_stop():
    sim, robot, controllers = slider_arm('Velocity', 'Velocity', {
        'shoulder_controller': {'type': 'velocity_controllers/JointVelocityController', 'joint': 'shoulder'},
        'slide_controller': {'type': 'velocity_controllers/JointVelocityController', 'joint': 'slide'},
    })
    controllers['shoulder_controller'].set_command(5.0)
    controllers['slide_controller'].set_command(1.0)
    positions, velocities, efforts = run(sim, robot, 0.3)
    assert velocities[-1] == pytest.approx(VELOCITY, rel=1e-6)
    positions, velocities, efforts = run(sim, robot, 2.0)
    assert_within_limits(positions, velocities, efforts)
    assert positions[-1] == pytest.approx(UPPER, abs=1e-12)
    assert velocities[-1] == pytest.approx([0.0, 0.0], abs=1e-12)
    controllers['shoulder_controller'].set_command(-5.0)
    positions, velocities, efforts = run(sim, robot, 2.0)
    assert_within_limits(positions, velocities, efforts)
    assert positions[-1][0] == pytest.approx(LOWER[0], abs=1e-12)


def test_an_effort_controller_is_held_to_the_effort_limit():
    sim, robot, controllers = slider_arm('Effort', 'Effort', {
        'shoulder_controller': {'type': 'effort_controllers/JointEffortController', 'joint': 'shoulder'},
        'slide_controller': {'type': 'effort_controllers/JointEffortController', 'joint': 'slide'},
    })
    controllers['shoulder_controller'].set_command(-1000.0)
    controllers['slide_controller'].set_command(1000.0)
    positions, velocities, efforts = run(sim, robot, 0.05)
    assert efforts[0] == pytest.approx([-20.0, 50.0])
    positions, velocities, efforts = run(sim, robot, 3.0)
    assert_within_limits(positions, velocities, efforts)
    assert positions[-1] == pytest.approx([LOWER[0], UPPER[1]], abs=1e-12)
