"""Save World As: the running world written back as Gazebo writes it, and read back the same."""
import glob
import math
import os
import xml.etree.ElementTree as ET

import pytest

import sdf_check
from flatsim.authoring.saving import save_text
from flatsim.authoring.world_writer import world_sdf
from flatsim.loading.sdf_world import load_world, parse_sdf_models, parse_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation
from flatsim.world.sim_models import FROM_INSERT, FROM_SDF, FROM_URDF, FROM_WORLD, MAX_WRITTEN_DEPTH, ModelOrigin

HERE = os.path.dirname(os.path.abspath(__file__))
PROJECT_WORLDS = sorted(glob.glob(os.path.join(HERE, '..', '..', 'my_robot', 'worlds', '*.world')))
# Real students' worlds, read only when this machine has them; the tests above use our own.
COMPAT = '/work/shared/compat'
COMPAT_WORLDS = sorted(glob.glob(os.path.join(COMPAT, '**', '*.world'), recursive=True))

# A world with most of what a Gazebo world holds: implicit includes, a light, physics,
# a plugin, gui, a mesh flatsim cannot read, an include that is not on the path, a
# building whose <state> moved a link, a ball the state moved, and a model the state deleted.
WORLD = """<?xml version="1.0" ?>
<sdf version="1.6">
  <world name="house">
    <include><uri>model://ground_plane</uri></include>
    <include><uri>model://sun</uri></include>
    <light name="lamp" type="point"><pose>1 1 2 0 0 0</pose><diffuse>1 1 1 1</diffuse></light>
    <physics type="ode"><max_step_size>0.002</max_step_size><real_time_factor>1</real_time_factor>
      <real_time_update_rate>500</real_time_update_rate></physics>
    <plugin name="welcome" filename="libwelcome.so"><greeting>hello</greeting></plugin>
    <model name="building">
      <static>1</static>
      <pose>1 0 0 0 0 0</pose>
      <link name="Wall_0">
        <pose>0 2 0 0 0 0</pose>
        <collision name="Wall_0_Collision"><pose>0 0 1 0 0 0</pose>
          <geometry><box><size>4 0.15 2</size></box></geometry></collision>
        <visual name="Wall_0_Visual"><pose>0 0 1 0 0 0</pose>
          <geometry><box><size>4 0.15 2</size></box></geometry>
          <material><script><uri>file://media/materials/scripts/gazebo.material</uri>
            <name>Gazebo/Bricks</name></script><ambient>1 1 1 1</ambient></material></visual>
      </link>
      <link name="Wall_1">
        <pose>2 0 0 0 0 1.5707963267948966</pose>
        <collision name="Wall_1_Collision"><pose>0 0 1 0 0 0</pose>
          <geometry><box><size>4 0.15 2</size></box></geometry></collision>
      </link>
    </model>
    <model name="statue">
      <static>1</static><pose>-2 -2 0 0 0 0</pose>
      <link name="link"><visual name="v"><geometry><mesh><uri>model://statue/meshes/statue.dae</uri></mesh>
        </geometry></visual></link>
    </model>
    <include><uri>model://bookshelf</uri><name>shelf</name><pose>-3 0 0 0 0 0</pose></include>
    <model name="white_ball">
      <pose>0 -1 0.1 0 0 0</pose>
      <link name="link">
        <inertial><mass>0.5</mass></inertial>
        <collision name="collision"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
        <visual name="visual"><geometry><sphere><radius>0.1</radius></sphere></geometry>
          <material><ambient>1 1 1 1</ambient><diffuse>1 1 1 1</diffuse><emissive>1 1 1 1</emissive></material>
        </visual>
      </link>
    </model>
    <model name="crate">
      <static>1</static><pose>3 3 0.25 0 0 0</pose>
      <link name="link"><collision name="c"><geometry><box><size>0.5 0.5 0.5</size></box></geometry>
      </collision></link>
    </model>
    <gui fullscreen="0"><camera name="user_camera"><pose>-3 -3 2.5 0 0.5 0.785</pose></camera></gui>
    <state world_name="house">
      <sim_time>12 0</sim_time>
      <model name="building">
        <pose>1 0 0 0 0 0</pose>
        <link name="Wall_0"><pose>1 2.5 0 0 0 0</pose></link>
      </model>
      <model name="white_ball"><pose>0.5 -1.5 0.1 0 0 0</pose></model>
      <deletions><name>crate</name></deletions>
    </state>
  </world>
</sdf>
"""

ROBOT = """<robot name="my_robot">
  <link name="base"><collision><geometry><box size="0.4 0.3 0.2"/></geometry></collision>
    <inertial><mass value="5"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
</robot>"""

CYLINDER = """<sdf version="1.6"><model name="post"><static>true</static><pose>0 0 0.5 0 0 0</pose>
  <link name="link"><collision name="c"><geometry><cylinder><radius>0.2</radius><length>1</length>
  </cylinder></geometry></collision></link></model></sdf>"""


@pytest.fixture
def house(tmp_path, home):
    path = tmp_path / 'house.world'
    path.write_text(WORLD)
    return load_world(str(path))


def poses_by_model(world):
    return {model.name: model.pose for model in world.models}


def assert_same_pose(a, b):
    assert a.matrix() == pytest.approx(b.matrix(), abs=1e-9)


def assert_same_world(before, after, moved=None):
    """after holds before's models, each where moved says or where it was, with the same shapes."""
    moved = moved or {}
    names = {model.name for model in before.models}
    assert names - {'ground_plane'} == {model.name for model in after.models} - {'ground_plane'}
    for model in before.models:
        again = after.model(model.name)
        assert_same_pose(again.pose, moved.get(model.name, model.pose))
        assert [link for link, _ in again.links] == [link for link, _ in model.links]
        for (_, pose), (_, pose_again) in zip(model.links, again.links):
            assert_same_pose(pose_again, pose)
        for geoms, geoms_again in ((model.collisions, again.collisions), (model.visuals, again.visuals)):
            assert [(g.name, g.kind, g.size) for g in geoms] == [(g.name, g.kind, g.size) for g in geoms_again]
            for geom, geom_again in zip(geoms, geoms_again):
                assert_same_pose(geom_again.pose, geom.pose)
                assert geom_again.color == pytest.approx(geom.color)


def move_balls(sim):
    """Roll every ball somewhere else; returns {name: the world pose it should be saved at}."""
    moved = {}
    for index, name in enumerate(sorted(n for n, m in sim.models.items() if m.kind == 'ball')):
        start = sim.models[name].initial_pose
        assert abs(start.roll) < 1e-12 and abs(start.pitch) < 1e-12
        target = Pose(start.x + 1.0 + index, start.y - 0.5, start.z, yaw=start.yaw + 0.3)
        sim.set_model_state(name, target)
        moved[name] = target
    return moved


def reload(text, tmp_path, name='saved.world'):
    path = tmp_path / name
    path.write_text(text)
    return load_world(str(path))


# The checker itself

def test_the_spec_check_refuses_what_sdf_does_not_have():
    if not sdf_check.spec_available('1.6'):
        pytest.skip('the SDF specification (Debian sdformat-sdf) is not installed')
    text = ("<sdf version='1.6'><world name='w'><model name='m'><pose relative='x'>0 0 0 0 0 0</pose>"
            "<link name='l'><bogus/></link></model><wrong/><plugin name='p' filename='f'><any><thing/></any>"
            "</plugin></world></sdf>")
    assert sorted(sdf_check.spec_errors(text)) == [
        "/sdf/world[@name='w']/model[@name='m']/link[@name='l']/bogus: <bogus> is not in SDF 1.6 here",
        "/sdf/world[@name='w']/model[@name='m']/pose: attribute 'relative' is not in SDF 1.6",
        "/sdf/world[@name='w']/wrong: <wrong> is not in SDF 1.6 here"]


def test_the_parser_check_refuses_two_models_of_one_name(tmp_path):
    if not sdf_check.parser_available():
        pytest.skip('libsdformat12 is not installed')
    path = tmp_path / 'twice.world'
    path.write_text("<sdf version='1.6'><world name='w'><model name='a'><link name='l'/></model>"
                    "<model name='a'><link name='l'/></model></world></sdf>")
    assert 'already exists' in sdf_check.parser_errors(str(path))


# Our own world

def test_a_saved_world_reads_back_with_the_same_models_and_poses(house, tmp_path):
    sim = Simulation(house)
    sim.set_model_state('white_ball', Pose(-1.0, 2.0, 0.1, yaw=0.7))
    saved = world_sdf(sim, house)
    again = reload(saved.text, tmp_path)
    assert_same_world(house, again, moved={'white_ball': Pose(-1.0, 2.0, 0.1, yaw=0.7)})
    # The state moved Wall_0 by half a metre; that survives the state being dropped.
    assert dict(again.model('building').links)['Wall_0'].y == pytest.approx(2.5)
    assert again.model('crate') is None and 'crate' not in saved.text
    assert again.ground_plane and again.max_step_size == 0.002 and again.real_time_update_rate == 500
    assert saved.notes == []
    # libsdformat cannot find the bookshelf either; that is all it or the specification finds.
    assert all('Unable to find uri[model://bookshelf]' in problem
               for problem in sdf_check.problems(saved.text, tmp_path))


def test_a_saved_world_keeps_what_flatsim_does_not_simulate(house):
    root = ET.fromstring(world_sdf(Simulation(house), house).text)
    assert root.tag == 'sdf' and root.get('version') == '1.6'
    world = root.find('world')
    assert world.get('name') == 'house' and world.find('state') is None
    assert [light.get('name') for light in world.findall('light')] == ['sun', 'lamp']
    assert world.find("light[@name='sun']/direction") is not None
    assert world.find("model[@name='ground_plane']/link/collision/geometry/plane") is not None
    assert world.find("plugin[@name='welcome']/greeting").text == 'hello'
    assert world.find('gui/camera/pose').text.split()[:2] == ['-3', '-3']
    assert world.find("model[@name='statue']/link/visual/geometry/mesh/uri").text == \
        'model://statue/meshes/statue.dae'
    assert world.find('include/uri').text == 'model://bookshelf'
    assert world.find("model[@name='building']/link[@name='Wall_0']/visual/material/script/name").text == \
        'Gazebo/Bricks'


def test_the_same_things_are_reported_after_a_save(house, tmp_path):
    again = reload(world_sdf(Simulation(house), house).text, tmp_path)
    assert sorted(map(str, again.skipped)) == sorted(map(str, house.skipped))


def test_a_robot_from_urdf_is_left_out_with_a_note(house, tmp_path):
    sim = Simulation(house)
    sim.spawn_robot('my_robot', load_robot(ROBOT), Pose(0.5, 0.5))
    saved = world_sdf(sim, house)
    assert 'my_robot' not in saved.text
    assert saved.notes == ['my_robot is a robot spawned from URDF (the launch file spawns it); left out of '
                           'the world, which must not hold the robot']
    assert reload(saved.text, tmp_path).model('my_robot') is None


def test_spawned_and_inserted_models_are_written_where_they_are(house, tmp_path):
    sim = Simulation(house)
    (post,), _ = parse_sdf_models(CYLINDER)
    post.name = 'post_spawned'
    sim.add_world_model(post, Pose(4, 1, 0, yaw=0.5) * post.pose)
    (dropped,), _ = parse_sdf_models(CYLINDER.replace('name="post"', 'name="post_1"'))
    sim.add_world_model(dropped, Pose(-4, 1) * dropped.pose,
                        origin=ModelOrigin(FROM_INSERT, ET.tostring(dropped.element, encoding='unicode')))
    sim.delete_model('statue')
    assert sim.origins['post_spawned'].kind == FROM_SDF and sim.origins['post_1'].kind == FROM_INSERT
    again = reload(world_sdf(sim, house).text, tmp_path)
    assert_same_pose(again.model('post_spawned').pose, Pose(4, 1, 0.5, yaw=0.5))
    assert_same_pose(again.model('post_1').pose, Pose(-4, 1, 0.5))
    assert again.model('statue') is None


def test_origins_follow_spawns_deletes_and_resets(house):
    sim = Simulation(house)
    assert {name: origin.kind for name, origin in sim.origins.items()} == {
        'building': FROM_WORLD, 'statue': FROM_WORLD, 'white_ball': FROM_WORLD}
    assert ET.fromstring(sim.origins['white_ball'].sdf).get('name') == 'white_ball'
    sim.spawn_robot('my_robot', load_robot(ROBOT), Pose())
    assert sim.origins['my_robot'] == ModelOrigin(FROM_URDF)
    sim.reset_time()
    sim.reset_world()
    assert set(sim.origins) == {'building', 'statue', 'white_ball', 'my_robot'}
    sim.delete_model('white_ball')
    assert set(sim.origins) == set(sim.models)


def test_a_robot_spawned_from_sdf_keeps_its_sdf(tmp_path):
    saved_robot = os.path.join(HERE, 'fixtures', 'worlds', 'saved_robot.world')
    world = load_world(saved_robot)
    (name,) = [model.name for model in world.models if model.robot is not None]
    sim = Simulation()
    robot_model = world.model(name)
    sim.spawn_robot(name, robot_model.robot, robot_model.pose)
    assert sim.origins[name].kind == FROM_SDF and '<plugin' in sim.origins[name].sdf
    again = reload(world_sdf(sim).text, tmp_path)
    assert again.model(name).robot is not None


def test_an_empty_simulation_gives_a_world_gazebo_would_load(tmp_path):
    saved = world_sdf(Simulation())
    world = ET.fromstring(saved.text).find('world')
    assert [(elem.tag, elem.get('name')) for elem in world] == [
        ('light', 'sun'), ('model', 'ground_plane'), ('physics', None)]
    assert len(saved.notes) == 2
    assert sdf_check.problems(saved.text, tmp_path) == []


def test_save_world_as_replaces_the_file(house, tmp_path):
    folder = tmp_path / 'worlds'
    folder.mkdir()
    (folder / 'house.world').write_text('old')
    # As the studio's Save World As writes it (flatsim.studio.editors).
    saved = world_sdf(Simulation(house), house)
    path = save_text([str(tmp_path)], str(folder), 'house.world', saved.text)
    assert path == str(folder / 'house.world') and saved.notes == []
    assert load_world(path).model('white_ball') is not None
    assert os.listdir(folder) == ['house.world']


# The project's worlds and, where this machine has them, students' worlds

def save_and_read_back(path, tmp_path):
    """(world as loaded, as saved with its balls moved and read back, the saved text)."""
    world = load_world(path)
    sim = Simulation(world)
    moved = move_balls(sim)
    saved = world_sdf(sim, world)
    again = reload(saved.text, tmp_path)
    assert_same_world(world, again, moved)
    return world, again, saved.text


@pytest.mark.parametrize('path', PROJECT_WORLDS, ids=os.path.basename)
def test_the_projects_worlds_save_and_read_back_with_moved_balls(path, tmp_path, home):
    _, again, text = save_and_read_back(path, tmp_path)
    assert again.ground_plane
    assert sdf_check.problems(text, tmp_path) == []


@pytest.mark.skipif(not COMPAT_WORLDS, reason='no students\' worlds on this machine')
@pytest.mark.parametrize('path', COMPAT_WORLDS, ids=lambda p: os.path.relpath(p, COMPAT))
def test_students_worlds_save_and_read_back(path, tmp_path, home):
    world, again, text = save_and_read_back(path, tmp_path)
    assert sorted(map(str, again.skipped)) == sorted(
        str(item) for item in world.skipped if not item.subject.startswith('state of'))
    if sdf_check.spec_available(again.sdf_version):
        source_errors = set(sdf_check.spec_errors(open(path).read().lstrip()))
        assert set(sdf_check.spec_errors(text)) <= source_errors


def test_moving_a_ball_keeps_its_height_roll_and_pitch(tmp_path):
    world = parse_world(WORLD.replace('<pose>0 -1 0.1 0 0 0</pose>', '<pose>0 -1 0.1 0.2 0.1 0</pose>')
                        .replace('<model name="white_ball"><pose>0.5 -1.5 0.1 0 0 0</pose></model>', ''))
    sim = Simulation(world)
    sim.set_model_state('white_ball', Pose(2, 3, 0, yaw=math.pi / 2))
    again = reload(world_sdf(sim, world).text, tmp_path)
    ball = again.model('white_ball').pose
    assert (ball.x, ball.y, ball.z) == pytest.approx((2, 3, 0.1))
    start = world.model('white_ball').pose
    expected = Pose(0, 0, 0, yaw=math.pi / 2).matrix()[:3, :3] @ start.matrix()[:3, :3]
    assert ball.matrix()[:3, :3] == pytest.approx(expected, abs=1e-9)


def test_a_model_nested_too_deep_to_write_is_left_out_with_a_note():
    text = '<link name="l"><collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link>'
    for depth in range(2000):
        text = '<model name="m%d">%s</model>' % (depth, text)
    world = parse_world('<sdf version="1.6"><world name="w">%s</world></sdf>' % text, model_paths=[])
    saved = world_sdf(Simulation(world), world)
    assert saved.notes[0] == 'm1999 came with no SDF to write; left out'
    assert 'm1999' not in saved.text


def test_a_plugin_nested_too_deep_to_write_is_left_out_with_a_note():
    """ElementTree writes a Python call per level: 3,000 levels would end Save World As with
    Python's recursion limit."""
    deep = '<plugin name="p" filename="libp.so">%s%s</plugin>' % ('<a>' * 3000, '</a>' * 3000)
    world = parse_world('<sdf version="1.6"><world name="w">%s<light name="sun" type="directional"/>'
                        '</world></sdf>' % deep, model_paths=[])
    saved = world_sdf(Simulation(world), world)
    assert saved.notes[0] == 'a <plugin> nested deeper than %d levels; left out' % MAX_WRITTEN_DEPTH
    assert '<plugin' not in saved.text and '<light name="sun"' in saved.text
