"""The Model Editor's files: the course's my_ball, inertia, checks, and the ball in a world and a camera."""
import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import sdf_check
from flatsim.authoring import model_writer as mw
from flatsim.authoring.world_writer import world_sdf
from flatsim.errors import AuthoringError
from flatsim.loading.config import CameraConfig
from flatsim.loading.model_path import list_models
from flatsim.loading.sdf_world import load_world, parse_sdf_models, white_balls
from flatsim.pose import Pose
from flatsim.sensors.camera import PinholeCamera
from flatsim.world.sim import Simulation

WHITE = (1.0, 1.0, 1.0, 1.0)


def save(design, allowed_folders, folder):
    """The design's model folder, written as the studio's save_model writes it (flatsim.studio.editors)."""
    return mw.save_model_files(design.name, mw.model_config(design), mw.model_sdf(design),
                               allowed_folders, folder)

# What Gazebo 11's save dialog wrote for a student's ball, with only the name changed.
MY_BALL_CONFIG = """<?xml version="1.0" ?>
<model>
    <name>my_ball</name>
    <version>1.0</version>
    <sdf version="1.7">model.sdf</sdf>
    <author>
        <name></name>
        <email></email>
    </author>
    <description></description>
</model>
"""


def my_ball():
    """The course's ball: a sphere of radius 0.1, Ambient, Diffuse, Specular and Emissive all 1."""
    return mw.ModelDesign('my_ball', [mw.LinkDesign([mw.Shape('sphere', (0.1,),
                                                              material=mw.Material(WHITE, WHITE, WHITE, WHITE))])])


def test_my_ball_config_is_what_gazebo_writes():
    assert mw.model_config(my_ball()) == MY_BALL_CONFIG


def test_my_ball_sdf_has_the_sphere_in_visual_and_collision_and_white_colours(tmp_path):
    text = mw.model_sdf(my_ball())
    root = ET.fromstring(text)
    assert root.get('version') == '1.7'
    model = root.find('model')
    assert model.get('name') == 'my_ball' and model.findtext('static') == '0'
    link = model.find('link')
    assert link.get('name') == 'link'
    assert link.findtext('visual/geometry/sphere/radius') == '0.1'
    assert link.findtext('collision/geometry/sphere/radius') == '0.1'
    for tag in ('ambient', 'diffuse', 'specular', 'emissive'):
        assert link.findtext('visual/material/' + tag) == '1 1 1 1'
    assert link.findtext('pose') == '0 0 0.1 0 0 0'
    assert float(link.findtext('inertial/inertia/ixx')) == pytest.approx(0.4 * 0.1 ** 2)
    assert sdf_check.problems(text, tmp_path) == []


def test_my_ball_saved_inserted_and_seen_as_the_white_ball(home, tmp_path):
    """Save as my_ball, find it under Insert, drop it in a world, see it pure white, save the world."""
    models = os.path.join(home, '.gazebo', 'models')
    os.makedirs(models)
    folder = save(my_ball(), [home], models)
    assert folder == os.path.join(models, 'my_ball')
    assert sorted(os.listdir(folder)) == ['model.config', 'model.sdf']
    assert [(m.name, m.problem) for m in list_models() if m.uri == 'model://my_ball'] == [('my_ball', '')]

    world_file = tmp_path / 'room.world'
    world_file.write_text('<sdf version="1.6"><world name="default">'
                          '<include><uri>model://ground_plane</uri></include>'
                          '<include><uri>model://my_ball</uri><pose>2 1 0 0 0 0</pose></include>'
                          '</world></sdf>')
    world = load_world(str(world_file))
    assert [ball.name for ball in white_balls(world)] == ['my_ball'] and not world.skipped
    sim = Simulation(world)
    assert sim.models['my_ball'].kind == 'ball'
    camera = PinholeCamera(CameraConfig(width=64, height=48, hfov=1.0))
    image = camera.render(sim.scene, 1.0, 1.0, 0.1, 0.0)
    assert tuple(image[24, 32]) == (255, 255, 255)
    assert (image == 255).all(axis=2).sum() < image.shape[0] * image.shape[1] / 4

    sim.set_model_state('my_ball', Pose(3.0, -1.0, 0.1))
    saved = tmp_path / 'saved.world'
    saved.write_text(world_sdf(sim, world).text)
    again = load_world(str(saved))
    (ball,) = white_balls(again)
    assert (ball.name, ball.pose.x, ball.pose.y, ball.pose.z) == ('my_ball', 3.0, -1.0, 0.0)
    assert ball.visuals[0].pose.z == pytest.approx(0.1)


def test_a_spawned_model_sdf_loads_as_written():
    design = mw.ModelDesign('table', [
        mw.LinkDesign([mw.Shape('box', (1.0, 0.6, 0.05), Pose(0, 0, 0.7)),
                       mw.Shape('cylinder', (0.03, 0.7), Pose(0.4, 0.25, 0.35))], mass=10.0)], static=True)
    (model,), skipped = parse_sdf_models(mw.model_sdf(design))
    assert not skipped and model.static and model.mass == 10.0
    assert [(geom.name, geom.kind, geom.size) for geom in model.collisions] == [
        ('collision', 'box', (1.0, 0.6, 0.05)), ('collision_1', 'cylinder', (0.03, 0.7))]
    assert [geom.name for geom in model.visuals] == ['visual', 'visual_1']
    top, leg = model.collisions
    assert (top.pose.z, leg.pose.x, leg.pose.z) == pytest.approx((0.7 + 0.0, 0.4, 0.35))


def test_inertia_of_one_shape_is_the_textbook_one():
    box = mw.LinkDesign([mw.Shape('box', (1.0, 2.0, 3.0))], mass=12.0)
    assert np.diag(mw.link_inertia(box)) == pytest.approx([13.0, 10.0, 5.0])
    cylinder = mw.LinkDesign([mw.Shape('cylinder', (0.5, 2.0))], mass=4.0)
    assert np.diag(mw.link_inertia(cylinder)) == pytest.approx([4 * (0.75 + 4) / 12, 4 * (0.75 + 4) / 12, 0.5])


def test_inertia_of_two_shapes_shares_the_mass_by_volume_and_moves_them():
    link = mw.LinkDesign([mw.Shape('sphere', (0.1,), Pose(1, 0, 0)), mw.Shape('sphere', (0.1,), Pose(-1, 0, 0))],
                         mass=2.0)
    inertia = mw.link_inertia(link)
    own = 0.4 * 1.0 * 0.01
    assert np.diag(inertia) == pytest.approx([2 * own, 2 * own + 2 * 1.0, 2 * own + 2 * 1.0])


def test_a_link_stands_its_lowest_shape_on_the_floor():
    assert mw.link_pose(mw.LinkDesign([mw.Shape('box', (1, 1, 1))])).z == pytest.approx(0.5)
    on_its_side = mw.Shape('cylinder', (0.2, 1.0), Pose(roll=math.pi / 2))
    assert mw.link_pose(mw.LinkDesign([on_its_side])).z == pytest.approx(0.2)
    assert mw.link_pose(mw.LinkDesign([on_its_side], pose=Pose(z=3))).z == 3


@pytest.mark.parametrize('change, message', [
    (lambda d: setattr(d, 'name', ''), 'needs a name'),
    (lambda d: setattr(d, 'name', '../evil'), "may not hold '/'"),
    (lambda d: setattr(d, 'links', []), 'has no link'),
    (lambda d: d.links.append(mw.LinkDesign([mw.Shape('box', (1, 1, 1))])), 'two links named link'),
    (lambda d: setattr(d.links[0], 'mass', 0.0), 'mass must be a positive number'),
    (lambda d: setattr(d.links[0], 'shapes', []), 'has no shape'),
    (lambda d: setattr(d.links[0].shapes[0], 'kind', 'cone'), 'box, sphere or cylinder'),
    (lambda d: setattr(d.links[0].shapes[0], 'size', (0.0,)), 'size must be 1 positive numbers'),
    (lambda d: setattr(d.links[0].shapes[0], 'size', (float('nan'),)), 'size must be 1 positive numbers'),
    (lambda d: setattr(d.links[0].shapes[0], 'size', (-0.1,)), 'size must be 1 positive numbers'),
    (lambda d: setattr(d.links[0].shapes[0], 'pose', Pose(float('inf'))), 'pose must be finite'),
    (lambda d: setattr(d.links[0].shapes[0].material, 'emissive', (1, 1, 2, 1)), 'emissive must be four'),
])
def test_a_bad_design_gets_a_clear_error_and_writes_nothing(change, message, tmp_path):
    design = my_ball()
    change(design)
    with pytest.raises(AuthoringError, match=message.replace('(', r'\(')):
        save(design, [str(tmp_path)], str(tmp_path))
    assert os.listdir(tmp_path) == []


def test_a_model_name_with_spaces_gets_gazebos_folder_name(tmp_path):
    design = my_ball()
    design.name = 'white ball'
    assert save(design, [str(tmp_path)], str(tmp_path)) == str(tmp_path / 'white_ball')
    assert ET.parse(str(tmp_path / 'white_ball' / 'model.config')).findtext('name') == 'white ball'


def test_a_save_that_fails_part_way_leaves_the_old_model_as_it_was(tmp_path):
    models = str(tmp_path)
    folder = save(mw.ModelDesign('crate', [mw.LinkDesign([mw.Shape('box', (1, 1, 1))])]),
                           [models], models)
    old = {name: open(os.path.join(folder, name)).read() for name in ('model.config', 'model.sdf')}
    os.makedirs(os.path.join(folder, 'meshes'))
    with open(os.path.join(folder, 'meshes', 'crate.dae'), 'w') as mesh:
        mesh.write('a mesh')
    # model.config goes first and would be written; model.sdf cannot be (no UTF-8 for it).
    with pytest.raises(AuthoringError) as refused:
        mw.save_model_files('crate', '<model>new</model>', '<sdf>\ud800</sdf>', [models], models)
    assert {name: open(os.path.join(folder, name)).read() for name in old} == old
    assert 'model.sdf' in str(refused.value) and str(refused.value).endswith('the folder there is unchanged')
    assert sorted(os.listdir(models)) == ['crate']
    # A save that succeeds replaces both files and keeps what else the folder held.
    mw.save_model_files('crate', '<model>new</model>', '<sdf>new</sdf>', [models], models)
    assert open(os.path.join(folder, 'model.config')).read() == '<model>new</model>'
    assert open(os.path.join(folder, 'meshes', 'crate.dae')).read() == 'a mesh'
    assert sorted(os.listdir(models)) == ['crate']
