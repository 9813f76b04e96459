"""The stand-in catalogue for model-database meshes, and how the world loader uses it."""
import pytest

from flatsim.loading.materials import BELOW_WHITE
from flatsim.loading.sdf_world import parse_world
from flatsim.loading.stand_ins import NUMBER_BLOCK_SIDE, PIXEL_FONT, stand_in

NUMBER_MESH = 'model://number1/meshes/number.dae'


def number_world(mesh_xml, material='Number/Two', state_scale=None, collision=False):
    state = '' if state_scale is None else '''
      <state world_name="default"><model name="block"><pose>0 3 1 0 0 0</pose>
        <scale>%s</scale></model></state>''' % state_scale
    geometry = '<geometry>%s</geometry>' % mesh_xml
    script = '' if material is None else '<material><script><name>%s</name></script></material>' % material
    return parse_world('''<sdf version="1.6"><world name="default">%s
      <model name="block"><static>1</static><pose>5 5 0.4 0 0 1.5708</pose><link name="link">
        <visual name="visual">%s%s</visual>%s
      </link></model></world></sdf>''' % (
        state, geometry, script,
        '<collision name="collision">%s</collision>' % geometry if collision else ''))


def mesh(uri=NUMBER_MESH, scale='0.5 0.5 0.5'):
    return '<mesh><uri>%s</uri><scale>%s</scale></mesh>' % (uri, scale)


def test_a_number_block_is_the_meshs_cube_at_its_scale_in_white():
    found = stand_in(NUMBER_MESH, (0.5, 0.5, 0.5), 'Number/One')
    block = found.parts[0]
    assert block.size == (0.4, 0.4, 0.4) and block.centre == (0.0, 0.0, 0.0)
    # White but not the unlit 255 white that ball detectors look for.
    assert block.color[:3] == (BELOW_WHITE,) * 3
    assert found.description == 'a white 0.40 m cube with the digit 1 on its faces'
    assert stand_in(NUMBER_MESH, (1.0, 0.5, 2.0)).parts[0].size == (0.8, 0.4, 1.6)


@pytest.mark.parametrize('uri, material, digit', [
    (NUMBER_MESH, 'Number/Three', 3),          # the course's world: number1's mesh, number3's script
    ('model://number4/meshes/number.dae', None, 4),
    ('model://number2/meshes/number.dae', 'Gazebo/Grey', 2),
])
def test_the_digit_comes_from_the_material_script_else_the_model(uri, material, digit):
    assert 'the digit %d' % digit in stand_in(uri, material=material).description


def test_meshes_outside_the_catalogue_have_no_stand_in():
    assert stand_in('model://willowgarage/meshes/willowgarage_visual.dae') is None
    assert stand_in('package://my_robot/meshes/number.dae') is None
    assert stand_in('') is None


def test_the_digit_is_black_strokes_on_each_side_face_and_the_top():
    found = stand_in(NUMBER_MESH, (0.5, 0.5, 0.5), 'Number/One')
    half = 0.2
    strokes = found.parts[1:]
    assert all(p.color[:3] == (0.0, 0.0, 0.0) and p.visual_only for p in strokes)
    faces = {p.name.split('_')[1] for p in strokes}
    assert faces == {'x+', 'x-', 'y+', 'y-', 'z+'}
    for stroke in strokes:
        normal = {'x': 0, 'y': 1, 'z': 2}[stroke.name.split('_')[1][0]]
        # Standing proud of its face, and inside the face's outline.
        outer = abs(stroke.centre[normal]) + stroke.size[normal] / 2
        assert half < outer <= half * 1.02
        for axis in {0, 1, 2} - {normal}:
            assert abs(stroke.centre[axis]) + stroke.size[axis] / 2 <= half * 0.6 + 1e-9
    # A few strokes a face: the glyph's runs of pixels, merged where they stack.
    assert all(sum(p.name.startswith('digit_%s_' % face) for p in strokes) <= 5 for face in faces)


def test_the_front_strokes_spell_the_glyph_as_seen_from_outside():
    # Face y- seen from -y: right is +x, up is +z; the cell is 3 x 5 pixels of the font.
    found = stand_in(NUMBER_MESH, (0.5, 0.5, 0.5), 'Number/Two')
    pixel = 0.6 * 0.4 / 5
    lit = set()
    for part in found.parts:
        if part.name.startswith('digit_y-_'):
            x0 = part.centre[0] - part.size[0] / 2
            z1 = part.centre[2] + part.size[2] / 2
            for col in range(round(part.size[0] / pixel)):
                for row in range(round(part.size[2] / pixel)):
                    lit.add((round(x0 / pixel + 1.5) + col, round(2.5 - z1 / pixel) + row))
    drawn = tuple(''.join('X' if (col, row) in lit else '.' for col in range(3)) for row in range(5))
    assert drawn == PIXEL_FONT[2]


def test_the_loader_draws_a_stand_in_and_says_so():
    spec = number_world(mesh())
    model = spec.model('block')
    assert len(model.visuals) == len(stand_in(NUMBER_MESH, (0.5,) * 3, 'Number/Two').parts)
    block = model.visuals[0]
    assert block.kind == 'box' and block.size == (0.4, 0.4, 0.4) and block.name == 'visual::block'
    # Strokes turn with the model: yawed by 90 degrees, the y- face looks along +x.
    stroke = next(g for g in model.visuals if g.name.startswith('visual::digit_y-_'))
    world = model.pose * stroke.pose
    assert world.x > 5.2 and abs(world.y - 5.0) < 0.1 and abs(world.yaw - 1.5708) < 1e-9
    reasons = [str(s) for s in spec.skipped]
    assert reasons == ['block/link/visual: mesh %s cannot be read; drawn as a stand-in instead: '
                       'a white 0.40 m cube with the digit 2 on its faces' % NUMBER_MESH]


def test_a_collision_mesh_stands_in_as_the_bare_block():
    model = number_world(mesh(), collision=True).model('block')
    assert [g.name for g in model.collisions] == ['collision::block']


def test_other_meshes_are_still_left_out_with_the_reason():
    spec = number_world(mesh('model://willowgarage/meshes/willowgarage_visual.dae', '1 1 1'))
    assert spec.model('block').visuals == []
    assert [str(s) for s in spec.skipped] == [
        'block/link/visual: mesh model://willowgarage/meshes/willowgarage_visual.dae file not found; '
        'left out']


def test_a_bad_mesh_scale_is_named_and_the_visual_left_out():
    spec = number_world(mesh(scale='0.5 0 0.5'))
    assert spec.model('block').visuals == []
    assert "mesh scale '0.5 0 0.5' is not positive; left out" in str(spec.skipped[0])


@pytest.mark.parametrize('state_scale, reported', [
    ('0.5 0.5 0.5', False),     # Gazebo gives the meshes that scale: they have it already
    ('1 1 1', False),
    ('2 2 2', True),
])
def test_a_saved_state_scale_is_reported_only_when_it_would_change_something(state_scale, reported):
    spec = number_world(mesh(), state_scale=state_scale)
    assert any('state scale' in str(s) for s in spec.skipped) == reported
    assert spec.model('block').visuals[0].size == (0.4, 0.4, 0.4)
