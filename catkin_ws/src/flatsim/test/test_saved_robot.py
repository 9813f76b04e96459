"""A robot saved inside a world file runs as if spawned from its URDF, without ROS."""
import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from flatsim.authoring.world_writer import world_sdf
from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world, parse_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation
from test_sim_spawn import ROBOT

WORLD = os.path.join(os.path.dirname(__file__), 'fixtures', 'worlds', 'saved_robot.world')
WALL_FACE_X = 3.4


@pytest.fixture
def sim():
    return Simulation(load_world(WORLD))


def run(sim, seconds):
    for _ in range(int(round(seconds / sim.step_size))):
        sim.step()


def test_the_saved_model_reads_as_the_robot_it_was_spawned_as():
    world = load_world(WORLD)
    spec = world.model('saved_bot').robot
    assert spec is not None
    assert (spec.drive.left_joints, spec.drive.right_joints) == (['left_wheel_hinge'],
                                                                 ['right_wheel_hinge'])
    assert spec.drive.command_topic == '/cmd_vel' and spec.drive.wheel_separation == 0.3
    # SDF's unlimited revolute hinge is URDF's continuous joint, its axis in the child's frame.
    hinge = spec.joints['left_wheel_hinge']
    assert hinge.kind == 'continuous' and hinge.axis == pytest.approx((0.0, 1.0, 0.0))
    assert hinge.origin.y == pytest.approx(0.15) and hinge.origin.z == pytest.approx(0.1)
    camera, = spec.cameras
    assert (camera.image_topic, camera.width, camera.link) == ('/camera/rgb/image_raw', 64,
                                                               'robot_footprint')
    laser, = spec.lasers
    assert (laser.topic, laser.samples, laser.pose.x) == ('/scan', 181, pytest.approx(0.15))
    # Nothing is reported as ignored: the sensors and plugins run.
    assert not [s for s in world.skipped if 'saved_bot' in str(s)], world.skipped


def test_it_drives_and_its_lidar_and_camera_see_the_world(sim):
    robot = sim.models['saved_bot']
    assert robot.kind == 'robot' and robot.saved
    assert sim.model_pose('saved_bot').x == pytest.approx(0.5)   # the state block's pose
    laser = next(slot for slot in robot.sensors if slot.kind == 'laser')
    ranges = np.asarray(sim.sense(laser))
    assert ranges[90] == pytest.approx(WALL_FACE_X - 0.5 - 0.15, abs=0.02)
    camera = next(slot for slot in robot.sensors if slot.kind == 'camera')
    assert np.asarray(sim.sense(camera)).shape == (48, 64, 3)
    robot.drive.set_command(0.5, 0.0)
    run(sim, 1.0)
    pose = sim.model_pose('saved_bot')
    # 0.5 m/s for 1 s, less the spin-up the plugin's torque allows; straight ahead.
    assert 0.85 < pose.x < 1.0 and abs(pose.y) < 0.01
    assert np.asarray(sim.sense(laser))[90] == pytest.approx(WALL_FACE_X - pose.x - 0.15, abs=0.02)


def test_a_robot_spawned_under_its_name_replaces_the_saved_copy(sim, my_robot_spec):
    robot = sim.spawn_robot('saved_bot', my_robot_spec, Pose(-1.0, 0.0, 0.0))
    assert sim.models['saved_bot'] is robot and not robot.saved
    assert sim.model_pose('saved_bot').x == pytest.approx(-1.0)
    assert 'replaced by the robot spawned under that name' in str(sim.skipped[-1])
    with pytest.raises(FlatsimError, match='already exists'):
        sim.spawn_robot('saved_bot', my_robot_spec, Pose())


# Read without complaint, refused only when it is put into physics: more than flatsim simulates.
TOO_HEAVY = ROBOT.replace('<mass value="5"/>', '<mass value="1e12"/>')


@pytest.mark.parametrize('spec, pose, refusal', [
    (TOO_HEAVY, Pose(-1.0, 0.0, 0.0), 'mass 1e\\+12 kg is outside'),
    (ROBOT, Pose(1e6, 0.0, 0.0), 'beyond the'),
], ids=['too heavy', 'placed too far'])
def test_a_spawn_that_fails_leaves_the_saved_copy_running_where_it_was(spec, pose, refusal):
    world = load_world(WORLD)
    sim = Simulation(world)
    copy = sim.models['saved_bot']
    copy.drive.set_command(0.5, 0.0)
    run(sim, 0.5)
    before = sim.model_pose('saved_bot')
    assert before.x > 0.6
    with pytest.raises(FlatsimError, match=refusal):
        sim.spawn_robot('saved_bot', load_robot(spec, name='saved_bot'), pose)
    assert sim.models['saved_bot'] is copy and copy.saved
    assert sim.model_pose('saved_bot') == before
    assert not any('replaced' in str(item) for item in sim.skipped)
    # Its body is back in physics: it still drives, and a spawn that fits still replaces it.
    run(sim, 0.2)
    assert sim.model_pose('saved_bot').x > before.x + 0.05
    moved = sim.model_pose('saved_bot')
    saved = ET.fromstring(world_sdf(sim, world).text)
    model, = [m for m in saved.iter('model') if m.get('name') == 'saved_bot']
    x, y = (float(v) for v in model.findtext('pose').split()[:2])
    assert (x, y) == (pytest.approx(moved.x, abs=1e-6), pytest.approx(moved.y, abs=1e-6))
    robot = sim.spawn_robot('saved_bot', load_robot(ROBOT, name='saved_bot'), Pose(-1.0, 0.0, 0.0))
    assert sim.models['saved_bot'] is robot and sim.model_pose('saved_bot').x == pytest.approx(-1.0)


def test_a_saved_robot_that_is_no_tree_of_links_is_held_still_with_a_reason():
    with open(WORLD) as handle:
        text = handle.read()
    # The right wheel's hinge gone: two links without a parent, which no URDF can say.
    start = text.index('<joint name="right_wheel_hinge"')
    text = text[:start] + text[text.index('</joint>', start) + len('</joint>'):]
    world = parse_world(text)
    assert world.model('saved_bot').robot is None
    reasons = [str(s) for s in world.skipped if s.subject == 'saved_bot']
    assert any('cannot run' in r and 'held still' in r for r in reasons), world.skipped
    sim = Simulation(world)
    assert sim.models['saved_bot'].kind == 'static'


def test_static_models_and_models_without_sensors_or_plugins_stay_plain_models():
    world = parse_world('''<sdf version="1.6"><world name="w">
      <model name="camera_post"><static>1</static><link name="l">
        <sensor name="c" type="camera"><camera><image><width>8</width><height>8</height></image>
        </camera></sensor></link></model>
      <model name="cart"><link name="a"><collision name="c"><geometry><box><size>1 1 1</size>
        </box></geometry></collision></link></model>
    </world></sdf>''')
    assert world.model('camera_post').robot is None and world.model('cart').robot is None
    assert math.isclose(world.model('cart').mass, 1.0)


def test_inspect_describes_the_saved_robot(capsys):
    from flatsim.inspect_cli import main
    assert main(['--world', WORLD]) == 0
    out = capsys.readouterr().out
    assert 'robot saved_bot (saved in the world file)' in out
    assert 'laser hokuyo on robot_footprint: 181 beams' in out and '-> /scan' in out
