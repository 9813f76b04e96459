"""The studio's Insert tab, Model and Building Editors and Save World, without a browser or ROS:
a hub over a bare Simulation (flatsim.studio.sim_world.SimWorld) with the editors' commands."""
import json
import logging
import os

import pytest

from flatsim.authoring import building, saving
from flatsim.errors import AuthoringError
from flatsim.loading.model_path import gui_ini_model_paths
from flatsim.loading.sdf_world import load_world, parse_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.studio import editors
from flatsim.studio.hub import Hub
from flatsim.studio.sim_world import SimWorld
from flatsim.world.sim import Simulation
from flatsim.world.sim_models import FROM_INSERT

from test_studio_hub import ROBOT, Clock, Tab

WORLD = '''<sdf version="1.6"><world name="room">
  <include><uri>model://ground_plane</uri></include>
  <model name="crate"><static>true</static><pose>2 0 0.25 0 0 0.5</pose><link name="l">
    <collision name="c"><geometry><box><size>0.5 0.4 0.5</size></box></geometry></collision>
    <visual name="v"><geometry><box><size>0.5 0.4 0.5</size></box></geometry></visual>
  </link></model>
</world></sdf>'''
WHITE = [1, 1, 1, 1]
MY_BALL = [{'name': 'link_0', 'mass': 1, 'pose': None,
            'shapes': [{'kind': 'sphere', 'size': [0.1], 'ambient': WHITE, 'diffuse': WHITE,
                        'specular': WHITE, 'emissive': WHITE}]}]
# A room of 4 m by 3 m, drawn from (0, 0), with a door in its east wall.
ROOM = [{'start': [0, 0], 'end': [4, 0]}, {'start': [4, 0], 'end': [4, 3]},
        {'start': [4, 3], 'end': [0, 3]}, {'start': [0, 3], 'end': [0, 0]}]
DOOR = [{'wall': 1, 'offset': 1.5, 'kind': 'door', 'width': 0.9, 'height': 2.0, 'elevation': 0}]


@pytest.fixture
def world_file(tmp_path):
    path = tmp_path / 'worlds' / 'room.world'
    path.parent.mkdir()
    path.write_text(WORLD)
    return str(path)


@pytest.fixture
def studio(home, world_file, caplog):
    """(hub, editors, sim) for a world opened as `gazebo room.world` opens it, a robot spawned."""
    world = load_world(world_file)
    sim = Simulation(world)
    sim.spawn_robot('bot', load_robot(ROBOT), Pose(-1.0, -1.0))
    hub = Hub(SimWorld(sim, world=world), log=logging.getLogger('studio-test'), clock=Clock())
    caplog.set_level(logging.INFO, logger='studio-test')
    return hub, editors.install(hub, world_file), sim


class Page:
    """A tab on the hub: ask() sends a request and returns its reply."""

    def __init__(self, hub):
        self.hub = hub
        self.tab = Tab()
        self.session = hub.connect(self.tab)

    def ask(self, **request):
        request.setdefault('id', len(self.tab.texts) + 1)
        self.hub.receive(self.session, json.dumps(request))
        reply = self.tab.last('reply')
        assert reply['id'] == request['id']
        return reply


def test_simple_shapes_get_gazebos_names_and_land_where_dropped(studio):
    hub, _, sim = studio
    page = Page(hub)
    names = [page.ask(type='insert', shape=shape, at=[1.0, 2.0])['name']
             for shape in ('box', 'box', 'sphere', 'cylinder')]
    assert names == ['unit_box_0', 'unit_box_1', 'unit_sphere_0', 'unit_cylinder_0']
    pose = sim.model_pose('unit_sphere_0')
    assert (pose.x, pose.y, pose.z) == pytest.approx((1.0, 2.0, 0.5))
    assert sim.models['unit_sphere_0'].kind == 'ball'
    assert sim.origins['unit_box_0'].kind == FROM_INSERT
    sim.delete_model('unit_box_0')
    assert page.ask(type='insert', shape='box', at=[0, 0])['name'] == 'unit_box_0'


def test_an_inserted_cylinder_and_the_static_crate_are_moved_and_the_cylinder_is_pushed(studio):
    hub, _, sim = studio
    page = Page(hub)
    assert page.ask(type='insert', shape='cylinder', at=[-1.0, 0.0])['name'] == 'unit_cylinder_0'
    assert sim.models['unit_cylinder_0'].kind == 'body'
    for name in ('unit_cylinder_0', 'crate'):
        reply = page.ask(type='set_pose', model=name, pose=[0.5, -3.0 if name == 'crate' else 0.0,
                                                            0.5, 0, 0, 0.2])
        assert reply['ok'], reply
    assert sim.model_pose('crate') == Pose(0.5, -3.0, 0.5, yaw=0.2)
    assert sim.model_pose('unit_cylinder_0').x == pytest.approx(0.5)
    # 1 kg at 1 m/s on the ground (mu 1): it slides 1 / (2 * 9.8) m and stops.
    sim.set_model_state('unit_cylinder_0', Pose(0.5, 0.0, 0.5), (1.0, 0.0, 0.0))
    for _ in range(500):
        sim.step()
    assert sim.model_pose('unit_cylinder_0').x == pytest.approx(0.5 + 1 / 19.6, abs=0.005)


def test_my_ball_saved_is_listed_under_insert_and_inserted_as_the_white_ball(studio, home):
    hub, _, sim = studio
    page, other = Page(hub), Page(hub)
    before = {model['uri'] for model in page.ask(type='model_path')['models']}
    assert 'model://my_ball' not in before and {'model://ground_plane', 'model://sun'} <= before
    reply = page.ask(type='save_model', name='my_ball', links=MY_BALL)
    folder = os.path.join(home, '.gazebo', 'models', 'my_ball')
    assert reply['ok'] and reply['saved'] and reply['folder'] == folder
    assert sorted(os.listdir(folder)) == ['model.config', 'model.sdf']
    # ~/.gazebo/models is always on the model path, so gui.ini need not name it.
    assert not os.path.exists(os.path.join(home, '.gazebo', 'gui.ini'))
    # Every page hears of the new model, without asking.
    (listed,) = [m for m in other.tab.last('model_path')['models'] if m['name'] == 'my_ball']
    assert listed == {'name': 'my_ball', 'folder': folder, 'path': os.path.dirname(folder),
                      'uri': 'model://my_ball', 'description': '', 'problem': ''}
    assert page.ask(type='insert', model=folder, at=[3.0, -1.0])['name'] == 'my_ball'
    assert page.ask(type='insert', model=folder, at=[3.0, 1.0])['name'] == 'my_ball_0'
    assert sim.models['my_ball'].kind == 'ball'
    pose = sim.model_pose('my_ball')
    assert (pose.x, pose.y, pose.z) == pytest.approx((3.0, -1.0, 0.0))
    (prim,) = [i for i in sim.models['my_ball'].prim_ids if sim.scene.visual[i]]
    assert sim.scene.unlit_white[prim]


def test_saving_over_a_model_asks_first_and_a_second_page_cannot_take_it(studio, home):
    hub, _, _ = studio
    first, second = Page(hub), Page(hub)
    assert first.ask(type='save_model', name='my_ball', links=MY_BALL)['saved']
    sdf = os.path.join(home, '.gazebo', 'models', 'my_ball', 'model.sdf')
    old = open(sdf).read()
    again = first.ask(type='save_model', name='my_ball', links=MY_BALL)
    assert again['ok'] and not again['saved']
    assert again['message'].startswith('A model already exists in folder %s.' % os.path.dirname(sdf))
    refused = second.ask(type='save_model', name='my_ball', overwrite=True,
                         links=[dict(MY_BALL[0], mass=5)])
    assert not refused['ok']
    assert refused['message'] == ('%s is being edited in the Model Editor of window 1; save under '
                                  'another name, or once it is closed there' % os.path.dirname(sdf))
    assert open(sdf).read() == old
    first.ask(type='editor_closed', editor='model')
    assert second.ask(type='save_model', name='my_ball', overwrite=True,
                      links=[dict(MY_BALL[0], mass=5)])['saved']
    assert '<mass>5</mass>' in open(sdf).read()


@pytest.mark.parametrize('request_fields, says', [
    (dict(name='../my_ball', links=MY_BALL), "the model name '../my_ball' may not hold '/'"),
    (dict(name='a/b', links=MY_BALL), "the model name 'a/b' may not hold '/'"),
    (dict(name='ball', links=[dict(MY_BALL[0], shapes=[{'kind': 'sphere', 'size': [-0.1]}])]),
     'link link_0: sphere size must be 1 positive numbers, got (-0.1,)'),
    (dict(name='ball', links=[dict(MY_BALL[0], mass=-1)]),
     'link link_0: the mass must be a positive number, got -1.0'),
    (dict(name='ball', links=[{'shapes': 'round'}]), 'links[0].shapes must be a list'),
    (dict(name='ball', folder='/etc', links=MY_BALL), '/etc is not inside the folders flatsim may write to'),
])
def test_a_bad_model_is_refused_with_a_clear_message_and_nothing_written(studio, home, caplog,
                                                                        request_fields, says):
    hub, _, sim = studio
    page = Page(hub)
    reply = page.ask(type='save_model', **request_fields)
    assert not reply['ok'] and says in reply['message']
    assert says in caplog.text
    assert not os.path.exists(os.path.join(home, '.gazebo', 'models', 'ball'))
    assert not os.path.exists(os.path.join(os.path.dirname(home), 'my_ball'))
    time = sim.time
    sim.step()
    assert sim.time > time


def test_a_building_is_snapped_saved_and_inserted_where_it_was_drawn(studio, home):
    hub, _, sim = studio
    page = Page(hub)
    # Drawn a little off the grid: the server snaps as the page does.
    walls = [dict(ROOM[0], start=[0.05, -0.04])] + ROOM[1:]
    reply = page.ask(type='save_building', name='house', walls=walls, openings=DOOR)
    folder = os.path.join(home, 'building_editor_models', 'house')
    assert reply['saved'] and reply['folder'] == folder
    assert reply['walls'][0] == {'start': [0.0, 0.0], 'end': [4.0, 0.0]}
    assert gui_ini_model_paths() == [os.path.dirname(folder)]
    assert page.ask(type='insert', model=folder)['name'] == 'house'
    model = sim.models['house']
    assert sim.model_pose('house').x == pytest.approx(2.0)
    assert model.handle is None and len(model.colliders) == 5   # 3 whole walls, the east one beside its door


def test_a_model_saved_in_a_picked_folder_joins_gui_ini_and_is_listed_under_insert(studio, home, tmp_path):
    page = Page(studio[0])
    picked = tmp_path / 'my_models'
    picked.mkdir()
    assert page.ask(type='pick_folder', path=str(picked))['ok']
    reply = page.ask(type='save_model', name='my_ball', folder=str(picked), links=MY_BALL)
    assert reply['saved'] and reply['folder'] == str(picked / 'my_ball')
    assert gui_ini_model_paths() == [str(picked)]
    assert str(picked / 'my_ball') in [m['folder'] for m in page.ask(type='model_path')['models']]


@pytest.mark.parametrize('walls, openings, says', [
    ([dict(ROOM[0], end=[0, 0])] + ROOM[1:], [], 'Wall_0 has no length: it starts and ends at (0.0, 0.0)'),
    ([dict(ROOM[0], thickness=-0.15)] + ROOM[1:], [], 'Wall_0 thickness must be a positive number, got -0.15'),
    (ROOM, [dict(DOOR[0], width=-0.9)], 'door on Wall_1 width must be a positive number, got -0.9'),
    (ROOM, [dict(DOOR[0], offset=2.9)], 'door on Wall_1 does not fit'),
    ([dict(ROOM[0], start=[4.1, 0.1])] + ROOM[1:], [], 'Wall_0 has no length'),
])
def test_a_bad_building_is_refused_with_a_clear_message(studio, home, walls, openings, says):
    page = Page(studio[0])
    reply = page.ask(type='save_building', name='house', walls=walls, openings=openings)
    assert not reply['ok'] and says in reply['message']
    assert not os.path.exists(os.path.join(home, 'building_editor_models', 'house'))


def test_insert_lists_a_broken_model_and_refuses_it_clearly(studio, home):
    broken = os.path.join(home, '.gazebo', 'models', 'broken')
    os.makedirs(broken)
    with open(os.path.join(broken, 'model.config'), 'w') as config:
        config.write('<model><name>broken thing</name><sdf version="1.6">model.sdf</sdf>')
    page = Page(studio[0])
    (listed,) = [m for m in page.ask(type='model_path')['models'] if m['folder'] == broken]
    assert listed['name'] == 'broken' and listed['problem'].startswith('model.config cannot be read')
    reply = page.ask(type='insert', model=broken, at=[0, 0])
    assert not reply['ok']
    assert reply['message'].startswith('cannot insert broken (%s): model.config cannot be read' % broken)
    outside = page.ask(type='insert', model='/etc', at=[0, 0])
    assert not outside['ok'] and outside['message'].startswith('/etc is not a model folder on the model path')
    (sun_folder,) = [m['folder'] for m in editors.model_list()['models'] if m['uri'] == 'model://sun']
    sun = page.ask(type='insert', model=sun_folder)
    assert sun['message'] == 'cannot insert Sun: it is a light, and flatsim simulates no lights'


def test_save_world_writes_over_the_world_file_without_the_robot(studio, world_file):
    hub, _, sim = studio
    page = Page(hub)
    page.ask(type='insert', shape='box', at=[-2.0, 1.5])
    reply = page.ask(type='save_world')
    assert reply['ok'] and reply['path'] == world_file
    assert any(note.startswith('bot is a robot spawned from URDF') for note in reply['notes'])
    saved = load_world(world_file)
    assert sorted(model.name for model in saved.models) == ['crate', 'ground_plane', 'unit_box_0']
    (box,) = [model for model in saved.models if model.name == 'unit_box_0']
    assert (box.pose.x, box.pose.y) == (-2.0, 1.5)
    assert page.ask(type='places')['world_file'] == world_file


def test_save_world_as_goes_only_to_picked_folders_and_says_why_not(studio, tmp_path):
    hub, _, _ = studio
    page = Page(hub)
    elsewhere = tmp_path / 'elsewhere'
    elsewhere.mkdir()
    refused = page.ask(type='save_world', folder=str(elsewhere), file='copy.world')
    assert not refused['ok'] and 'is not inside the folders flatsim may write to' in refused['message']
    listing = page.ask(type='list_folder', path=str(tmp_path))
    assert listing['folders'] == ['elsewhere', 'home', 'worlds'] and listing['parent'] == str(tmp_path.parent)
    assert page.ask(type='list_folder', path=str(tmp_path / 'worlds'))['files'] == ['room.world']
    assert page.ask(type='pick_folder', path=str(elsewhere))['folder'] == str(elsewhere)
    for name, says in (('../copy.world', "may not hold '/'"), ('a/b.world', "may not hold '/'"),
                       ('..', "may not hold '..'")):
        reply = page.ask(type='save_world', folder=str(elsewhere), file=name)
        assert not reply['ok'] and says in reply['message']
    saved = page.ask(type='save_world', folder=str(elsewhere), file='copy.world')
    assert saved['path'] == str(elsewhere / 'copy.world')
    # Save World now writes where Save World As wrote.
    assert page.ask(type='save_world')['path'] == str(elsewhere / 'copy.world')
    assert parse_world((elsewhere / 'copy.world').read_text()).name == 'room'


def test_without_a_world_file_save_world_asks_for_one(home):
    sim = Simulation()
    hub = Hub(SimWorld(sim), clock=Clock())
    editors.install(hub)
    page = Page(hub)
    reply = page.ask(type='save_world')
    assert not reply['ok'] and reply['message'].startswith('this world has not been saved yet: use '
                                                           'File > Save World As')
    assert page.ask(type='places')['world_file'] == ''


@pytest.mark.parametrize('file_name, says', [
    ('copy.txt', "the world file name 'copy.txt' must end in .world, such as myworld.world"),
    ('copy', "the world file name 'copy' must end in .world"),
    ('.world', "the world file name '.world' may not start with a dot"),
    ('.hidden.world', "may not start with a dot (it would be hidden)"),
    ('../copy.world', "the world file name '../copy.world' may not hold '/'"),
    ('a..world', "the world file name 'a..world' may not hold '..'"),
    ('tab\t.world', 'holds a control character'),
])
def test_save_world_as_takes_only_a_plain_world_file_name(studio, world_file, file_name, says):
    page = Page(studio[0])
    folder = os.path.dirname(world_file)
    before = sorted(os.listdir(folder))
    reply = page.ask(type='save_world', folder=folder, file=file_name)
    assert not reply['ok'] and says in reply['message']
    assert sorted(os.listdir(folder)) == before


def test_save_world_as_replaces_a_file_only_once_the_page_confirms(studio, world_file):
    page = Page(studio[0])
    folder = os.path.dirname(world_file)
    other = os.path.join(folder, 'other.world')
    with open(other, 'w') as old:
        old.write('the old world')
    asked = page.ask(type='save_world', folder=folder, file='other.world')
    assert asked['ok'] and asked['saved'] is False and asked['exists'] == other
    assert asked['message'] == '%s already exists. Do you want to replace it?' % other
    assert open(other).read() == 'the old world'
    # Save World goes on writing over the world that was opened, not over the one asked about.
    assert page.ask(type='places')['world_file'] == world_file
    replaced = page.ask(type='save_world', folder=folder, file='other.world', overwrite=True)
    assert replaced['ok'] and replaced['saved'] and replaced['path'] == other
    assert parse_world(open(other).read()).name == 'room'
    # A new file needs no confirmation.
    assert page.ask(type='save_world', folder=folder, file='new.world')['saved']


@pytest.mark.parametrize('name, says', [
    ('.hidden', "the model name '.hidden' may not start with a dot"),
    ('my..ball', "the model name 'my..ball' may not hold '..'"),
    ('..', "may not hold '/', '\\\\', '::' or be '.' or '..'"),
])
def test_a_model_name_must_be_a_plain_folder_name(studio, home, name, says):
    page = Page(studio[0])
    reply = page.ask(type='save_model', name=name, links=MY_BALL)
    assert not reply['ok'] and says in reply['message']
    models = os.path.join(home, '.gazebo', 'models')
    assert not os.path.exists(models) or os.listdir(models) == []


def test_a_building_name_must_be_a_plain_folder_name(studio, home):
    reply = Page(studio[0]).ask(type='save_building', name='.house', walls=ROOM)
    assert not reply['ok'] and "the building name '.house' may not start with a dot" in reply['message']
    assert not os.path.exists(os.path.join(home, 'building_editor_models', '.house'))


def test_any_folder_already_there_is_written_over_only_once_the_page_confirms(studio, home):
    page = Page(studio[0])
    models = os.path.join(home, '.gazebo', 'models')
    # Not a model (no model.config or model.sdf), but someone's folder all the same.
    notes = os.path.join(models, 'my_ball')
    os.makedirs(notes)
    with open(os.path.join(notes, 'notes.txt'), 'w') as kept:
        kept.write('mine')
    asked = page.ask(type='save_model', name='my_ball', links=MY_BALL)
    assert asked['ok'] and asked['saved'] is False and asked['exists'] == notes
    assert os.listdir(notes) == ['notes.txt']
    with open(os.path.join(models, 'a_file'), 'w') as in_the_way:
        in_the_way.write('not a folder')
    refused = page.ask(type='save_model', name='a_file', links=MY_BALL, overwrite=True)
    assert not refused['ok'] and refused['message'] == (
        'cannot save a_file in %s: a file named a_file is in the way' % models)
    assert open(os.path.join(models, 'a_file')).read() == 'not a folder'


@pytest.mark.parametrize('path, says', [
    ('/', 'files may not be saved in the root folder /'),
    ('/etc', '/etc is a folder of the system; files may not be saved there'),
    ('/usr/share', '/usr/share is a folder of the system'),
    ('/lib', 'is a folder of the system'),
    ('/proc/self', 'is a folder of the system'),
    ('/var/tmp', '/var/tmp is a folder of the system'),
    ('/root', '/root is a folder of the system'),
    ('relative/folder', "the folder to pick must be an absolute path, got 'relative/folder'"),
])
def test_picking_a_folder_of_the_system_is_refused(studio, home, path, says):
    page = Page(studio[0])
    reply = page.ask(type='pick_folder', path=path)
    assert not reply['ok'] and says in reply['message']
    assert page.ask(type='places')['picked'] == []


def test_picking_refuses_a_link_to_a_system_folder_and_takes_home(studio, home, tmp_path):
    page = Page(studio[0])
    link = tmp_path / 'looks_harmless'
    link.symlink_to('/etc')
    reply = page.ask(type='pick_folder', path=str(link))
    assert not reply['ok'] and '%s (/etc) is a folder of the system' % link in reply['message']
    assert page.ask(type='pick_folder', path=home)['folder'] == home
    inside = os.path.join(home, 'worlds')
    os.makedirs(inside)
    assert page.ask(type='pick_folder', path=inside)['folder'] == inside
    assert page.ask(type='places')['picked'] == [home, inside]


def test_home_is_pickable_even_where_it_is_a_folder_of_the_system():
    assert saving.check_pickable_folder('/root', '/root') == '/root'
    assert saving.check_pickable_folder('/var/tmp', '/var/tmp') == '/var/tmp'
    # A HOME of / makes nothing pickable that is not so anyway.
    with pytest.raises(AuthoringError, match='root folder'):
        saving.check_pickable_folder('/', '/')


def test_the_folder_chooser_lists_only_folders_and_world_files(studio, tmp_path):
    page = Page(studio[0])
    folder = tmp_path / 'mixed'
    (folder / 'sub').mkdir(parents=True)
    for name in ('a.world', 'b.sdf', 'notes.txt', 'model.config'):
        (folder / name).write_text('x')
    listing = page.ask(type='list_folder', path=str(folder))
    assert listing['folders'] == ['sub'] and listing['files'] == ['a.world']
    unknown = page.ask(type='list_folder', path=str(folder), extension='.txt')
    assert not unknown['ok'] and unknown['message'] == 'list_folder does not take extension'


def test_an_insert_the_simulator_refuses_leaves_nothing_that_save_world_trips_on(studio, world_file):
    hub, _, sim = studio
    page = Page(hub)
    models, colliders = set(sim.models), sim.physics.static_count()
    # Within what a page may ask for, beyond what flatsim simulates (100 km).
    far = page.ask(type='insert', shape='sphere', at=[2e5, 0.0])
    assert not far['ok'] and 'beyond the 100000 m from the origin' in far['message']
    assert 'unit_sphere_0' not in sim.origins and set(sim.models) == models
    assert sim.physics.static_count() == colliders
    saved = page.ask(type='save_world')
    assert saved['ok'], saved['message']
    assert 'unit_sphere_0' not in {model.name for model in load_world(world_file).models}
    # The name is free again, and the next sphere takes it.
    assert page.ask(type='insert', shape='sphere', at=[1.0, 1.0])['name'] == 'unit_sphere_0'


HUGE = '1' + '0' * 400      # a whole number JSON allows, too big for any float


@pytest.mark.parametrize('text, says', [
    ('{"type": "save_model", "name": "ball", "links": [{"name": "l", "mass": %s, "shapes": '
     '[{"kind": "sphere", "size": [0.1]}]}]}' % HUGE, 'links[0].mass must be a finite number'),
    ('{"type": "save_model", "name": "ball", "links": [{"name": "l", "shapes": '
     '[{"kind": "sphere", "size": [NaN]}]}]}', 'links[0].shapes[0].size[0] must be a finite number'),
    ('{"type": "save_model", "name": "ball", "links": [{"name": "l", "shapes": '
     '[{"kind": "box", "size": [5000, 1, 1]}]}]}', 'size 5000 m is more than the 1000 m a shape may be'),
    ('{"type": "save_building", "name": "house", "walls": [{"start": [0, 0], "end": [4, 0], '
     '"height": 1e999}]}', 'walls[0].height must be a finite number'),
    ('{"type": "save_building", "name": "house", "walls": [{"start": [0, 0], "end": [4, 0], '
     '"thickness": 2000}]}', 'Wall_0 thickness is 2000 m, more than the 1000 m'),
    ('{"type": "insert", "shape": "box", "at": [%s, 0]}' % HUGE, 'at must be two finite numbers'),
    ('{"type": "list_folder", "path": 5}', 'path must be a non-empty string'),
])
def test_bad_editor_input_gets_a_clear_reply_and_writes_nothing(studio, home, caplog, text, says):
    hub, _, sim = studio
    page = Page(hub)
    models = set(sim.models)
    hub.receive(page.session, text)
    reply = page.tab.last('reply')
    assert reply['ok'] is False and says in reply['message'], reply['message']
    assert [record for record in caplog.records if record.exc_info or record.levelno >= logging.ERROR] == []
    assert set(sim.models) == models
    assert not os.path.exists(os.path.join(home, '.gazebo', 'models', 'ball'))
    assert not os.path.exists(os.path.join(home, 'building_editor_models', 'house'))


@pytest.mark.parametrize('value', ['fast', -1, 70000, 1.5, True, None, '8080x'])
def test_a_studio_port_that_is_no_port_is_a_clear_error(value):
    from flatsim.studio.server import StudioError, port_number
    with pytest.raises(StudioError, match='~studio_port must be a whole number from 0'):
        port_number(value)


def test_a_studio_port_given_as_text_is_read():
    from flatsim.studio.server import port_number
    assert port_number('8080') == 8080 and port_number(0) == 0


def test_insert_lists_an_unreadable_model_folder_with_the_reason(studio, home, monkeypatch):
    from test_model_path import unreadable
    locked = os.path.join(home, '.gazebo', 'models', 'locked')
    os.makedirs(locked)
    unreadable(monkeypatch, locked)
    page = Page(studio[0])
    (listed,) = [m for m in page.ask(type='model_path')['models'] if m['folder'] == locked]
    assert listed['name'] == 'locked'
    assert listed['problem'] == 'the folder cannot be read (Permission denied)'
    reply = page.ask(type='insert', model=locked, at=[0, 0])
    assert not reply['ok'] and reply['message'] == (
        'cannot insert locked (%s): the folder cannot be read (Permission denied)' % locked)


def test_the_hello_gives_the_building_editor_the_grid_snap_defaults_and_limits_held_here(studio,
                                                                                      monkeypatch):
    hub, _, _ = studio
    sent = Page(hub).tab.last('hello')['building']
    assert sent['grid_step'] == 0.25 and sent['snap_radius'] == 0.25
    assert sent['wall'] == {'thickness': 0.15, 'height': 2.5, 'color': [1.0, 1.0, 1.0, 1.0]}
    assert sent['door']['width'] == 0.9 and sent['window']['elevation'] == 0.5
    assert sent['max_parts'] == editors.MAX_PARTS
    # Changed where the server snaps and checks, the next page is told, and the server snaps so.
    monkeypatch.setattr(building, 'GRID_STEP', 0.5)
    page = Page(hub)
    assert page.tab.last('hello')['building']['grid_step'] == 0.5
    reply = page.ask(type='save_building', name='grid', walls=[{'start': [0.3, 0.1], 'end': [2.2, 0.2]}])
    assert reply['ok'], reply['message']
    assert reply['walls'] == [{'start': [0.5, 0.0], 'end': [2.0, 0.0]}]
