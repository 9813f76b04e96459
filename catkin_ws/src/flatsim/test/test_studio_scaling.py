"""The Scale tool's command on a bare Simulation: a simple shape takes its new sizes in the
simulation (colliders, scene, the saved world), and anything else is refused, unchanged."""
import logging
import math
import xml.etree.ElementTree as ET

import pymunk
import pytest

from flatsim.loading.sdf_world import parse_world
from flatsim.studio import editors
from flatsim.studio.hub import Hub
from flatsim.studio.sim_world import SimWorld
from flatsim.world.sim import Simulation

from test_studio_editor_commands import Page, world_file  # noqa: F401 - the fixture
from test_studio_hub import Clock

TWO_LINKS = '''<sdf version="1.6"><model name="pair"><static>true</static>
  <link name="a"><collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link>
  <link name="b"><pose>2 0 0 0 0 0</pose>
    <collision name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link>
</model></sdf>'''


@pytest.fixture
def page(tmp_path, monkeypatch):
    monkeypatch.setenv('HOME', str(tmp_path))
    sim = Simulation()
    hub = Hub(SimWorld(sim), log=logging.getLogger('studio-test'), clock=Clock())
    editors.install(hub)
    return Page(hub), sim


def insert(page, shape, at):
    reply = page.ask(type='insert', shape=shape, at=list(at))
    assert reply['ok'], reply['message']
    return reply['name']


def scene_model(page, name):
    page.hub.tick()
    scene = page.tab.last('scene')
    return next(model for model in scene['models'] if model['name'] == name)


def test_a_box_stretched_into_a_wall_blocks_what_drives_into_it(page):
    page, sim = page
    name = insert(page, 'box', (0.0, 1.2))
    assert scene_model(page, name)['simple_shape'] == 'box'
    reply = page.ask(type='scale', model=name, scale=[1.0, 3.0, 0.5])
    assert reply['ok'], reply['message']
    shape = scene_model(page, name)['links'][0]['shapes'][0]
    assert shape['size'] == pytest.approx([1.0, 3.0, 0.5])
    # Where it stands, under its name; the scene's colliders have its new size.
    pose = sim.model_pose(name)
    assert (pose.x, pose.y) == pytest.approx((0.0, 1.2))
    colliders = [i for i in sim.models[name].prim_ids if sim.scene.alive[i] and not sim.scene.visual[i]]
    assert [2 * sim.scene.half_y[i] for i in colliders] == pytest.approx([3.0])
    # Saved so, and started so after Reset Model Poses.
    saved = ET.fromstring(page.hub.world.world_sdf().text)
    model = next(found for found in saved.iter('model') if found.get('name') == name)
    assert [size.text.split() for size in model.iter('size')] == [['1', '3', '0.5']] * 2
    assert name in [model.name for model in parse_world(page.hub.world.world_sdf().text).models]
    assert page.ask(type='reset_model_poses')['ok']
    pose = sim.model_pose(name)
    assert (pose.x, pose.y) == pytest.approx((0.0, 1.2))


def test_a_sphere_stays_round_and_a_cylinder_keeps_a_round_base(page):
    page, _ = page
    sphere = insert(page, 'sphere', (3.0, 3.0))
    assert page.ask(type='scale', model=sphere, scale=[1.0, 1.0, 0.4])['ok']
    assert scene_model(page, sphere)['links'][0]['shapes'][0]['size'] == pytest.approx([0.2])
    cylinder = insert(page, 'cylinder', (-3.0, 3.0))
    assert page.ask(type='scale', model=cylinder, scale=[1.0, 2.0, 3.0])['ok']
    assert scene_model(page, cylinder)['links'][0]['shapes'][0]['size'] == pytest.approx([1.0, 3.0])


def test_what_is_no_simple_shape_and_bad_factors_are_refused_and_nothing_changes(page):
    page, sim = page
    assert page.hub.world.insert_model('pair', TWO_LINKS, (5.0, 5.0)).ok
    page.hub.model_names.add('pair')
    before = sim.models['pair']
    reply = page.ask(type='scale', model='pair', scale=[2.0, 1.0, 1.0])
    assert not reply['ok']
    assert reply['message'] == ('pair is not a simple shape: only a model of one box, cylinder or '
                                'sphere is scaled, as in Gazebo')
    assert sim.models['pair'] is before
    assert scene_model(page, 'pair')['simple_shape'] is None
    box = insert(page, 'box', (0.0, -3.0))
    for scale, says in (([0.0, 1.0, 1.0], 'scale must be three positive numbers [sx, sy, sz]'),
                        ([1.0, 1.0], 'scale must be three positive numbers'),
                        ([1000.0, 1.0, 1.0], "%s's size would be 1000 m; a scaled shape is 0.001 to 100 m"
                         % box)):
        reply = page.ask(type='scale', model=box, scale=scale)
        assert not reply['ok'] and says in reply['message'], reply
    assert scene_model(page, box)['links'][0]['shapes'][0]['size'] == pytest.approx([1.0, 1.0, 1.0])


def test_a_static_box_of_the_world_file_is_scaled_where_it_stands_and_saved_so(home, world_file):
    from flatsim.loading.sdf_world import load_world
    world = load_world(world_file)
    sim = Simulation(world)
    hub = Hub(SimWorld(sim, world=world), log=logging.getLogger('studio-test'), clock=Clock())
    editors.install(hub, world_file)
    page = Page(hub)
    # 0.9 m along the crate's length: beyond its end now, inside it once it is 2 m long.
    along = (2.0 + 0.9 * math.cos(0.5), 0.9 * math.sin(0.5))

    def collider_at(point):
        return [hit.shape for hit in sim.physics.space.point_query(point, 0.0, pymunk.ShapeFilter())
                if hit.shape.body is sim.physics.space.static_body]

    assert collider_at(along) == []
    reply = page.ask(type='scale', model='crate', scale=[4.0, 1.0, 2.0])
    assert reply['ok'], reply['message']
    assert sim.models['crate'].kind == 'static'
    pose = sim.model_pose('crate')
    assert (pose.x, pose.y, pose.z, pose.yaw) == pytest.approx((2.0, 0.0, 0.25, 0.5))
    assert scene_model(page, 'crate')['links'][0]['shapes'][0]['size'] == pytest.approx([2.0, 0.4, 1.0])
    # What drives or rolls into it meets the new collider, and the old one is gone.
    assert collider_at(along) == sim.models['crate'].colliders
    assert sim.physics.static_count() == len(sim.models['crate'].colliders)
    saved = parse_world(hub.world.world_sdf().text)
    crate = next(model for model in saved.models if model.name == 'crate')
    assert crate.static and [geom.size for geom in crate.collisions] == [pytest.approx((2.0, 0.4, 1.0))]
