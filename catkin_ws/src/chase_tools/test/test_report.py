"""chase_tools.report on bags written here with rosbags: whole, cut short, lacking topics, not bags."""
import numpy as np
import pytest
from rosbags.rosbag1 import Writer
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.msg import get_types_from_msg

import cv2
from chase_tools import bag_tracks, drawing, report
from flatsim.ros.overhead import rgb8

WORLD = """<?xml version="1.0"?>
<sdf version="1.6">
  <world name="corridor">
    <include><uri>model://ground_plane</uri></include>
    <model name="wall">
      <static>true</static>
      <pose>3 0 0.5 0 0 0</pose>
      <link name="link">
        <collision name="c"><geometry><box><size>0.2 4 1</size></box></geometry></collision>
        <visual name="v">
          <geometry><box><size>0.2 4 1</size></box></geometry>
          <material><ambient>0 0 1 1</ambient><diffuse>0 0 1 1</diffuse></material>
        </visual>
      </link>
    </model>
    <model name="white_ball">
      <pose>2 0 0.1 0 0 0</pose>
      <link name="link">
        <inertial><mass>0.5</mass></inertial>
        <collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
        <visual name="v">
          <geometry><sphere><radius>0.1</radius></sphere></geometry>
          <material><ambient>1 1 1 1</ambient><diffuse>1 1 1 1</diffuse>
            <emissive>1 1 1 1</emissive></material>
        </visual>
      </link>
    </model>
  </world>
</sdf>
"""
MODEL_STATES_MSG = """string[] name
geometry_msgs/Pose[] pose
geometry_msgs/Twist[] twist
"""
# The robot drives along x at SPEED from the origin towards the ball at (2, 0); it is
# within 0.4 m from x = 1.6, i.e. t = 3.56 s, first seen by the 10 Hz states at 3.6 s.
SPEED = 0.45
DURATION = 4.0
BALL = (2.0, 0.0)
FIRST_WHITE_FRAME = 3                          # frames at 0, 0.5, 1.0, 1.5 s: the fourth has white
FRAME_SHAPE = (12, 16, 3)


def _typestore():
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg(MODEL_STATES_MSG, 'gazebo_msgs/msg/ModelStates'))
    # Bags recorded before flatsim served Gazebo's API carry its own copy of the type.
    store.register(get_types_from_msg(MODEL_STATES_MSG, 'flatsim/msg/ModelStates'))
    return store


def _pose(store, x, y):
    types = store.types
    return types['geometry_msgs/msg/Pose'](types['geometry_msgs/msg/Point'](x, y, 0.0),
                                           types['geometry_msgs/msg/Quaternion'](0.0, 0.0, 0.0, 1.0))


def _twist(store, vx=0.0):
    vector = store.types['geometry_msgs/msg/Vector3']
    return store.types['geometry_msgs/msg/Twist'](vector(vx, 0.0, 0.0), vector(0.0, 0.0, 0.0))


def _header(store, t, seq=0):
    time = store.types['builtin_interfaces/msg/Time'](int(t), int(round((t % 1) * 1e9)))
    return store.types['std_msgs/msg/Header'](seq, time, 'frame')


def frame_at(index):
    image = np.full(FRAME_SHAPE, 90, dtype=np.uint8)
    image[:, :, 0] = index                    # tells the frames apart
    if index >= FIRST_WHITE_FRAME:
        image[5:7, 8:10] = 255
    return image


def write_bag(path, with_states=True, compression=None, chunk_bytes=None, wall_per_sim=None):
    """wall_per_sim: stamp messages with a wall clock running this much faster than sim
    time, as rosbag does without use_sim_time; by default they carry sim time."""
    store = _typestore()
    types = store.types
    writer = Writer(path)
    if compression:
        writer.set_compression(compression)
    if chunk_bytes:
        writer.chunk_threshold = chunk_bytes
    writer.open()
    topics = {
        'clock': ('/clock', 'rosgraph_msgs/msg/Clock'),
        'states': ('/gazebo/model_states', 'gazebo_msgs/msg/ModelStates'),
        'odom': ('/odom', 'nav_msgs/msg/Odometry'),
        'cmd': ('/cmd_vel', 'geometry_msgs/msg/Twist'),
        'scan': ('/scan', 'sensor_msgs/msg/LaserScan'),
        'camera': ('/camera/rgb/image_throttled', 'sensor_msgs/msg/Image'),
    }
    if not with_states:
        del topics['states']
    conns = {key: writer.add_connection(topic, msgtype, typestore=store)
             for key, (topic, msgtype) in topics.items()}

    def put(key, t, msg):
        if key in conns:
            received = 1000.0 + t * wall_per_sim if wall_per_sim else t
            writer.write(conns[key], int(round(received * 1e9)),
                         store.serialize_ros1(msg, msg.__msgtype__))

    for step in range(int(DURATION * 100) + 1):
        t = step / 100.0
        put('clock', t, types['rosgraph_msgs/msg/Clock'](_header(store, t).stamp))
        if step % 10 == 0:
            x = SPEED * t
            zero = _twist(store)
            put('states', t, types['gazebo_msgs/msg/ModelStates'](
                ['ground_plane', 'my_robot', 'white_ball'],
                [_pose(store, 0, 0), _pose(store, x, 0.0), _pose(store, *BALL)], [zero] * 3))
            covariance = np.zeros(36)
            put('odom', t, types['nav_msgs/msg/Odometry'](
                _header(store, t), 'base',
                types['geometry_msgs/msg/PoseWithCovariance'](_pose(store, x, 0.0), covariance),
                types['geometry_msgs/msg/TwistWithCovariance'](_twist(store, SPEED), covariance)))
            put('cmd', t, _twist(store, SPEED))
            put('scan', t, types['sensor_msgs/msg/LaserScan'](
                _header(store, t), -1.0, 1.0, 0.5, 0.0, 0.1, 0.1, 10.0,
                np.ones(5, dtype=np.float32), np.zeros(0, dtype=np.float32)))
        if step % 50 == 0:
            index = step // 50
            put('camera', t, types['sensor_msgs/msg/Image'](
                _header(store, t, seq=15 * index + 1), FRAME_SHAPE[0], FRAME_SHAPE[1], 'rgb8', 0,
                FRAME_SHAPE[1] * 3, frame_at(index).ravel()))
    writer.close()
    return path


@pytest.fixture(scope='module')
def world(tmp_path_factory):
    path = tmp_path_factory.mktemp('world') / 'corridor.world'
    path.write_text(WORLD)
    return str(path)


@pytest.fixture(scope='module')
def whole_bag(tmp_path_factory):
    return str(write_bag(tmp_path_factory.mktemp('bags') / 'whole.bag'))


def read_png(path):
    return cv2.cvtColor(cv2.imread(str(path), cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)


def test_whole_bag_reads_every_topic(whole_bag):
    summary = bag_tracks.read_bag(whole_bag)
    assert summary.notes == []
    counts = {topic: count for topic, (_, count) in summary.topics.items()}
    assert counts == {'/clock': 401, '/gazebo/model_states': 41, '/odom': 41, '/cmd_vel': 41,
                      '/scan': 41, '/camera/rgb/image_throttled': 9}
    assert summary.robot_source == 'model states'
    assert summary.robot.length() == pytest.approx(SPEED * DURATION)
    assert summary.clock == (0.0, DURATION)
    assert summary.camera_frames == 9
    assert summary.camera_last_seq == 15 * 8 + 1
    assert summary.first_sight_time == pytest.approx(1.5)
    np.testing.assert_array_equal(summary.first_sight, frame_at(FIRST_WHITE_FRAME))


def test_first_sight_says_how_close_the_recorded_frames_come():
    def line(before, first):
        summary = bag_tracks.BagSummary(path='x.bag')
        summary.first_sight = frame_at(FIRST_WHITE_FRAME)
        summary.first_sight_time, summary.first_sight_seq = first
        if before:
            summary.before_sight_time, summary.before_sight_seq = before
        return report.first_sight_line(summary, start_time=1.0)
    assert line((2.0, 30), (2.5, 31)) == ('at 1.5 s of sim time '
                                          '(first_sight.png, the camera\'s first frame that shows it)')
    assert line(None, (1.0, 7)) == ('by 0.0 s of sim time: first_sight.png, the first recorded frame, '
                                    'already shows it')
    assert line((2.0, 0), (2.5, 0)) == ('between 1.0 s and 1.5 s of sim time; first_sight.png is the first '
                                        'recorded frame that shows it, at 1.5 s')


def test_report_files_of_a_whole_bag(whole_bag, world, tmp_path):
    built, _ = report.build(whole_bag, str(tmp_path), world)
    assert built.outcome.reached
    assert built.outcome.time_to_reach == pytest.approx(3.6)
    assert built.outcome.closest == pytest.approx(2.0 - SPEED * DURATION)
    text = (tmp_path / 'summary.md').read_text()
    assert '- Outcome: reached' in text
    assert '3.6 s of sim time' in text
    assert 'Path length: 1.80 m (from model states)' in text
    assert '121 published' in text and '9 recorded on `/camera/rgb/image_throttled`' in text
    # Thinned frames: the camera first saw the ball after the last recorded frame without it.
    assert ('- First sight of the ball: between 1.0 s and 1.5 s of sim time; first_sight.png is the first '
            'recorded frame that shows it, at 1.5 s (14 camera frames before it were not recorded)\n') in text
    np.testing.assert_array_equal(read_png(tmp_path / 'first_sight.png'),
                                  frame_at(FIRST_WHITE_FRAME))

    image = read_png(tmp_path / 'trajectory.png')
    frame = built.frame
    assert image.shape == frame.shape
    assert tuple(image[frame.pixel_of(*BALL)[::-1]]) == drawing.BALL_MARK_COLOR
    assert tuple(image[frame.pixel_of(3.0, 1.5)[::-1]]) == rgb8((0, 0, 1))
    on_path = np.all(image == drawing.PATH_COLOR, axis=2)
    # The path runs 1.8 m along y = 0; most of it is not under the start or end marks.
    assert on_path.sum() > 0.8 * 1.8 / frame.resolution
    first, _ = frame.pixel_of(0.3, 0.0)
    last, _ = frame.pixel_of(1.5, 0.0)
    rows = np.flatnonzero(on_path[:, first:last].any(axis=1))
    assert rows.size and abs(frame.to_world(first, rows.mean())[1]) < 3 * frame.resolution


def test_cut_bag_reports_what_it_holds(whole_bag, world, tmp_path, capsys):
    cut = tmp_path / 'cut.bag'
    small_chunks = write_bag(tmp_path / 'chunks.bag', chunk_bytes=4096)
    data = small_chunks.read_bytes()
    cut.write_bytes(data[:len(data) // 2])
    out = tmp_path / 'out'
    assert report.main([str(cut), '--world', world, '--output', str(out)]) == 0
    text = (out / 'summary.md').read_text()
    assert 'cut short' in text and 'no usable index' in text
    assert 'cut short' in capsys.readouterr().err
    summary = bag_tracks.read_bag(str(cut))
    assert 0 < len(summary.robot) < 41
    # What is left is the start of the run, unchanged.
    whole = bag_tracks.read_bag(whole_bag)
    np.testing.assert_allclose(summary.robot.x, whole.robot.x[:len(summary.robot)])
    assert (out / 'trajectory.png').exists()


@pytest.mark.parametrize('compression', [Writer.CompressionFormat.LZ4, Writer.CompressionFormat.BZ2],
                         ids=['lz4', 'bz2'])
def test_cut_compressed_bag_keeps_its_complete_chunks(tmp_path, compression):
    bag = write_bag(tmp_path / 'c.bag', compression=compression, chunk_bytes=4096)
    data = bag.read_bytes()
    cut = tmp_path / 'cut.bag'
    cut.write_bytes(data[:len(data) * 2 // 3])
    summary = bag_tracks.read_bag(str(cut))
    assert any('cut short' in note for note in summary.notes)
    assert 0 < len(summary.robot) < 41
    assert summary.topics['/clock'][1] < 401


def test_bag_without_model_states_uses_odometry(tmp_path, world):
    bag = write_bag(tmp_path / 'odom.bag', with_states=False)
    built, summary = report.build(str(bag), str(tmp_path / 'out'), world)
    assert summary.robot_source.startswith('odometry')
    assert summary.robot.length() == pytest.approx(SPEED * DURATION)
    text = (tmp_path / 'out' / 'summary.md').read_text()
    assert 'no model states in the bag' in text
    assert 'drawn where the world file puts it' in text
    # The ball's place comes from the world file.
    assert built.outcome.time_to_reach == pytest.approx(3.6)


def test_wall_stamped_bag_gives_sim_times_and_real_time_factor(tmp_path, world):
    bag = write_bag(tmp_path / 'wall.bag', wall_per_sim=2.0)
    built, summary = report.build(str(bag), str(tmp_path / 'out'), world)
    assert summary.robot.t[0] == pytest.approx(0.0) and summary.robot.t[-1] == pytest.approx(DURATION)
    assert built.outcome.time_to_reach == pytest.approx(3.6)
    text = (tmp_path / 'out' / 'summary.md').read_text()
    assert 'Real-time factor: 0.50 (4.0 s of sim time in 8.0 s of wall time)' in text


def test_run_facts_give_the_real_time_factor_and_outcome(whole_bag, world, tmp_path):
    facts = report.RunFacts(wall_seconds=2.0, sim_seconds=3.0, reached=False, detail='timed out')
    report.build(whole_bag, str(tmp_path), world, run=facts)
    text = (tmp_path / 'summary.md').read_text()
    assert 'Real-time factor: 1.50 (3.0 s of sim time in 2.0 s of wall time)' in text
    assert '- Outcome: not reached (timed out)' in text


def test_damaged_messages_are_skipped_and_counted(tmp_path):
    store = _typestore()
    zero = _twist(store)
    writer = Writer(tmp_path / 'damaged.bag')
    writer.open()
    conn = writer.add_connection('/flatsim/model_states', 'flatsim/msg/ModelStates', typestore=store)
    for step in range(4):
        msg = store.types['flatsim/msg/ModelStates'](['my_robot'], [_pose(store, step, 0.0)], [zero])
        data = store.serialize_ros1(msg, msg.__msgtype__)
        writer.write(conn, step * 10**8, data if step % 2 else data[:9])
    writer.close()
    summary = bag_tracks.read_bag(str(tmp_path / 'damaged.bag'))
    np.testing.assert_allclose(summary.robot.x, [1.0, 3.0])
    assert summary.undecodable == 2
    assert any('2 messages in all could not be decoded' in note for note in summary.notes)


@pytest.mark.parametrize('content', [b'', b'not a bag\n', b'#ROSBAG V2.0\n\x05\x00'],
                         ids=['empty', 'text', 'header-cut'])
def test_unreadable_files_give_a_summary_not_a_traceback(tmp_path, content, capsys):
    bag = tmp_path / 'bad.bag'
    bag.write_bytes(content)
    out = tmp_path / 'out'
    assert report.main([str(bag), '--output', str(out)]) == 1
    text = (out / 'summary.md').read_text()
    assert '- Outcome: not reached' in text
    assert 'no sim clock in the bag' in text
    assert 'Traceback' not in capsys.readouterr().err


def test_missing_bag_and_world_are_notes(tmp_path):
    built, _ = report.build(str(tmp_path / 'nothing.bag'), str(tmp_path / 'out'),
                            str(tmp_path / 'nothing.world'))
    text = (tmp_path / 'out' / 'summary.md').read_text()
    assert 'there is no bag at' in text
    assert 'the world could not be read' in text
    assert not built.outcome.reached
