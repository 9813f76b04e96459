"""Spawning and deleting models: names, and colliders that go with their model."""
import xml.etree.ElementTree as ET

import pytest

from flatsim.authoring.world_writer import world_sdf

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import parse_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation

ROBOT = '''<robot name="bot">
  <link name="base"><collision><geometry><box size="0.4 0.3 0.2"/></geometry></collision>
    <inertial><mass value="5"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>'''

# A world saved with the robot in it: the robot is a plain model with its shape.
WORLD = '''<sdf version="1.6"><world name="w">
  <model name="bot"><pose>0 0 0.1 0 0 0</pose><link name="base">
    <collision name="c"><geometry><box><size>0.4 0.3 0.2</size></box></geometry></collision>
  </link></model>
  <model name="crate"><static>true</static><pose>2 0 0.25 0 0 0</pose><link name="l">
    <collision name="c"><geometry><box><size>0.5 0.5 0.5</size></box></geometry></collision>
  </link></model>
</world></sdf>'''


def solids(sim):
    """Names of the models whose shapes are in physics besides robots: bodies, and one
    entry per static collider."""
    return sorted([handle.name for handle in sim.physics.bodies() if handle.kind == 'body']
                  + ['static'] * sim.physics.static_count())


def test_a_robot_takes_the_place_of_the_saved_model_with_its_name():
    sim = Simulation(parse_world(WORLD))
    shapes = len(sim.scene)
    assert solids(sim) == ['bot', 'static']
    robot = sim.spawn_robot('bot', load_robot(ROBOT), Pose())
    assert sim.models['bot'] is robot
    # The saved copy's body and its one scene shape are gone; the robot's own shapes came.
    assert solids(sim) == ['static']
    assert robot.prim_ids and len(sim.scene) == shapes - 1 + len(robot.prim_ids)
    assert any('replaced by the robot' in str(item) for item in sim.skipped)


def test_a_robot_that_cannot_be_placed_leaves_the_saved_model_with_its_name():
    world = parse_world(WORLD)
    sim = Simulation(world)
    copy = sim.models['bot']
    shapes = len(sim.scene)
    with pytest.raises(FlatsimError, match='beyond the'):
        sim.spawn_robot('bot', load_robot(ROBOT), Pose(1e6, 0.0))
    assert sim.models['bot'] is copy
    assert (solids(sim), len(sim.scene)) == (['bot', 'static'], shapes)
    assert [m.get('name') for m in ET.fromstring(world_sdf(sim, world).text).iter('model')
            if m.get('name') in ('bot', 'crate')] == ['bot', 'crate']
    # Nothing of the refused robot is left in physics to hold the name.
    robot = sim.spawn_robot('bot', load_robot(ROBOT), Pose())
    assert sim.models['bot'] is robot and solids(sim) == ['static']


def test_a_second_robot_with_a_taken_name_is_refused():
    sim = Simulation(parse_world(WORLD))
    sim.spawn_robot('bot', load_robot(ROBOT), Pose())
    with pytest.raises(FlatsimError, match="'bot' already exists"):
        sim.spawn_robot('bot', load_robot(ROBOT), Pose(1.0, 1.0))


def test_deleting_a_static_model_removes_its_colliders():
    sim = Simulation(parse_world(WORLD))
    before = sim.physics.static_count()
    sim.delete_model('crate')
    assert sim.physics.static_count() == before - 1
    assert 'crate' not in sim.models
