"""Undo and Redo in the world without a browser or ROS: the history on its own (over a world
that only records what it is asked), and the hub's undo and redo over a bare Simulation."""
import logging
import xml.etree.ElementTree as ET

import pytest

from flatsim.loading.sdf_world import load_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.studio import editors
from flatsim.studio.history import DELETE, INSERT, MOVE, SCALE, Edit, History
from flatsim.studio.hub import Hub
from flatsim.studio.sim_world import SimWorld
from flatsim.studio.world import KeptModel, Outcome
from flatsim.world.sim import Simulation

from test_studio_editor_commands import Page
from test_studio_hub import ROBOT, WORLD, Clock


class Recorder:
    """A world that does what it is asked and remembers it."""

    def __init__(self):
        self.calls = []
        self.refuse = False

    def _answer(self, *call):
        self.calls.append(call)
        return Outcome(not self.refuse, 'refused' if self.refuse else 'done')

    def set_model_pose(self, name, pose):
        return self._answer('set_pose', name, pose)

    def delete_model(self, name):
        return self._answer('delete', name)

    def restore_model(self, kept):
        return self._answer('restore', kept.name, kept.pose)


def kept(name, x=0.0):
    return KeptModel(name, False, None, None, Pose(x, 0.0, 0.5), Pose(x, 0.0, 0.5))


def identities(**models):
    return lambda model: models.get(model)


# -- the history on its own ------------------------------------------------------------

def test_undo_and_redo_go_back_and_forth_through_the_edits_in_order():
    world, history = Recorder(), History()
    history.record(Edit(INSERT, 'box', kept=kept('box', 1.0)), 1)
    history.record(Edit(MOVE, 'box', before=Pose(1.0), after=Pose(2.0)), 1)
    assert history.labels() == {'undo': ['Move box', 'Insert box'], 'redo': []}
    history.undo(world, identities(box=1))
    # The history knows the box is still there, as it left it, and then gone.
    assert history.expected == {'box': 1}
    history.undo(world, identities())
    assert history.expected == {'box': None}
    assert world.calls == [('set_pose', 'box', Pose(1.0)), ('delete', 'box')]
    assert history.labels() == {'undo': [], 'redo': ['Insert box', 'Move box']}
    history.redo(world, identities(box=2))
    history.redo(world, identities(box=2))
    assert world.calls[2:] == [('restore', 'box', Pose(1.0, 0.0, 0.5)), ('set_pose', 'box', Pose(2.0))]
    _, outcome = history.redo(world, identities(box=2))
    assert not outcome.ok and outcome.message == 'there is nothing to redo'


def test_a_new_edit_forgets_what_was_undone_and_the_oldest_edits_go_past_the_limit():
    world, history = Recorder(), History(limit=3)
    for x in range(4):
        history.record(Edit(MOVE, 'box', before=Pose(x), after=Pose(x + 1)), 1)
    assert len(history.done) == 3
    history.undo(world, identities(box=1))
    history.record(Edit(DELETE, 'ball', kept=kept('ball')), None)
    assert history.labels() == {'undo': ['Delete ball', 'Move box', 'Move box'], 'redo': []}


def test_a_drag_is_one_move_until_the_page_lets_the_model_go():
    world, history = Recorder(), History()
    page, other = object(), object()
    assert history.moved(page, 'box', Pose(0.0), Pose(0.1), 1)
    assert not history.moved(page, 'box', None, Pose(0.2), 1)
    assert not history.moved(page, 'box', None, Pose(0.3), 1)
    assert len(history.done) == 1 and history.done[0].after == Pose(0.3)
    # Another page's move of it is its own.
    assert history.moved(other, 'box', Pose(0.3), Pose(0.5), 1)
    history.close_move(other, 'box')
    assert history.moved(other, 'box', Pose(0.5), Pose(0.6), 1)
    history.undo(world, identities(box=1))
    history.undo(world, identities(box=1))
    history.undo(world, identities(box=1))
    assert [call[2] for call in world.calls] == [Pose(0.5), Pose(0.3), Pose(0.0)]


def test_a_refused_undo_stays_in_the_history():
    world, history = Recorder(), History()
    history.record(Edit(DELETE, 'ball', kept=kept('ball')), None)
    world.refuse = True
    edit, outcome = history.undo(world, identities(ball=1))
    assert not outcome.ok and outcome.message == 'refused' and edit.label == 'Delete ball'
    assert history.labels()['undo'] == ['Delete ball']


def test_models_changed_from_outside_take_their_edits_out_of_the_history():
    history = History()
    history.record(Edit(INSERT, 'box', kept=kept('box')), 1)
    history.record(Edit(MOVE, 'ball', before=Pose(0.0), after=Pose(1.0)), 2)
    history.record(Edit(DELETE, 'crate', kept=kept('crate')), None)
    history.record(Edit(MOVE, 'box', before=Pose(0.0), after=Pose(1.0)), 1)
    # Moved by a ROS node: same identity, nothing dropped.
    assert history.notice({'box': 1, 'ball': 2}) == []
    # box deleted and spawned again (another identity), crate spawned where Delete left none.
    assert history.notice({'box': 7, 'ball': 2, 'crate': 3}) == ['box', 'crate']
    assert history.labels() == {'undo': ['Move ball'], 'redo': []}
    # ball deleted outside.
    assert history.notice({}) == ['ball']
    assert history.labels() == {'undo': [], 'redo': []}


# -- the hub's undo and redo over a simulation ------------------------------------------------

class RefusesToRestore(Recorder):
    """A world that cannot place one kept model (by its pose's x) again."""

    def __init__(self, refused_x):
        super().__init__()
        self.refused_x = refused_x

    def restore_model(self, kept):
        self.calls.append(('restore', kept.name, kept.pose))
        ok = kept.pose.x != self.refused_x
        return Outcome(ok, 'done' if ok else 'refused')


def test_a_scale_is_undone_by_putting_the_model_from_before_in_its_place_and_redone_alike():
    world, history = Recorder(), History()
    before, after = kept('box', 1.0), kept('box', 2.0)
    history.record(Edit(SCALE, 'box', kept=after, replaced=before), 1)
    assert history.labels() == {'undo': ['Scale box'], 'redo': []}
    history.undo(world, identities(box=2))
    # The box is still there (another one, the one from before).
    assert history.expected == {'box': 2}
    history.redo(world, identities(box=3))
    assert world.calls == [('delete', 'box'), ('restore', 'box', before.pose),
                           ('delete', 'box'), ('restore', 'box', after.pose)]


def test_a_scale_undo_that_cannot_place_the_model_from_before_puts_the_scaled_one_back():
    world, history = RefusesToRestore(refused_x=1.0), History()
    before, after = kept('box', 1.0), kept('box', 2.0)
    history.record(Edit(SCALE, 'box', kept=after, replaced=before), 1)
    _, outcome = history.undo(world, identities(box=1))
    assert not outcome.ok
    assert world.calls == [('delete', 'box'), ('restore', 'box', before.pose), ('restore', 'box', after.pose)]
    # Still to be undone.
    assert history.labels() == {'undo': ['Scale box'], 'redo': []}


@pytest.fixture
def studio(home, tmp_path, caplog):
    path = tmp_path / 'w.world'
    path.write_text(WORLD)
    world = load_world(str(path))
    sim = Simulation(world)
    sim.spawn_robot('bot', load_robot(ROBOT), Pose(-1.0, -1.0, yaw=0.3))
    hub = Hub(SimWorld(sim, world=world), log=logging.getLogger('studio-test'), clock=Clock())
    caplog.set_level(logging.INFO, logger='studio-test')
    editors.install(hub)
    return hub, sim


def xy_yaw(pose):
    return pytest.approx([pose.x, pose.y, pose.yaw], abs=1e-6)


def test_undo_of_an_insert_deletes_it_in_the_simulation_and_redo_puts_it_back_where_it_was(studio):
    hub, sim = studio
    page = Page(hub)
    inserted = page.ask(type='insert', shape='box', at=[1.5, -2.0])
    assert inserted['ok'] and inserted['name'] == 'unit_box_0'
    placed = sim.model_pose('unit_box_0')
    assert page.tab.last('history')['undo'] == ['Insert unit_box_0']
    undone = page.ask(type='undo')
    assert undone['ok'] and undone['edit'] == 'Insert unit_box_0'
    assert 'unit_box_0' not in sim.models
    assert page.tab.last('history') == {'type': 'history', 'undo': [], 'redo': ['Insert unit_box_0'],
                                        'dropped': []}
    assert page.ask(type='redo')['ok']
    assert sim.model_pose('unit_box_0') == placed
    # Made again from its SDF: Save World As writes it as before.
    assert ET.fromstring(sim.origins['unit_box_0'].sdf).find('link/visual/geometry/box') is not None
    hub.tick()
    assert 'unit_box_0' in [model['name'] for model in page.tab.last('scene')['models']]


def test_undo_of_a_delete_makes_the_model_again_with_its_sdf_pose_and_start(studio):
    hub, sim = studio
    page = Page(hub)
    assert page.ask(type='set_pose', model='white_ball', pose=[0.5, -0.5, 0.1, 0, 0, 0.7])['ok']
    page.ask(type='release', model='white_ball')
    where = sim.model_pose('white_ball')
    origin = sim.origins['white_ball']
    assert page.ask(type='delete', model='white_ball')['ok']
    assert 'white_ball' not in sim.models
    assert page.ask(type='undo')['ok']
    assert 'white_ball' in hub.model_names
    ball = sim.models['white_ball']
    back = sim.model_pose('white_ball')
    # (A ball's turn is not simulated: it is placed unturned, as a pasted ball.)
    assert ball.kind == 'ball' and (back.x, back.y, back.z) == (where.x, where.y, where.z)
    assert sim.origins['white_ball'] == origin
    # Reset Model Poses still takes it to where the world file put it.
    assert page.ask(type='reset_model_poses')['ok']
    assert sim.model_pose('white_ball').x == pytest.approx(1.0)
    assert page.ask(type='redo')['ok']
    assert 'white_ball' not in sim.models


def test_undo_of_a_deleted_robot_brings_it_back_with_its_camera(studio):
    hub, sim = studio
    page = Page(hub)
    assert page.ask(type='delete', model='bot')['ok']
    assert page.ask(type='undo')['ok']
    assert sim.models['bot'].kind == 'robot'
    assert sim.model_pose('bot').x == pytest.approx(-1.0)
    hub.tick()
    bot = next(m for m in page.tab.last('scene')['models'] if m['name'] == 'bot')
    assert [sensor['name'] for sensor in bot['sensors']] == ['cam']


def test_a_drag_is_undone_in_one_step_and_each_field_edit_in_one(studio):
    hub, sim = studio
    page = Page(hub)
    start = sim.model_pose('crate')
    for x in (2.2, 2.4, 2.6):
        assert page.ask(type='set_pose', model='crate', pose=[x, 0, 0.25, 0, 0, 0.5])['ok']
    page.ask(type='release', model='crate')
    for y in (1.0, 2.0):
        page.ask(type='set_pose', model='crate', pose=[2.6, y, 0.25, 0, 0, 0.5])
        page.ask(type='release', model='crate')
    assert page.tab.last('history')['undo'] == ['Move crate'] * 3
    assert page.ask(type='undo')['ok']
    assert sim.model_pose('crate') == Pose(2.6, 1.0, 0.25, yaw=0.5)
    # Models come and go meanwhile: the crate's edits stay, and it stays known.
    assert page.ask(type='insert', shape='box', at=[0, 3])['ok']
    assert page.ask(type='undo')['edit'] == 'Insert unit_box_0'
    assert page.ask(type='undo')['ok'] and page.ask(type='undo')['ok']
    assert sim.model_pose('crate') == start
    assert 'crate' in hub.model_names
    assert page.ask(type='redo')['ok']
    assert sim.model_pose('crate') == Pose(2.6, 0.0, 0.25, yaw=0.5)
    assert page.ask(type='set_pose', model='crate', pose=[1, 1, 0.25, 0, 0, 0])['ok']


def test_paste_is_undone_and_redone(studio):
    hub, sim = studio
    page = Page(hub)
    pasted = page.ask(type='paste', model='white_ball', pose=[-1, 2, 0.1, 0, 0, 0])
    assert page.ask(type='undo')['ok']
    assert pasted['name'] not in sim.models
    assert page.ask(type='redo')['ok']
    assert sim.models[pasted['name']].kind == 'ball'
    assert sim.model_pose(pasted['name']).y == pytest.approx(2.0)


def test_two_pages_share_one_history(studio):
    hub, sim = studio
    first, second = Page(hub), Page(hub)
    assert first.ask(type='insert', shape='sphere', at=[0, 2])['ok']
    assert second.tab.last('history')['undo'] == ['Insert unit_sphere_0']
    assert second.ask(type='undo')['ok']
    assert 'unit_sphere_0' not in sim.models
    assert first.tab.last('history')['redo'] == ['Insert unit_sphere_0']


def test_undo_waits_for_another_window_editing_the_model(studio):
    hub, sim = studio
    first, second = Page(hub), Page(hub)
    first.ask(type='set_pose', model='crate', pose=[3, 0, 0.25, 0, 0, 0])
    refused = second.ask(type='undo')
    assert not refused['ok']
    assert refused['message'] == 'crate is being edited in window 1; try again when it is done there'
    assert sim.model_pose('crate').x == pytest.approx(3.0)
    first.ask(type='release', model='crate')
    assert second.ask(type='undo')['ok']
    assert sim.model_pose('crate').x == pytest.approx(2.0)


def test_nothing_to_undo_is_said_so(studio):
    hub, _ = studio
    page = Page(hub)
    reply = page.ask(type='undo')
    assert not reply['ok'] and reply['message'] == 'there is nothing to undo'
    assert page.tab.last('history') == {'type': 'history', 'undo': [], 'redo': [], 'dropped': []}


def test_a_model_moved_from_outside_is_still_put_back_where_the_user_had_it(studio):
    hub, sim = studio
    page = Page(hub)
    page.ask(type='set_pose', model='white_ball', pose=[0, 0, 0.1, 0, 0, 0])
    page.ask(type='release', model='white_ball')
    # A ROS node (/gazebo/set_model_state) moves it on.
    sim.set_model_state('white_ball', Pose(-2.0, 2.0))
    hub.tick()
    assert page.ask(type='undo')['ok']
    assert sim.model_pose('white_ball').x == pytest.approx(1.0)
    assert sim.model_pose('white_ball').y == pytest.approx(1.0)


def test_a_model_deleted_or_replaced_from_outside_leaves_the_history(studio, caplog):
    hub, sim = studio
    page = Page(hub)
    page.ask(type='set_pose', model='crate', pose=[3, 0, 0.25, 0, 0, 0])
    page.ask(type='release', model='crate')
    page.ask(type='set_pose', model='white_ball', pose=[0, 0, 0.1, 0, 0, 0])
    page.ask(type='release', model='white_ball')
    assert page.ask(type='delete', model='bot')['ok']
    # /gazebo/delete_model takes the ball out; a robot is spawned where Delete left none.
    sim.delete_model('white_ball')
    sim.spawn_robot('bot', load_robot(ROBOT), Pose(2.0, 2.0))
    hub.tick()
    assert page.tab.last('history') == {'type': 'history', 'undo': ['Move crate'], 'redo': [],
                                        'dropped': ['bot', 'white_ball']}
    assert 'white_ball, bot' in caplog.text or 'bot, white_ball' in caplog.text
    assert page.ask(type='undo')['edit'] == 'Move crate'
    assert sim.model_pose('crate').x == pytest.approx(2.0)
    # The robot spawned from outside is left alone, and the ball stays gone.
    assert sim.model_pose('bot').x == pytest.approx(2.0)
    assert 'white_ball' not in sim.models


def test_a_model_replaced_from_outside_between_two_looks_is_seen(studio):
    hub, sim = studio
    page = Page(hub)
    assert page.ask(type='insert', shape='box', at=[1, 1])['ok']
    # Deleted and spawned again under the same name before the studio reads the world again.
    again = sim.models['unit_box_0'].source
    sim.delete_model('unit_box_0')
    sim.add_world_model(again, Pose(4.0, 4.0, 0.5))
    assert not page.ask(type='undo')['ok']
    assert page.tab.last('history')['dropped'] == ['unit_box_0']
    assert sim.model_pose('unit_box_0').x == pytest.approx(4.0)


def test_a_scale_is_undone_and_redone_in_the_simulation(studio):
    hub, sim = studio
    page = Page(hub)
    assert page.ask(type='insert', shape='box', at=[1.5, -2.0])['ok']

    def size():
        return ET.fromstring(sim.origins['unit_box_0'].sdf).find('link/collision/geometry/box/size').text

    assert size() == '1 1 1'
    placed = sim.model_pose('unit_box_0')
    assert page.ask(type='scale', model='unit_box_0', scale=[3, 1, 1])['ok']
    assert size() == '3 1 1'
    assert page.tab.last('history')['undo'] == ['Scale unit_box_0', 'Insert unit_box_0']
    undone = page.ask(type='undo')
    assert undone['ok'] and undone['edit'] == 'Scale unit_box_0'
    assert size() == '1 1 1' and sim.model_pose('unit_box_0') == placed
    assert page.ask(type='redo')['ok']
    assert size() == '3 1 1' and sim.model_pose('unit_box_0') == placed
    # A refused scale is no edit.
    assert not page.ask(type='scale', model='bot', scale=[2, 2, 2])['ok']
    assert page.tab.last('history')['undo'] == ['Scale unit_box_0', 'Insert unit_box_0']
