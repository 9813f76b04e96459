"""Ground that robots drive on, and models that robots and balls push, in the pure Simulation.

The house of fixtures/worlds/building_floor.world is what Gazebo's Building
Editor saves once a floor is added: four walls on a floor slab, 17 x 10.5 x
0.1 m from z 0 to 0.1. In Gazebo the robot stands and drives on the slab,
the ball rests on it, and a 1 kg box in the robot's way is pushed along.
"""
import math
import pathlib

import numpy as np
import pymunk
import pytest

from flatsim.loading.config import LaserConfig
from flatsim.loading.sdf_world import load_world, parse_world
from flatsim.pose import Pose
from flatsim.sensors.lidar import Lidar
from flatsim.world.sim import Simulation

BUILDING = pathlib.Path(__file__).parent / 'fixtures' / 'worlds' / 'building_floor.world'
FLOOR_TOP = 0.1
# The highest slab robots drive onto (docs/simulator.md, Ground).
MAX_STEP_HEIGHT = 0.1
FLOOR_RGB = (204, 153, 76)      # the slab's diffuse 0.8 0.6 0.3, fully lit


def run(sim, seconds):
    for _ in range(int(round(seconds / sim.step_size))):
        sim.step()


def static_collider_at(sim, x, y):
    hit = sim.physics.space.point_query_nearest((x, y), 0.0, pymunk.ShapeFilter())
    return hit is not None and hit.shape.body is sim.physics.space.static_body


def slab_world(top, bottom=0.0, name='slab', x=2.0):
    """A static 2 x 2 m slab from z = bottom to z = top, centred at (x, 0)."""
    return '''<sdf version="1.6"><world name="w">
  <model name="{name}"><static>1</static><pose>{x} 0 0 0 0 0</pose><link name="l">
    <collision name="c"><pose>0 0 {z} 0 0 0</pose>
      <geometry><box><size>2 2 {h}</size></box></geometry></collision>
    <visual name="v"><pose>0 0 {z} 0 0 0</pose>
      <geometry><box><size>2 2 {h}</size></box></geometry></visual>
  </link></model>
</world></sdf>'''.format(name=name, x=x, z=(top + bottom) / 2, h=top - bottom)


def lidar(z_range=10.0):
    return Lidar(LaserConfig(samples=3, min_angle=-0.1, max_angle=0.1, range_min=0.05,
                             range_max=z_range))


# -- ground ------------------------------------------------------------------------------

def test_the_building_floor_is_ground_and_only_its_walls_are_obstacles():
    sim = Simulation(load_world(str(BUILDING)))
    assert not static_collider_at(sim, 0.0, 0.0)
    assert not static_collider_at(sim, 6.0, -3.0)
    assert static_collider_at(sim, 0.0, 5.175)      # a wall
    assert static_collider_at(sim, 8.575, 0.0)
    assert sim.physics.static_count() == 4
    assert sim.ground_height(0.0, 0.0) == pytest.approx(FLOOR_TOP)
    assert sim.ground_height(9.0, 0.0) == 0.0       # outside the house


def test_the_robot_drives_on_the_floor_and_stands_on_its_top(my_robot_spec):
    sim = Simulation(load_world(str(BUILDING)))
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(-2.0, -2.0, 0.0))
    assert sim.model_pose('my_robot').z == pytest.approx(FLOOR_TOP)
    robot.drive.set_command(0.5, 0.0)
    run(sim, 2.0)
    assert sim.model_pose('my_robot').x > -1.3       # 0.7 m on, the drive's ramp taken
    # The ball rests on the floor's top, its centre a radius above it.
    assert sim.model_pose('white_ball').z == pytest.approx(FLOOR_TOP + 0.1)
    assert sim.model_pose('unit_box').z == pytest.approx(FLOOR_TOP + 0.5)


def test_the_camera_sees_the_floor_and_the_ball_on_it(my_robot_spec):
    sim = Simulation(load_world(str(BUILDING)))
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(0.0, 0.0, 0.0))
    camera = next(slot for slot in robot.sensors if slot.kind == 'camera')
    assert sim.sensor_pose(camera).z == pytest.approx(FLOOR_TOP + 0.11)
    image = sim.sense(camera)
    height, width, _ = image.shape
    # Below the horizon, the floor in the slab's colour, not the ground's grey.
    assert tuple(image[height - 1, width // 2]) == FLOOR_RGB
    assert tuple(image[height * 3 // 4, width // 4]) == FLOOR_RGB
    # The ball (white, 3 m ahead, its centre at the camera's height) in full, in the middle.
    white = np.argwhere(np.all(image == 255, axis=2))
    rows, columns = white[:, 0], white[:, 1]
    focal = width / 2 / math.tan(camera.config.hfov / 2)
    diameter = 2 * focal * 0.1 / math.sqrt((3.0 - 0.255) ** 2 - 0.1 ** 2)
    assert columns.max() - columns.min() + 1 == pytest.approx(diameter, abs=2)
    assert rows.max() - rows.min() + 1 == pytest.approx(diameter, abs=2)
    assert (rows.min() + rows.max()) / 2 == pytest.approx((height - 1) / 2 + focal * 0.01 / 2.745, abs=1.5)


def test_a_lidar_above_the_slab_does_not_see_it_and_one_below_its_top_does():
    sim = Simulation(parse_world(slab_world(0.08)))
    beams = lidar()
    # From beside the slab, 0.5 m from its near edge at x = 1.
    assert np.all(np.isinf(beams.scan(sim.scene, 0.5, 0.0, 0.2, 0.0)))
    assert beams.scan(sim.scene, 0.5, 0.0, 0.05, 0.0)[1] == pytest.approx(0.5, abs=1e-4)


def test_a_thin_slab_is_ground_and_a_higher_or_raised_one_an_obstacle(my_robot_spec):
    for top, bottom, ground in ((MAX_STEP_HEIGHT, 0.0, True), (0.03, -0.2, True),
                                (MAX_STEP_HEIGHT + 0.02, 0.0, False), (0.1, 0.05, False)):
        sim = Simulation(parse_world(slab_world(top, bottom)))
        assert static_collider_at(sim, 2.0, 0.0) is not ground, (top, bottom)
        robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(0.0, 0.0, 0.0))
        robot.drive.set_command(0.5, 0.0)
        run(sim, 4.0)
        # Driving 2 m: onto the slab when it is ground, against its edge at x = 1 when not.
        assert (sim.model_pose('my_robot').x > 1.5) is ground, (top, bottom)


# -- bodies ------------------------------------------------------------------------------

def test_the_robot_pushes_a_unit_box_out_of_its_way(my_robot_spec):
    sim = Simulation(load_world(str(BUILDING)))
    assert sim.models['unit_box'].kind == 'body'
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(-6.0, 3.0, 0.0))
    robot.drive.set_command(0.5, 0.0)
    run(sim, 4.0)
    box = sim.model_pose('unit_box')
    robot_x = sim.model_pose('my_robot').x
    assert robot_x > -4.8                   # it went on past where the box's near face stood
    assert box.x > -4.0 + 0.5
    # The box stays ahead of the robot: its near face (0.5 m back) is at the robot's front.
    assert box.x - 0.5 > robot_x
    assert abs(box.y - 3.0) < 0.3
    assert box.z == pytest.approx(FLOOR_TOP + 0.5)


def test_a_box_knocked_by_the_ball_slides_a_little_and_stops():
    sim = Simulation(load_world(str(BUILDING)))
    sim.set_model_state('white_ball', Pose(-6.0, 3.0, 0.2), twist=(3.0, 0.0, 0.0))
    run(sim, 2.0)
    box = sim.model_pose('unit_box')
    vx, vy, _ = sim.model_twist('unit_box')
    # 0.5 kg at 3 m/s into 1 kg: the box starts at about 1 to 1.2 m/s and friction
    # (mu 1, g 9.8) stops it within 0.04 to 0.08 m.
    assert 0.03 < box.x + 4.0 < 0.1
    assert math.hypot(vx, vy) < 1e-3
    assert sim.model_pose('white_ball').x < box.x - 0.5


def test_a_heavier_box_slides_less_and_the_scene_follows_it():
    light = Simulation(load_world(str(BUILDING)))
    heavy_world = load_world(str(BUILDING))
    heavy_world.model('unit_box').mass = 5.0
    heavy_world.model('unit_box').inertials = [(5.0, 0.83, 0.0, 0.0, 0.0)]
    heavy = Simulation(heavy_world)
    for sim in (light, heavy):
        sim.set_model_state('unit_box', Pose(-4.0, 3.0, 0.6), twist=(1.0, 0.0, 0.0))
        run(sim, 1.0)
    # Coulomb friction brakes any mass at mu g: both slide 1 / (2 * 9.8) = 0.051 m.
    assert light.model_pose('unit_box').x + 4.0 == pytest.approx(0.051, abs=0.005)
    assert heavy.model_pose('unit_box').x + 4.0 == pytest.approx(0.051, abs=0.005)
    light.sync_moving_prims()
    box_prims = [light.scene.prim(i) for i in light.models['unit_box'].prim_ids]
    assert all(prim.x == pytest.approx(light.model_pose('unit_box').x) for prim in box_prims)
    assert all(prim.z_min == pytest.approx(FLOOR_TOP) for prim in box_prims)


JOINTED = '''<sdf version="1.6"><world name="w">
  <model name="door"><pose>2 0 0 0 0 0</pose>
    <link name="frame"><collision name="c"><pose>0 0 0.5 0 0 0</pose>
      <geometry><box><size>0.2 2 1</size></box></geometry></collision></link>
    <link name="leaf"><pose>0.3 0 0 0 0 0</pose><collision name="c"><pose>0 0 0.5 0 0 0</pose>
      <geometry><box><size>0.1 1 1</size></box></geometry></collision></link>
    <joint name="hinge" type="revolute"><parent>frame</parent><child>leaf</child>
      <axis><xyz>0 0 1</xyz></axis></joint>
  </model>
</world></sdf>'''


def test_a_jointed_model_is_held_still_says_why_and_is_still_moved_by_hand(my_robot_spec):
    world = parse_world(JOINTED)
    reasons = [item.reason for item in world.skipped if item.subject == 'door']
    assert len(reasons) == 1 and 'held still' in reasons[0] and 'joint' in reasons[0]
    assert 'set_model_state' in reasons[0]
    sim = Simulation(world)
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(0.0, 0.0, 0.0))
    robot.drive.set_command(0.5, 0.0)
    run(sim, 4.0)
    assert sim.model_pose('door').x == 2.0
    assert sim.model_pose('my_robot').x < 1.9 - 0.2
    sim.set_model_state('door', Pose(2.0, 5.0, 0.0))
    assert static_collider_at(sim, 2.0, 5.0) and not static_collider_at(sim, 2.0, 0.0)


def test_a_static_slab_moved_by_hand_takes_its_ground_along(my_robot_spec):
    sim = Simulation(parse_world(slab_world(0.08)))
    assert sim.ground_height(2.0, 0.0) == pytest.approx(0.08)
    sim.set_model_state('slab', Pose(-3.0, 0.0, 0.0))
    assert sim.ground_height(2.0, 0.0) == 0.0
    assert sim.ground_height(-3.0, 0.0) == pytest.approx(0.08)
    robot = sim.spawn_robot('my_robot', my_robot_spec, Pose(-3.0, 0.0, 0.0))
    assert sim.model_pose('my_robot').z == pytest.approx(0.08)
    slab = sim.scene.prim(sim.models['slab'].prim_ids[0])
    assert (slab.x, slab.y) == pytest.approx((-3.0, 0.0))
    assert robot is sim.models['my_robot']


def _crate(name, x, z):
    return ('<model name="%s"><pose>%g 0 %g 0 0 0</pose><link name="l"><collision name="c">'
            '<geometry><box><size>0.2 0.2 0.2</size></box></geometry></collision></link></model>'
            % (name, x, z))


def test_bodies_meet_only_where_their_heights_overlap():
    # A crate on a crate, half off it, and one beside the lower crate at its height.
    sim = Simulation(parse_world('<sdf version="1.6"><world name="w">%s%s%s</world></sdf>'
                                 % (_crate('low', 0.0, 0.1), _crate('high', 0.05, 0.3),
                                    _crate('beside', 0.5, 0.1))))
    run(sim, 0.5)
    assert sim.model_pose('low').x == 0.0 and sim.model_pose('high').x == 0.05
    # The lower crate slides under the upper one and into the one beside it.
    sim.set_model_state('low', Pose(0.0, 0.0, 0.1), twist=(3.0, 0.0, 0.0))   # slides 0.46 m
    run(sim, 1.0)
    assert sim.model_pose('high').x == pytest.approx(0.05, abs=1e-6)
    assert sim.model_pose('beside').x > 0.5 + 0.01
