import math
import os

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from flatsim.errors import ModelFileError
from flatsim.loading.materials import BELOW_WHITE, GAZEBO_MATERIALS, resolve_visual_color
from flatsim.loading.sdf_world import find_balls, load_world, parse_sdf_models, parse_world, white_balls
from flatsim.pose import Pose

WORLDS = os.path.join(os.path.dirname(__file__), 'fixtures', 'worlds')
HALF_PI = math.pi / 2


def world(name):
    return load_world(os.path.join(WORLDS, name))


def geom(geoms, name):
    matches = [g for g in geoms if g.name == name]
    assert len(matches) == 1, [g.name for g in geoms]
    return matches[0]


def assert_pose(pose, x, y, z, roll=0.0, pitch=0.0, yaw=0.0):
    expected = Pose(x, y, z, roll, pitch, yaw).matrix()
    np.testing.assert_allclose(pose.matrix(), expected, atol=1e-9)


def skipped_subjects(spec):
    return [s.subject for s in spec.skipped]


def skip_for(spec, subject_part):
    matches = [s for s in spec.skipped if subject_part in s.subject]
    assert len(matches) == 1, spec.skipped
    return matches[0]


# Composition of model, link and shape poses

def test_rotated_model_with_offset_link_composes_poses():
    spec = world('composition.world')
    hall = spec.model('hall')
    assert hall.static
    assert_pose(hall.pose, 1, 2, 0, yaw=HALF_PI)
    wall = geom(hall.collisions, 'Wall_0_Collision')
    assert wall.kind == 'box' and wall.size == (2.0, 0.15, 2.5)
    assert wall.link == 'Wall_0'
    assert_pose(wall.pose, 0.5, 0, 1.25)
    assert_pose(hall.pose * wall.pose, 1, 2.5, 1.25, yaw=HALF_PI)


def test_rotated_link_carries_its_shape_offset():
    hall = world('composition.world').model('hall')
    assert_pose(geom(hall.collisions, 'Wall_1_Collision').pose, 1, 1, 0, yaw=HALF_PI)


def test_nested_model_is_flattened_into_its_parent():
    cart = world('composition.world').model('cart')
    basket = geom(cart.visuals, 'basket_visual')
    assert basket.link == 'basket::link'
    assert_pose(basket.pose, -1, 1, 0, yaw=math.pi)


def test_mass_sums_links_with_one_kilogram_default():
    spec = world('composition.world')
    assert spec.model('cart').mass == pytest.approx(3.5 + 1.0 + 0.25)
    assert not spec.model('cart').static


def test_model_without_shapes_stays_listed():
    shell = world('composition.world').model('empty_shell')
    assert shell is not None
    assert shell.collisions == [] and shell.visuals == []
    assert shell.mass == 1.0


def test_physics_settings_and_clean_world_has_nothing_skipped():
    spec = world('composition.world')
    assert spec.name == 'composition'
    assert spec.max_step_size == 0.002
    assert spec.real_time_update_rate == 500
    assert spec.gravity == (0.0, 0.0, -9.81)
    assert spec.skipped == []
    assert [m.name for m in spec.models] == ['hall', 'cart', 'empty_shell']
    assert spec.sdf_version == '1.6'
    assert not spec.ground_plane


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-3, 3), min_size=18, max_size=18))
def test_geom_pose_is_model_times_link_times_geom(values):
    model_pose, link_pose, geom_pose = (Pose(*values[i:i + 6]) for i in (0, 6, 12))

    def text(pose):
        return ' '.join(repr(v) for v in (pose.x, pose.y, pose.z, pose.roll, pose.pitch, pose.yaw))
    spec = parse_world(
        '<sdf version="1.6"><world name="w"><model name="m"><pose>%s</pose><link name="l"><pose>%s</pose>'
        '<collision name="c"><pose>%s</pose><geometry><sphere><radius>1</radius></sphere></geometry>'
        '</collision></link></model></world></sdf>' % (text(model_pose), text(link_pose), text(geom_pose)))
    model = spec.models[0]
    np.testing.assert_allclose(model.pose.matrix(), model_pose.matrix(), atol=1e-9)
    np.testing.assert_allclose(model.collisions[0].pose.matrix(),
                               link_pose.matrix() @ geom_pose.matrix(), atol=1e-9)


# The <state> block

def test_state_model_and_link_poses_win():
    room = world('state.world').model('room')
    assert_pose(room.pose, 3, 4, 0, yaw=HALF_PI)
    wall_0 = geom(room.collisions, 'Wall_0_Collision')
    assert_pose(wall_0.pose, 1, 0, 0.5)
    assert_pose(room.pose * wall_0.pose, 3, 5, 0.5, yaw=HALF_PI)


def test_link_without_state_keeps_its_place_in_the_moved_model():
    room = world('state.world').model('room')
    wall_1 = geom(room.collisions, 'Wall_1_Collision')
    assert_pose(wall_1.pose, 2, 0, 0)
    assert_pose(room.pose * wall_1.pose, 3, 6, 0, yaw=HALF_PI)


def test_state_moves_the_ball():
    assert_pose(world('state.world').model('ball').pose, 2, -1, 0.1)


def test_state_of_missing_model_is_reported_and_ignored():
    spec = world('state.world')
    assert spec.model('ghost') is None
    assert 'no such model' in skip_for(spec, 'ghost').reason
    assert len(spec.skipped) == 1


def test_state_insertions_and_deletions_apply():
    spec = world('state.world')
    assert [m.name for m in spec.models] == ['room', 'ball', 'inserted']
    inserted = spec.model('inserted')
    assert inserted.static
    assert_pose(inserted.pose, 0, -3, 0)
    assert inserted.collisions[0].size == (0.2, 1.0)


# Shapes

def test_each_readable_shape_has_its_size():
    kit = world('shapes.world').model('kit')
    assert geom(kit.collisions, 'a_box').size == (1.0, 2.0, 3.0)
    assert geom(kit.collisions, 'a_cylinder').size == (0.25, 1.5)
    assert geom(kit.collisions, 'a_sphere').size == (0.3,)
    assert [g.name for g in kit.collisions] == ['a_box', 'a_cylinder', 'a_sphere']


def test_plane_normal_is_unit_and_marks_a_ground_plane():
    spec = world('shapes.world')
    plane = spec.model('ground_plane').collisions[0]
    assert plane.kind == 'plane'
    assert plane.size == (0.0, 0.0, 1.0, 100.0, 80.0)
    assert spec.ground_plane


def test_a_link_whose_visual_mesh_is_missing_is_drawn_by_its_collisions_and_named():
    spec = world('shapes.world')
    kit = spec.model('kit')
    assert [(g.name, g.kind, g.size) for g in kit.visuals] == [
        ('a_mesh::a_box', 'box', (1.0, 2.0, 3.0)), ('a_mesh::a_cylinder', 'cylinder', (0.25, 1.5)),
        ('a_mesh::a_sphere', 'sphere', (0.3,))]
    record = skip_for(spec, 'visual meshes not found')
    assert record.reason == ('drawn by their collisions instead: '
                             'kit::link (model://statue/meshes/statue.dae)')


def test_model_of_meshes_stays_with_empty_shape_lists():
    spec = world('shapes.world')
    statue = spec.model('statue')
    assert statue.collisions == [] and statue.visuals == []
    assert {'statue/body/collision', 'statue/body/visual'} <= set(skipped_subjects(spec))
    assert 'mesh model://statue/meshes/statue.dae file not found; left out' in \
        skip_for(spec, 'statue/body/visual').reason


@pytest.mark.parametrize('name, words', [
    ('a_polyline', 'polyline'),
    ('infinite_box', 'not finite'),
    ('negative_sphere', 'not positive'),
    ('flat_cylinder', 'not positive'),
    ('short_box', 'not 3 numbers'),
    ('no_geometry', 'no <geometry>'),
])
def test_unusable_shapes_are_skipped_with_a_reason(name, words):
    record = skip_for(world('shapes.world'), 'kit/link/%s' % name)
    assert words in record.reason


# Colours

def test_explicit_white_over_grey_script_is_unlit_white():
    ball = world('materials.world').model('white_ball')
    visual = ball.visuals[0]
    assert visual.unlit_white
    assert visual.color == (1.0, 1.0, 1.0, 1.0)
    assert visual.material == 'Gazebo/Grey'
    assert ball.mass == 0.5


def test_explicit_ambient_tints_the_grey_script():
    visual = world('materials.world').model('red_ball').visuals[0]
    assert not visual.unlit_white
    np.testing.assert_allclose(visual.color, (0.82, 0.46, 0.46, 1.0))


def test_white_emissive_alone_is_unlit_white():
    assert world('materials.world').model('glowing_ball').visuals[0].unlit_white


@pytest.mark.parametrize('name, color, unlit', [
    ('grey', (0.54, 0.54, 0.54, 1.0), False),
    ('bricks_white_ambient', GAZEBO_MATERIALS['Gazebo/Bricks'].texture_tint + (1.0,), False),
    ('wood', GAZEBO_MATERIALS['Gazebo/Wood'].texture_tint + (1.0,), False),
    ('orange', (1.0, 0.5088, 0.0468, 1.0), False),
    ('white_glow', (1.0, 1.0, 1.0, 1.0), True),
    ('nearly_white', (BELOW_WHITE, BELOW_WHITE, BELOW_WHITE, 1.0), False),
    ('half_transparent', (0.0, 0.0, 1.0, 0.5), False),
    ('no_material', (0.54, 0.54, 0.54, 1.0), False),
    ('custom_script', (0.54, 0.54, 0.54, 1.0), False),
])
def test_script_and_explicit_colours(name, color, unlit):
    visual = geom(world('materials.world').model('walls').visuals, name)
    np.testing.assert_allclose(visual.color, color)
    assert visual.unlit_white is unlit


def test_only_unlit_white_visuals_are_pure_white():
    for model in world('materials.world').models:
        for visual in model.visuals:
            assert (visual.color[:3] == (1.0, 1.0, 1.0)) is visual.unlit_white, visual.name


def test_unknown_material_script_is_reported_once():
    spec = world('materials.world')
    assert skipped_subjects(spec) == ['material script Quarry/Gravel']


def test_scene_ambient_weights_the_colour():
    color = resolve_visual_color('Gazebo/Grey', scene_ambient=(1.0, 1.0, 1.0)).color
    assert color == (0.3, 0.3, 0.3, 1.0)


def test_white_script_counts_as_unlit_white():
    assert world('materials.world').model('white_pillar').visuals[0].unlit_white


# Balls

def test_find_balls_takes_dynamic_single_sphere_models():
    spec = world('materials.world')
    assert [m.name for m in find_balls(spec)] == ['white_ball', 'red_ball', 'glowing_ball', 'big_ball']
    assert [m.name for m in find_balls(spec, min_radius=0.2)] == ['glowing_ball', 'big_ball']


def test_white_balls_need_an_unlit_white_sphere_visual():
    assert [m.name for m in white_balls(world('materials.world'))] == ['white_ball', 'glowing_ball']


# Reports of what cannot be used (SDF 1.4 layout)

def test_sdf14_world_reports_what_flatsim_cannot_use():
    spec = world('skips_sdf14.world')
    subjects = skipped_subjects(spec)
    assert len(subjects) == 9, subjects
    assert any('model://bookshelf' in s and 'shelf_1' in s for s in subjects)
    assert any('libwelcome.so' in s for s in subjects)
    assert any('walker' in s for s in subjects)
    assert any('<road>' in s for s in subjects)
    assert any('rover/chassis/sensor eye' in s for s in subjects)
    assert any('libgazebo_ros_diff_drive.so' in s for s in subjects)
    assert any('model://hokuyo' in s for s in subjects)
    # A sensor and a plugin make the rover a saved robot, which the include keeps from running.
    rover = [s.reason for s in spec.skipped if s.subject == 'rover']
    assert len(rover) == 2 and 'cannot run it (it holds nested models or includes)' in rover[0]
    assert rover[1].startswith('1 joint')
    assert not any('sun' in s or 'ground_plane' in s or 'lamp' in s for s in subjects)


def test_sdf14_physics_gravity_and_implicit_ground():
    spec = world('skips_sdf14.world')
    assert spec.sdf_version == '1.4'
    assert spec.max_step_size == 0.01
    assert spec.gravity == (0.0, 0.0, -3.7)
    assert spec.ground_plane
    rover = spec.model('rover')
    assert rover.mass == 2.0
    chassis, wheel = rover.collisions
    assert (chassis.link, wheel.link) == ('chassis', 'wheel')
    assert_pose(chassis.pose, 0, 0, 0)
    assert_pose(wheel.pose, 0, 0.15, 0, roll=HALF_PI)


# SDF 1.7 frames

def test_relative_to_names_frames_links_and_the_model():
    rig = world('frames_sdf17.world').model('rig')
    assert_pose(rig.pose, 1, 0, 0)
    assert_pose(geom(rig.visuals, 'base_visual').pose, 2, 0, 0)
    assert_pose(geom(rig.collisions, 'arm_collision').pose, 2, 2, 0.5, yaw=HALF_PI)
    assert_pose(geom(rig.visuals, 'tip_visual').pose, 0, 0, 3)
    assert_pose(geom(rig.collisions, 'beside_base').pose, 2, 0, 1)


def test_unknown_and_looping_frames_skip_the_link():
    spec = world('frames_sdf17.world')
    assert "'nowhere'" in skip_for(spec, 'rig/lost').reason
    assert 'loop' in skip_for(spec, 'rig/loop_a').reason
    assert 'loop' in skip_for(spec, 'rig/loop_b').reason
    assert len(spec.skipped) == 3


def test_model_pose_relative_to_world_frames():
    spec = world('frames_sdf17.world')
    assert_pose(spec.model('follower').pose, 1, 0, 1)
    assert_pose(spec.model('marker_post').pose, 1, -2, 0)


# Bad input

def test_malformed_xml_names_file_and_line():
    path = os.path.join(WORLDS, 'malformed.world')
    with pytest.raises(ModelFileError) as caught:
        load_world(path)
    assert caught.value.line == 6
    assert caught.value.path == path
    assert 'malformed.world:6' in str(caught.value)


def test_blank_lines_before_the_xml_declaration_are_accepted_and_counted():
    with pytest.raises(ModelFileError) as caught:
        parse_world(b'\n\n<?xml version="1.0" ?>\n<sdf version="1.6">\n<world name="w">\n</sdf>\n')
    assert caught.value.line == 6
    assert parse_world('\n  <?xml version="1.0" ?>\n<sdf version="1.6"><world name="w"/></sdf>').name == 'w'


def test_state_of_missing_link_is_reported():
    spec = parse_world('<sdf version="1.6"><world name="w"><model name="m"><link name="l"/></model>'
                       '<state world_name="w"><model name="m"><pose>1 0 0 0 0 0</pose>'
                       '<link name="gone"><pose>1 0 0 0 0 0</pose></link></model></state></world></sdf>')
    assert_pose(spec.models[0].pose, 1, 0, 0)
    assert skipped_subjects(spec) == ['state of link m/gone']


def test_missing_file_is_a_model_file_error(tmp_path):
    with pytest.raises(ModelFileError, match='cannot read'):
        load_world(str(tmp_path / 'nothing.world'))


@pytest.mark.parametrize('text, words', [
    ('<robot name="r"/>', 'not <sdf>'),
    ('<sdf version="1.6"><model name="m"/></sdf>', 'no <world>'),
    ('', 'not well-formed'),
])
def test_text_that_is_not_a_world_is_refused(text, words):
    with pytest.raises(ModelFileError, match=words):
        parse_world(text)


def test_bad_model_pose_skips_only_that_model():
    spec = parse_world(b'<sdf version="1.6"><world name="w">'
                       b'<model name="bad"><pose>1 2 nan 0 0 0</pose></model>'
                       b'<model name="good"><pose>1 2 3 0 0 0</pose></model></world></sdf>')
    assert [m.name for m in spec.models] == ['good']
    assert skipped_subjects(spec) == ['bad']


def test_duplicate_model_name_keeps_the_first():
    spec = parse_world('<sdf version="1.6"><world name="w">'
                       '<model name="m"><pose>1 0 0 0 0 0</pose></model>'
                       '<model name="m"><pose>2 0 0 0 0 0</pose></model></world></sdf>')
    assert len(spec.models) == 1
    assert_pose(spec.models[0].pose, 1, 0, 0)
    assert 'second model' in spec.skipped[0].reason


def test_model_sdf_for_spawning():
    models, skipped = parse_sdf_models(
        '<sdf version="1.6"><model name="box"><pose>0 0 0.5 0 0 0</pose><link name="l">'
        '<collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision>'
        '</link></model></sdf>')
    assert [m.name for m in models] == ['box'] and skipped == []
    assert_pose(models[0].pose, 0, 0, 0.5)


def test_many_models_load_in_order():
    count = 2000
    body = ''.join(
        '<model name="m%d"><static>1</static><pose>%d 0 0 0 0 0</pose><link name="l">'
        '<collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision>'
        '</link></model>' % (i, i) for i in range(count))
    state = ''.join('<model name="m%d"><pose>%d 1 0 0 0 0</pose></model>' % (i, i) for i in range(count))
    spec = parse_world('<sdf version="1.6"><world name="w">%s<state world_name="w">%s</state></world></sdf>'
                       % (body, state))
    assert len(spec.models) == count
    assert_pose(spec.models[-1].pose, count - 1, 1, 0)
