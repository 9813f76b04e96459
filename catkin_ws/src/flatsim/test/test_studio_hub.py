"""The studio's protocol without a browser or ROS: a hub over a bare Simulation
(flatsim.studio.sim_world.SimWorld, as the node's NodeWorld is over the running node)."""
import json
import logging
import struct
import subprocess
import sys
import types
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from flatsim.loading.sdf_world import parse_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.studio.hub import Hub
from flatsim.studio.model_names import clone_name
from flatsim.studio.protocol import MAX_REQUEST_NESTING, nested_deeper
from flatsim.studio.sim_world import SimWorld
from flatsim.studio.world import SnapshotTaker
from flatsim.world.sim import Simulation

WORLD = '''<sdf version="1.6"><world name="w">
  <model name="crate"><static>true</static><pose>2 0 0.25 0 0 0.5</pose><link name="l">
    <collision name="c"><geometry><box><size>0.5 0.4 0.5</size></box></geometry></collision>
    <visual name="v"><geometry><box><size>0.5 0.4 0.5</size></box></geometry>
      <material><ambient>0.6 0.3 0.1 1</ambient><diffuse>0.6 0.3 0.1 1</diffuse></material></visual>
  </link></model>
  <model name="white_ball"><pose>1 1 0.1 0 0 0</pose><link name="link">
    <collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
    <visual name="v"><geometry><sphere><radius>0.1</radius></sphere></geometry></visual>
  </link></model>
  <model name="statue"><static>true</static><pose>-2 0 0 0 0 0</pose><link name="l">
    <visual name="v"><geometry><mesh><uri>model://statue/meshes/statue.dae</uri></mesh></geometry></visual>
  </link></model>
</world></sdf>'''

ROBOT = '''<robot name="bot">
  <link name="base"><collision><geometry><box size="0.4 0.3 0.2"/></geometry></collision>
    <visual><geometry><box size="0.4 0.3 0.2"/></geometry></visual>
    <inertial><mass value="5"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="eye"><visual><geometry><sphere radius="0.05"/></geometry></visual></link>
  <joint name="eye_joint" type="fixed"><parent link="base"/><child link="eye"/>
    <origin xyz="0.2 0 0.1"/></joint>
  <gazebo reference="base"><material>Gazebo/Red</material></gazebo>
  <gazebo reference="eye"><sensor type="camera" name="cam"><update_rate>10</update_rate>
    <camera><horizontal_fov>1.0</horizontal_fov><image><width>64</width><height>48</height></image>
      <clip><near>0.05</near><far>50</far></clip></camera>
    <plugin name="c" filename="libgazebo_ros_camera.so"><cameraName>cam</cameraName></plugin>
  </sensor></gazebo>
</robot>'''


class Tab:
    """A transport that keeps what the hub sends."""

    def __init__(self):
        self.texts = []
        self.frames = []

    def send_text(self, text):
        self.texts.append(json.loads(text))

    def send_bytes(self, data):
        self.frames.append(data)

    def of_type(self, kind):
        return [message for message in self.texts if message['type'] == kind]

    def last(self, kind):
        found = self.of_type(kind)
        assert found, 'no %s message among %s' % (kind, [m['type'] for m in self.texts])
        return found[-1]


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


@pytest.fixture
def sim():
    world = Simulation(parse_world(WORLD))
    world.spawn_robot('bot', load_robot(ROBOT), Pose(-1.0, -1.0, yaw=0.3))
    return world


@pytest.fixture
def hub(sim):
    return Hub(SimWorld(sim), clock=Clock())


def ask(hub, session, tab, **request):
    request.setdefault('id', len(tab.texts) + 1)
    hub.receive(session, json.dumps(request))
    reply = tab.last('reply')
    assert reply['id'] == request['id']
    return reply


def test_a_new_page_gets_the_world_as_flatsim_simulates_it(hub, sim):
    tab = Tab()
    hub.connect(tab)
    assert [m['type'] for m in tab.texts] == ['hello', 'scene', 'skipped', 'status', 'leases',
                                             'history']
    scene = {model['name']: model for model in tab.last('scene')['models']}
    assert set(scene) == {'crate', 'white_ball', 'statue', 'bot'}
    crate = scene['crate']
    assert crate['static'] and crate['pose'] == [2.0, 0.0, 0.25, 0.0, 0.0, 0.5]
    (box,) = crate['links'][0]['shapes']
    assert box['shape'] == 'box' and box['size'] == [0.5, 0.4, 0.5]
    # The shape sits at the model's origin, in its colour.
    assert box['pose'] == pytest.approx([0.0] * 6, abs=1e-5)
    assert box['color'][:3] == pytest.approx([0.6, 0.3, 0.1], abs=0.01)
    ball = scene['white_ball']['links'][0]['shapes']
    assert [(s['shape'], s['size']) for s in ball] == [('sphere', [0.1])]
    bot = scene['bot']
    assert bot['kind'] == 'robot' and not bot['static']
    links = {link['name']: link for link in bot['links']}
    assert links['eye']['pose'][:3] == [0.2, 0.0, 0.1]
    assert links['base']['shapes'][0]['color'][:3] == pytest.approx([1.0, 0.0, 0.0], abs=0.01)
    (camera,) = bot['sensors']
    assert (camera['kind'], camera['link'], camera['hfov'], camera['width']) == ('camera', 'eye', 1.0, 64)
    # The mesh flatsim cannot draw is listed, not silently missing.
    skipped = tab.last('skipped')['items']
    assert any(item['subject'].startswith('statue') and 'mesh' in item['reason'] for item in skipped)


def test_no_page_no_work(hub):
    hub.tick()
    assert hub.world.snapshots == 0


def test_poses_stream_full_after_a_scene_then_only_what_moved(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    hub.tick()
    first = tab.last('poses')
    assert first['full'] and set(first['models']) == {'crate', 'white_ball', 'statue', 'bot'}
    assert first['models']['bot'][5] == pytest.approx(0.3)
    hub.tick()
    assert len(tab.of_type('poses')) == 1, 'nothing moved, so nothing is sent'
    sim.set_model_state('white_ball', Pose(0.5, -0.5, 0.1), (1.0, 0.0, 0.0))
    sim.step()
    hub.tick()
    moved = tab.last('poses')
    assert set(moved['models']) == {'white_ball'} and 'full' not in moved
    assert moved['models']['white_ball'][0] == pytest.approx(0.5, abs=0.01)
    assert session.needs_full_poses is False


def test_a_page_out_of_sight_costs_nothing_and_gets_all_poses_back(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    hub.tick()
    assert ask(hub, session, tab, type='stream', on=False)['ok']
    assert not hub.watched
    read, sent = hub.world.snapshots, len(tab.texts)
    sim.set_model_state('white_ball', Pose(0.5, -0.5, 0.1))
    hub.clock.now += 1.0
    hub.tick()
    assert hub.world.snapshots == read, 'the world is not read for a hidden page'
    assert len(tab.texts) == sent, 'a hidden page gets no poses and no status'
    assert ask(hub, session, tab, type='stream', on=True)['ok']
    hub.tick()
    poses = tab.last('poses')
    assert poses['full'] and set(poses['models']) == {'crate', 'white_ball', 'statue', 'bot'}
    assert poses['models']['white_ball'][:2] == pytest.approx([0.5, -0.5])


def test_set_pose_moves_the_model_in_the_simulation(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    reply = ask(hub, session, tab, type='set_pose', model='white_ball', pose=[1.5, -1.0, 0.1, 0, 0, 0])
    assert reply['ok'] and reply['request'] == 'set_pose'
    assert sim.model_pose('white_ball').x == pytest.approx(1.5)
    assert sim.model_pose('white_ball').y == pytest.approx(-1.0)


def test_a_static_model_is_moved_streamed_saved_pasted_and_reset_as_in_gazebo(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    hub.tick()
    scenes = len(tab.of_type('scene'))
    reply = ask(hub, session, tab, type='set_pose', model='crate', pose=[-0.5, 2.0, 0.25, 0, 0, 1.0])
    assert reply['ok'], reply
    assert sim.model_pose('crate') == Pose(-0.5, 2.0, 0.25, yaw=1.0)
    hub.tick()
    moved = tab.last('poses')
    assert moved['models'] == {'crate': [-0.5, 2.0, 0.25, 0.0, 0.0, 1.0]}
    assert len(tab.of_type('scene')) == scenes, 'a move is a pose, not a new scene'
    saved = ET.fromstring(hub.world.world_sdf().text)
    crate = next(m for m in saved.iter('model') if m.get('name') == 'crate')
    assert [float(v) for v in crate.findtext('pose').split()] == pytest.approx([-0.5, 2.0, 0.25, 0, 0, 1.0])
    pasted = ask(hub, session, tab, type='paste', model='crate', pose=[3, -2, 0.25, 0, 0, 0])
    assert pasted['ok'] and sim.models[pasted['name']].kind == 'static'
    assert sim.model_pose(pasted['name']).x == pytest.approx(3.0)
    assert ask(hub, session, tab, type='reset_model_poses')['ok']
    assert sim.model_pose('crate') == Pose(2.0, 0.0, 0.25, yaw=0.5)
    hub.tick()
    assert tab.last('poses')['models']['crate'] == [2.0, 0.0, 0.25, 0.0, 0.0, 0.5]


def test_a_dynamic_box_is_a_body_that_moves_in_the_stream(sim):
    box = parse_world(WORLD.replace('<model name="crate"><static>true</static>',
                                    '<model name="crate"><static>false</static>'))
    loose = Simulation(box)
    hub = Hub(SimWorld(loose), clock=Clock())
    tab = Tab()
    session = hub.connect(tab)
    hub.tick()
    crate = next(m for m in tab.last('scene')['models'] if m['name'] == 'crate')
    assert crate['kind'] == 'body' and crate['static'] is False
    assert ask(hub, session, tab, type='set_pose', model='crate', pose=[0.0, 2.0, 0.25, 0, 0, 0])['ok']
    hub.tick()
    assert tab.last('poses')['models']['crate'][:2] == pytest.approx([0.0, 2.0])


@pytest.mark.parametrize('text, says', [
    ('not json', 'not JSON'),
    ('[1, 2]', 'JSON object'),
    ('{"type": "fly"}', "unknown request type 'fly'"),
    ('{"type": "set_pose", "model": "white_ball"}', 'needs pose'),
    ('{"type": "set_pose", "model": "white_ball", "pose": [1, 2]}', 'six finite numbers'),
    ('{"type": "set_pose", "model": "white_ball", "pose": [NaN, 0, 0, 0, 0, 0]}', 'six finite numbers'),
    ('{"type": "set_pose", "model": "white_ball", "pose": [1e300, 0, 0, 0, 0, 0]}', 'too far'),
    ('{"type": "set_pose", "model": "white_ball", "pose": [1, 0, 0, 0, 0, 0], "speed": 3}',
     'does not take speed'),
    ('{"type": "set_pose", "model": "ghost", "pose": [1, 0, 0, 0, 0, 0]}', "no model named 'ghost'"),
    ('{"type": "step", "count": 0}', 'whole number from 1'),
    ('{"type": "step", "count": 1001}', 'a whole number from 1 to 1000'),
    ('{"type": "camera", "sensor": "bot::nope", "on": true}', "no camera 'bot::nope'"),
])
def test_a_bad_request_gets_a_clear_reply_and_a_log_line(hub, sim, text, says, caplog):
    tab = Tab()
    session = hub.connect(tab)
    before = sim.model_pose('white_ball')
    with caplog.at_level(logging.WARNING, logger='flatsim.studio'):
        hub.receive(session, text)
    reply = tab.last('reply')
    assert reply['ok'] is False and says in reply['message']
    assert says in caplog.text
    assert sim.model_pose('white_ball') == before
    # The page and the stream go on.
    assert ask(hub, session, tab, type='pause')['ok']


def test_a_second_window_editing_the_same_model_is_told_so(hub, sim):
    first, second = Tab(), Tab()
    a = hub.connect(first)
    b = hub.connect(second)
    assert ask(hub, a, first, type='lease', model='white_ball')['ok']
    assert second.last('leases')['leases'] == {'white_ball': a.id}
    refused = ask(hub, b, second, type='set_pose', model='white_ball', pose=[3, 3, 0.1, 0, 0, 0])
    assert not refused['ok']
    assert refused['message'] == ('white_ball is being edited in window %d; try again when it is '
                                  'done there' % a.id)
    assert sim.model_pose('white_ball').x == pytest.approx(1.0)
    assert not ask(hub, b, second, type='delete', model='white_ball')['ok']
    # Another model is free, and a closed tab frees what it held.
    assert ask(hub, b, second, type='lease', model='bot')['ok']
    hub.disconnect(a)
    assert second.last('leases')['leases'] == {'bot': b.id}
    assert ask(hub, b, second, type='set_pose', model='white_ball', pose=[3, 3, 0.1, 0, 0, 0])['ok']


def test_a_lease_runs_out_when_its_holder_goes_quiet(hub):
    first, second = Tab(), Tab()
    a, b = hub.connect(first), hub.connect(second)
    ask(hub, a, first, type='lease', model='white_ball')
    hub.clock.now += 10.0
    hub.tick()
    assert second.last('leases')['leases'] == {}
    assert ask(hub, b, second, type='lease', model='white_ball')['ok']


def test_paste_spawns_copies_under_gazebos_names(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    hub.tick()
    first = ask(hub, session, tab, type='paste', model='white_ball')
    second = ask(hub, session, tab, type='paste', model='white_ball', pose=[-1, 2, 0.1, 0, 0, 0])
    assert (first['name'], second['name']) == ('white_ball_clone', 'white_ball_clone_0')
    assert sim.models['white_ball_clone'].kind == 'ball'
    assert sim.model_pose('white_ball_clone').x == pytest.approx(1.5)
    assert sim.model_pose('white_ball_clone_0').y == pytest.approx(2.0)
    hub.tick()
    names = [model['name'] for model in tab.last('scene')['models']]
    assert 'white_ball_clone_0' in names
    assert tab.last('poses')['full']


def test_clone_names_skip_taken_ones():
    assert clone_name('box', {'box'}) == 'box_clone'
    assert clone_name('box', {'box', 'box_clone', 'box_clone_0'}) == 'box_clone_1'


def test_delete_sends_the_scene_without_the_model(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    assert ask(hub, session, tab, type='delete', model='white_ball')['ok']
    hub.tick()
    assert 'white_ball' not in [m['name'] for m in tab.last('scene')['models']]
    assert 'white_ball' not in sim.models


def test_pause_step_and_reset(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    for _ in range(10):
        sim.step()
    ask(hub, session, tab, type='pause')
    hub.tick()
    assert tab.last('status')['paused'] is True
    before = sim.time
    assert ask(hub, session, tab, type='step', count=3)['ok']
    assert sim.time == pytest.approx(before + 3 * sim.step_size)
    assert ask(hub, session, tab, type='reset_world')['ok']
    hub.tick()
    assert tab.last('status')['sim_time'] == 0.0


def test_the_camera_panel_gets_jpeg_frames_only_while_open(hub):
    tab = Tab()
    session = hub.connect(tab)
    hub.tick()
    assert tab.frames == []
    assert ask(hub, session, tab, type='camera', sensor='bot::cam', on=True)['ok']
    hub.tick()
    (frame,) = tab.frames
    length = struct.unpack('>I', frame[:4])[0]
    header = json.loads(frame[4:4 + length])
    assert header == {'type': 'camera_image', 'sensor': 'bot::cam', 'sim_time': 0.0,
                      'width': 64, 'height': 48}
    assert frame[4 + length:4 + length + 2] == b'\xff\xd8'     # a JPEG
    ask(hub, session, tab, type='camera', on=False)
    hub.clock.now += 1.0
    hub.tick()
    assert len(tab.frames) == 1


def test_scans_are_asked_of_the_simulator_only_while_a_page_draws_them(hub):
    tab = Tab()
    session = hub.connect(tab)
    ask(hub, session, tab, type='scans', on=True)
    assert hub.world.scans_wanted is True
    hub.disconnect(session)
    assert hub.world.scans_wanted is False


def test_snapshot_is_plain_and_cheap(sim):
    snapshot = SnapshotTaker().take(sim)
    assert snapshot.poses['bot'][:2] == pytest.approx([-1.0, -1.0])
    assert all(isinstance(v, float) for v in snapshot.poses['white_ball'])
    assert snapshot.poses['crate'] == [2.0, 0.0, 0.25, 0.0, 0.0, 0.5]
    assert np.isfinite(snapshot.sim_time)


def test_a_snapshot_reads_only_the_models_that_move(sim):
    taker = SnapshotTaker()
    first = taker.take(sim)
    assert set(first.moving) == {'white_ball', 'bot'}
    assert first.moving_poses.shape == (2, 4)
    # Static models are read once, while models neither come nor go.
    assert taker.take(sim).static_poses is first.static_poses
    sim.delete_model('crate')
    assert 'crate' not in taker.take(sim).static_poses


HUGE = '1' + '0' * 400      # a whole number JSON allows, too big for any float


@pytest.mark.parametrize('text, says', [
    ('{"type": "set_pose", "model": "white_ball", "pose": [%s, 0, 0, 0, 0, 0]}' % HUGE,
     'six finite numbers'),
    ('{"type": "set_pose", "model": "white_ball", "pose": [1e999, 0, 0, 0, 0, 0]}', 'six finite numbers'),
    ('{"type": "set_pose", "model": "white_ball", "pose": [-Infinity, 0, 0, 0, 0, 0]}',
     'six finite numbers'),
    ('{"type": "set_pose", "model": "white_ball", "pose": ["1", 0, 0, 0, 0, 0]}', 'six finite numbers'),
    ('{"type": "step", "count": %s}' % HUGE, 'whole number from 1'),
    ('{"type": "step", "count": "10"}', 'whole number from 1'),
    ('{"type": "paste", "model": "white_ball", "pose": [%s, 0, 0, 0, 0, 0]}' % HUGE, 'six finite'),
    ('{"type": 7}', 'unknown request type 7'),
    ('{"type": "delete", "model": "%s"}' % ('x' * 5000), 'at most 256 characters'),
    ('[' * 100000 + ']' * 100000, 'nested too deeply'),
    ('{"type": "pause", "id": "%s"}' % ('x' * (2 << 20)), 'more than the 1048576 the studio reads'),
    ('(a binary frame)', 'not JSON'),
])
def test_bad_input_gets_a_clear_reply_changes_nothing_and_logs_no_traceback(hub, sim, text, says,
                                                                            caplog):
    tab = Tab()
    session = hub.connect(tab)
    before = {name: sim.model_pose(name) for name in sim.models}
    time = sim.time
    with caplog.at_level(logging.WARNING, logger='flatsim.studio'):
        hub.receive(session, text)
    reply = tab.last('reply')
    assert reply['ok'] is False and says in reply['message'], reply['message']
    assert len(reply['message']) < 1000
    assert [record for record in caplog.records if record.exc_info or record.levelno >= logging.ERROR] == []
    assert {name: sim.model_pose(name) for name in sim.models} == before and sim.time == time


def test_a_request_nested_too_deeply_is_refused_before_python_reads_it(hub, monkeypatch):
    """json.loads recurses a level at a time: near Python's recursion limit a garbage collection
    could not free the simulator's pymunk bodies safely, so such a request is never read."""
    def no_reading(text):
        raise AssertionError('json.loads was called on a request nested too deeply')
    tab = Tab()
    session = hub.connect(tab)
    deep = '{"type": "pause", "id": %s1%s}' % ('[' * MAX_REQUEST_NESTING, ']' * MAX_REQUEST_NESTING)
    monkeypatch.setattr('flatsim.studio.hub.json', types.SimpleNamespace(loads=no_reading, dumps=json.dumps))
    hub.receive(session, deep)
    monkeypatch.undo()
    reply = tab.last('reply')
    assert reply['message'] == 'the request is nested too deeply to read (more than %d levels)' % (
        MAX_REQUEST_NESTING)


def test_nesting_is_counted_by_brackets_outside_strings():
    assert not nested_deeper('[' * MAX_REQUEST_NESTING + ']' * MAX_REQUEST_NESTING)
    assert nested_deeper('[' * (MAX_REQUEST_NESTING + 1) + ']' * (MAX_REQUEST_NESTING + 1))
    # Brackets inside strings, escaped quotes among them, are text.
    assert not nested_deeper('{"name": "%s", "note": "\\"%s"}' % ('[' * 100, '{' * 100))
    assert nested_deeper('["\\"", %s]' % ('[' * MAX_REQUEST_NESTING))


@pytest.mark.parametrize('text', ['"\\' * (1 << 19), '"' * (1 << 20), '\\"' * (1 << 19)])
def test_counting_the_nesting_of_a_request_of_any_text_is_one_pass(text):
    """A string left open, its quotes escaped, would make a pattern that gives back what it
    matched try every quote again: minutes for one request of 1 MiB, the studio held."""
    code = 'import sys\nfrom flatsim.studio.protocol import nested_deeper\nprint(nested_deeper(sys.stdin.read()))'
    done = subprocess.run([sys.executable, '-c', code], input=text, capture_output=True, text=True,
                          timeout=30)
    assert done.stdout.strip() == 'False', done.stderr
