"""The chase view's stream without a browser or a ROS master: the ball pixels of a camera image
by third, and the drive commands of the last 10 s, only while a page shows the view."""
import json
import struct

import cv2
import numpy as np
import pytest

from flatsim.loading.sdf_world import parse_world
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.studio import chase
from flatsim.studio.chase import CommandLog, DriveCommand
from flatsim.studio.hub import Hub
from flatsim.studio.sim_world import SimWorld
from flatsim.studio.world import find_sensor
from flatsim.world.sim import Simulation
from test_studio_hub import Tab

# A white ball (emissive: pure white in the camera) ahead of the robot and left of centre.
WORLD = '''<sdf version="1.6"><world name="w">
  <model name="white_ball"><pose>1.2 0.2 0.1 0 0 0</pose><link name="link">
    <collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
    <visual name="v"><geometry><sphere><radius>0.1</radius></sphere></geometry>
      <material><ambient>1 1 1 1</ambient><diffuse>1 1 1 1</diffuse><specular>1 1 1 1</specular>
        <emissive>1 1 1 1</emissive></material></visual>
  </link></model>
</world></sdf>'''

ROBOT = '''<robot name="bot">
  <link name="base"><collision><geometry><box size="0.4 0.3 0.2"/></geometry></collision>
    <inertial><mass value="5"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="eye"/>
  <joint name="eye_joint" type="fixed"><parent link="base"/><child link="eye"/>
    <origin xyz="0.2 0 0.1"/></joint>
  <gazebo reference="eye"><sensor type="camera" name="cam"><update_rate>10</update_rate>
    <camera><horizontal_fov>1.0</horizontal_fov><image><width>640</width><height>96</height></image>
      <clip><near>0.05</near><far>50</far></clip></camera>
    <plugin name="c" filename="libgazebo_ros_camera.so"><cameraName>cam</cameraName></plugin>
  </sensor></gazebo>
</robot>'''


class Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def ask(hub, session, tab, **request):
    hub.receive(session, json.dumps(request))
    return tab.last('reply')


def split(frame):
    length = struct.unpack('>I', frame[:4])[0]
    return json.loads(frame[4:4 + length]), frame[4 + length:]


@pytest.fixture
def sim():
    world = Simulation(parse_world(WORLD))
    world.spawn_robot('bot', load_robot(ROBOT), Pose(0.0, 0.0))
    return world


@pytest.fixture
def hub(sim):
    return Hub(SimWorld(sim), clock=Clock())


def expected_counts(sim):
    """The course's rule spelled out pixel by pixel: pure white, column < w/3 left, < 2w/3 middle."""
    pixels = sim.sense(find_sensor(sim, 'bot::cam', 'camera'))
    counts = [0, 0, 0]
    width = pixels.shape[1]
    for row, column in zip(*np.nonzero((pixels == 255).all(axis=2))):
        counts[0 if column < width / 3 else 1 if column < 2 * width / 3 else 2] += 1
    return counts


def test_the_chase_view_shows_the_ball_pixels_by_third_while_open(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    hub.tick()
    assert tab.frames == []
    assert ask(hub, session, tab, type='chase', sensor='bot::cam', on=True)['ok']
    hub.tick()
    (frame,) = tab.frames
    header, jpeg = split(frame)
    counts = expected_counts(sim)
    # The ball straddles the line between the left and middle thirds.
    assert counts[0] > 0 and counts[1] > 0 and counts[2] == 0
    assert header['counts'] == counts
    assert (header['type'], header['sensor'], header['image_width'], header['image_height']) == (
        'chase_image', 'bot::cam', 640, 96)
    assert header['thirds'] == [214, 427]
    assert (header['width'], header['height']) == (480, 72)
    # The ball's pixels are painted in the highlight colour, the rest dimmed.
    picture = cv2.cvtColor(cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_COLOR),
                           cv2.COLOR_BGR2RGB).astype(int)
    magenta = (picture[..., 0] > 200) & (picture[..., 1] < 80) & (picture[..., 2] > 200)
    assert magenta.sum() > 0.5 * sum(counts) * (480 / 640) ** 2
    # Nothing is left near white: what the eye takes for the ball is what the rule counts.
    assert not (picture > 180).all(axis=2).any()
    ask(hub, session, tab, type='chase', on=False)
    hub.clock.now += 1.0
    hub.tick()
    assert len(tab.frames) == 1


def test_the_strip_has_the_drive_commands_of_the_last_10_s_while_open(hub, sim):
    tab = Tab()
    session = hub.connect(tab)
    assert hub.world.command_log is None
    ask(hub, session, tab, type='chase', sensor='bot::cam', on=True)
    log = hub.world.command_log
    assert isinstance(log, CommandLog)
    sim.time = 12.0
    log.add(DriveCommand(1.5, 'bot', 0.5, 0.0, '/drive_bot'))           # older than 10 s
    log.add(DriveCommand(3.0, 'bot', 0.0, 0.5, '/drive_bot'))
    log.add(DriveCommand(3.5, 'other', 0.2, 0.0, '/elsewhere'))         # another robot's
    log.add(DriveCommand(11.0, 'bot', float('nan'), 0.0, '/rostopic_1', 'linear.x is nan'))
    hub.tick()
    header, _ = split(tab.frames[-1])
    assert header['commands'] == [
        {'t': 3.0, 'linear_x': 0.0, 'angular_z': 0.5, 'sender': '/drive_bot', 'refused': ''},
        {'t': 11.0, 'linear_x': 'nan', 'angular_z': 0.0, 'sender': '/rostopic_1',
         'refused': 'linear.x is nan'}]
    assert header['window'] == 10.0
    # A page out of sight, or a closed view, costs the simulator no recording.
    ask(hub, session, tab, type='stream', on=False)
    assert hub.world.command_log is None
    ask(hub, session, tab, type='stream', on=True)
    assert hub.world.command_log is not None
    hub.disconnect(session)
    assert hub.world.command_log is None


def test_closed_the_chase_view_costs_no_work(hub, monkeypatch):
    made = []
    real = chase.chase_frame
    monkeypatch.setattr(chase, 'chase_frame', lambda *args: made.append(args) or real(*args))
    tab = Tab()
    session = hub.connect(tab)
    # The camera panel alone: camera frames, and no chase frame, no commands recorded.
    ask(hub, session, tab, type='camera', sensor='bot::cam', on=True)
    hub.tick()
    assert len(tab.frames) == 1 and made == [] and hub.world.command_log is None
    ask(hub, session, tab, type='chase', sensor='bot::cam', on=True)
    hub.clock.now += 1.0
    hub.tick()
    assert len(made) == 1 and len(tab.frames) == 3
    ask(hub, session, tab, type='chase', on=False)
    hub.clock.now += 1.0
    hub.tick()
    assert len(made) == 1 and hub.world.command_log is None


def test_a_chase_view_of_a_camera_that_is_not_there_is_refused(hub):
    tab = Tab()
    session = hub.connect(tab)
    reply = ask(hub, session, tab, type='chase', sensor='bot::nose', on=True)
    assert not reply['ok'] and reply['message'] == "there is no camera 'bot::nose' in the world (cameras: bot::cam)"
    reply = ask(hub, session, tab, type='chase', on=True)
    assert not reply['ok'] and reply['message'] == 'chase needs sensor ("model::sensor") to turn it on'


def test_the_command_log_forgets_a_run_that_time_went_back_on():
    log = CommandLog()
    log.add(DriveCommand(5.0, 'bot', 0.5, 0.0, '/drive_bot'))
    # A command that came in after the camera frame of sim time 4.99 was taken still shows.
    assert len(log.recent('bot', 4.99)) == 1
    log.add(DriveCommand(15.5, 'bot', 0.5, 0.0, '/drive_bot'))
    assert len(log.recent('bot', 15.4)) == 1
    # Reset World: sim time starts over; the old run's commands are far ahead of it.
    assert log.recent('bot', 0.5) == []
    log.add(DriveCommand(0.6, 'bot', 0.0, 0.0, '/drive_bot'))
    log.add(DriveCommand(0.2, 'bot', 0.1, 0.0, '/drive_bot'))
    assert [c.linear_x for c in log.recent('bot', 0.7)] == [0.1]


def test_thirds_start_where_the_course_rule_puts_them():
    # column < width / 3 is left: 800 / 3 = 266.7, so 267 columns are left; 900 / 3 = 300 exactly.
    assert chase.third_starts(800) == (267, 534)
    assert chase.third_starts(900) == (300, 600)
    assert chase.third_starts(1) == (1, 1)
    mask = np.zeros((2, 800), dtype=bool)
    mask[0, [0, 266, 267, 533, 534, 799]] = True
    assert chase.counts_by_third(mask) == (2, 2, 2)
    mono = np.array([[255, 254, 255]], dtype=np.uint8)
    assert chase.counts_by_third(chase.ball_pixels(mono)) == (1, 0, 1)


@pytest.mark.parametrize('width, height', [(4000, 30), (801, 801), (481, 10), (64, 48)])
def test_no_ball_pixel_is_lost_from_the_smaller_picture(width, height):
    for column, row in [(0, 0), (width - 1, height - 1), (width // 2 + 1, height // 3)]:
        pixels = np.full((height, width, 3), 200, dtype=np.uint8)
        pixels[row, column] = 255
        picture = chase.highlighted(pixels, chase.ball_pixels(pixels))
        assert picture.shape[1] == min(width, chase.CHASE_MAX_WIDTH)
        assert ((picture == chase.HIGHLIGHT).all(axis=2)).sum() >= 1
        # Only near the ball pixel.
        rows, columns = np.nonzero((picture == chase.HIGHLIGHT).all(axis=2))
        scale = picture.shape[1] / width
        assert abs(columns.mean() - column * scale) <= 2 and abs(rows.mean() - row * scale) <= 2
    mono = np.full((height, width), 254, dtype=np.uint8)
    mono[0, 0] = 255
    assert (chase.highlighted(mono, chase.ball_pixels(mono))[0, 0] == chase.HIGHLIGHT).all()


def fake_node(log=None):
    """What FlatsimNode's /cmd_vel callbacks use of the node: its lock, sim time and log."""
    import threading
    from types import SimpleNamespace

    from flatsim.ros.node import FlatsimNode
    node = SimpleNamespace(lock=threading.RLock(), sim=SimpleNamespace(time=4.0), command_log=log,
                           lockstep=SimpleNamespace(command_arrived=lambda name: None))
    node.record_command = lambda robot, msg, refused='': FlatsimNode.record_command(
        node, robot, msg, refused)
    return node


def twist(linear, angular, sender):
    from geometry_msgs.msg import Twist
    msg = Twist()
    msg.linear.x, msg.angular.z = linear, angular
    msg._connection_header = {'callerid': sender}
    return msg


def test_the_node_records_drive_commands_only_while_a_view_is_open(monkeypatch):
    from types import SimpleNamespace

    from flatsim.ros.controllers import ControlIo
    from flatsim.ros.node import FlatsimNode
    from flatsim.world.drive import InvalidCommand

    def set_command(linear, angular, sideways):
        if linear != linear:
            raise InvalidCommand('linear.x is nan')
    robot = SimpleNamespace(name='bot', drive=SimpleNamespace(set_command=set_command))
    warned = []
    monkeypatch.setattr('flatsim.ros.node.rospy.logwarn_throttle', lambda *args: warned.append(args))
    node = fake_node()
    FlatsimNode.on_cmd_vel(node, twist(0.5, 0.0, '/drive_bot'), robot)
    assert node.command_log is None
    node.command_log = CommandLog()
    FlatsimNode.on_cmd_vel(node, twist(0.5, 0.0, '/drive_bot'), robot)
    FlatsimNode.on_cmd_vel(node, twist(float('nan'), 0.0, '/rostopic_1'), robot)
    # ros_control's diff_drive_controller takes /cmd_vel too.
    io = SimpleNamespace(node=node, robot=robot)
    got = []
    ControlIo.on_twist(io, twist(0.0, -0.5, '/drive_bot'), (None, lambda *args: got.append(args)))
    assert got == [(0.0, -0.5, 4.0)]
    recorded = node.command_log.recent('bot', 4.0)
    assert [(c.linear_x, c.angular_z, c.sender, c.refused) for c in recorded[::2]] == [
        (0.5, 0.0, '/drive_bot', ''), (0.0, -0.5, '/drive_bot', '')]
    assert recorded[1].sender == '/rostopic_1' and recorded[1].refused == 'linear.x is nan'


def test_reset_world_clears_the_strip_at_once():
    from types import SimpleNamespace

    from flatsim.ros.node import FlatsimNode
    node = fake_node(CommandLog())
    node.command_log.add(DriveCommand(3.0, 'bot', 0.5, 0.0, '/drive_bot'))
    node.sim.reset_time = lambda: setattr(node.sim, 'time', 0.0)
    node.last_scans = {}
    node.gazebo = SimpleNamespace()
    node.lockstep.interrupt = lambda: None
    FlatsimNode.reset_time(node)
    assert node.command_log.recent('bot', 0.0) == []
