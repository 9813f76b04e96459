"""A report of a chase from a ROS 1 bag: a map with the path, the ball's first sight, a summary.

  rosrun chase_tools report BAG [--world WORLD] [--output DIR] [--robot my_robot] [--ball NAME]

No ROS here: the bag is read with rosbags, so no master is needed. A bag that
lacks topics, was never closed, or was cut short still gives a report of what
it holds, with a note of what is missing in summary.md and on stderr.

Writes into the output folder:
  trajectory.png  the world from above (the same 2.5D primitives flatsim uses),
                  the robot's path, its start and end, the ball where it was
  first_sight.png the first recorded camera frame with a pure white pixel (summary.md
                  says how close to the camera's own first sight it is)
  summary.md      outcome, time to reach, path length, camera frames, real-time factor
"""
import argparse
import bz2
import mmap
import os
import struct
import sys
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import cv2
import lz4.frame
import numpy as np
from rosbags.rosbag1 import Reader, ReaderError
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.msg import get_types_from_msg, normalize_msgtype

from chase_tools import arguments
from chase_tools.reach import CENTRE_REACH_M
from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world, white_balls
from flatsim.ros.overhead import fit_frame, moving_indices, render_static
from flatsim.world.scene import Scene
from flatsim.world.sim import Simulation

REACH_M = CENTRE_REACH_M
ROBOT_NAME = 'my_robot'
# Roles of the topics a chase bag holds, found by message type so that remapped names work.
MODEL_STATES_TYPES = ('flatsim/msg/ModelStates', 'gazebo_msgs/msg/ModelStates')
ODOM_TYPE = 'nav_msgs/msg/Odometry'
TWIST_TYPE = 'geometry_msgs/msg/Twist'
SCAN_TYPE = 'sensor_msgs/msg/LaserScan'
IMAGE_TYPE = 'sensor_msgs/msg/Image'
CLOCK_TYPE = 'rosgraph_msgs/msg/Clock'
EXPECTED = (('model states', MODEL_STATES_TYPES), ('odometry', (ODOM_TYPE,)),
            ('drive commands', (TWIST_TYPE,)), ('laser scans', (SCAN_TYPE,)),
            ('camera images', (IMAGE_TYPE,)), ('sim clock', (CLOCK_TYPE,)))

MAP_RESOLUTION = 0.01                          # m per pixel, unless the world is too big
MAP_MAX_PIXELS = 1000
PATH_COLOR = (230, 30, 30)
START_COLOR = (20, 170, 60)
END_COLOR = (40, 90, 230)
BALL_MARK_COLOR = (255, 0, 255)
TEXT_COLOR = (0, 0, 0)
MARK_RADIUS_PX = 6

_NO_ROBOT = 'no robot pose in the bag'


# -- reading a bag, indexed or not ---------------------------------------------------------
@dataclass
class RawMessage:
    topic: str
    msgtype: str                               # normalised: pkg/msg/Type
    msgdef: str
    time_ns: int                               # the bag's receive time
    data: bytes


BAG_MAGIC = b'#ROSBAG V2.0\n'
_OP_MSG_DATA, _OP_CHUNK, _OP_CONNECTION = 0x02, 0x05, 0x07


def _header_fields(blob):
    fields = {}
    pos = 0
    while pos + 4 <= len(blob):
        (size,) = struct.unpack_from('<I', blob, pos)
        pos += 4
        name, sep, value = bytes(blob[pos:pos + size]).partition(b'=')
        if not sep or pos + size > len(blob):
            raise ValueError('bad header field')
        fields[name.decode()] = value
        pos += size
    return fields


def _records(buf, pos):
    """(header fields, data, complete) of each record from pos; the last may be incomplete."""
    end = len(buf)
    while pos + 4 <= end:
        (header_len,) = struct.unpack_from('<I', buf, pos)
        if pos + 8 + header_len > end:
            return
        try:
            header = _header_fields(buf[pos + 4:pos + 4 + header_len])
        except (ValueError, UnicodeDecodeError):
            return
        (data_len,) = struct.unpack_from('<I', buf, pos + 4 + header_len)
        start = pos + 8 + header_len
        complete = start + data_len <= end
        yield header, buf[start:min(start + data_len, end)], complete
        if not complete:
            return
        pos = start + data_len


def _decompress(compression, data, complete):
    if compression == b'none':
        return bytes(data)
    if compression == b'lz4':
        return lz4.frame.LZ4FrameDecompressor().decompress(bytes(data)) if not complete \
            else lz4.frame.decompress(bytes(data))
    if compression == b'bz2':
        return bz2.BZ2Decompressor().decompress(bytes(data))
    raise ValueError('compression %r' % compression.decode(errors='replace'))


def scan_bag(path, notes):
    """Every message a ROS 1 bag holds, read record by record without its index.

    For bags that were never closed or were cut short: the index at the end
    is missing, but the chunks before it are intact, and so is the start of a
    chunk that was cut.
    """
    with open(path, 'rb') as stream:
        size = os.fstat(stream.fileno()).st_size
        if stream.read(len(BAG_MAGIC)) != BAG_MAGIC or size <= len(BAG_MAGIC):
            raise FlatsimError('%s is not a ROS 1 bag (it does not start with %r)'
                               % (path, BAG_MAGIC.decode().strip()))
        with mmap.mmap(stream.fileno(), 0, access=mmap.ACCESS_READ) as buf:
            yield from _scan_records(buf, len(BAG_MAGIC), size, notes)


def _scan_records(buf, start, size, notes):
    connections = {}
    cut = False
    for header, data, complete in _records(buf, start):
        op = header.get('op', b'\0')[0]
        if op == _OP_CHUNK:
            try:
                body = _decompress(header.get('compression', b'none'), data, complete)
            except (ValueError, RuntimeError, OSError, EOFError) as err:
                notes.append('a chunk of the bag could not be decompressed (%s); skipped' % err)
                continue
            inner_complete = True
            for inner, inner_data, inner_ok in _records(body, 0):
                inner_complete = inner_ok
                if not inner_ok:
                    break
                message = _message_record(inner, inner_data, connections)
                if message is not None:
                    yield message
            cut = cut or not complete or not inner_complete
        else:
            message = _message_record(header, data, connections) if complete else None
            if message is not None:
                yield message
            cut = cut or not complete
    if cut:
        notes.append('the bag is cut short: its last record is incomplete at byte %d; '
                     'everything before it is reported' % size)


def _message_record(header, data, connections):
    op = header.get('op', b'\0')[0]
    if op == _OP_CONNECTION:
        fields = _header_fields(data)
        conn = struct.unpack('<I', header['conn'])[0]
        connections[conn] = (fields.get('topic', header.get('topic', b'')).decode(),
                             normalize_msgtype(fields['type'].decode()),
                             fields.get('message_definition', b'').decode())
    elif op == _OP_MSG_DATA:
        conn = struct.unpack('<I', header['conn'])[0]
        if conn in connections:
            secs, nsecs = struct.unpack('<II', header['time'])
            topic, msgtype, msgdef = connections[conn]
            return RawMessage(topic, msgtype, msgdef, secs * 10**9 + nsecs, bytes(data))
    return None


def bag_messages(path, notes):
    """Every message of the bag at path; problems are appended to notes.

    Raises FlatsimError only if the file is not a ROS 1 bag at all.
    """
    with open(path, 'rb') as stream:
        if stream.read(len(BAG_MAGIC)) != BAG_MAGIC:
            raise FlatsimError('%s is not a ROS 1 bag (it does not start with %r)'
                               % (path, BAG_MAGIC.decode().strip()))
    try:
        reader = Reader(path)
        reader.open()
    except ReaderError:
        notes.append('the bag has no usable index: it was not closed, or it is cut short; '
                     'its records are read one by one')
        yield from scan_bag(path, notes)
        return
    try:
        for conn, time_ns, data in reader.messages():
            yield RawMessage(conn.topic, conn.msgtype, conn.msgdef.data, time_ns, data)
    except ReaderError as err:
        notes.append('reading stopped early: %s' % err)
    finally:
        reader.close()


# -- what the bag says about the chase ------------------------------------------------------
@dataclass
class Track:
    """Positions over time: t (s, sim time once mapped), x, y (m)."""
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    y: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @classmethod
    def of(cls, rows):
        rows = np.asarray(rows, dtype=float).reshape(-1, 3)
        return cls(rows[:, 0], rows[:, 1], rows[:, 2])

    def __len__(self):
        return len(self.t)

    def points(self):
        return np.column_stack([self.x, self.y])

    def length(self):
        return float(np.sum(np.hypot(np.diff(self.x), np.diff(self.y))))

    def at(self, times):
        """Positions at the given times, held at the ends."""
        return np.column_stack([np.interp(times, self.t, self.x), np.interp(times, self.t, self.y)])


@dataclass
class BagSummary:
    path: str
    topics: Dict[str, List] = field(default_factory=dict)      # topic -> [msgtype, count]
    robot: Track = field(default_factory=Track)
    robot_source: str = ''
    ball: Track = field(default_factory=Track)
    clock: Optional[tuple] = None              # (first, last) sim seconds
    bag_span: Optional[tuple] = None           # (first, last) receive time, s
    camera_topic: str = ''
    camera_frames: int = 0
    camera_last_seq: int = 0
    first_sight: Optional[np.ndarray] = None   # rgb frame
    first_sight_time: Optional[float] = None
    first_sight_seq: int = 0
    # The recorded frame just before first sight, which does not show the ball: with it, when
    # the camera was thinned, the camera's own first sight lies between the two.
    before_sight_time: Optional[float] = None
    before_sight_seq: Optional[int] = None
    undecodable: int = 0
    notes: List[str] = field(default_factory=list)


class _Collector:
    """Turns the bag's messages into a BagSummary, deserialising only what is needed."""

    def __init__(self, summary, robot_name, ball_name):
        self.summary = summary
        self.robot_name = robot_name
        self.ball_name = ball_name
        self.typestore = get_typestore(Stores.ROS1_NOETIC)
        self.robot_rows, self.ball_rows, self.odom_rows = [], [], []
        self.clock_pairs = []                  # (receive s, clock s)

    def _decode(self, message):
        if message.msgtype not in self.typestore.fielddefs:
            self.typestore.register(get_types_from_msg(message.msgdef, message.msgtype))
        return self.typestore.deserialize_ros1(message.data, message.msgtype)

    def add(self, message):
        entry = self.summary.topics.setdefault(message.topic, [message.msgtype, 0])
        entry[1] += 1
        received = message.time_ns * 1e-9
        span = self.summary.bag_span
        self.summary.bag_span = (received, received) if span is None else \
            (min(span[0], received), max(span[1], received))
        kind = message.msgtype
        if kind not in MODEL_STATES_TYPES + (ODOM_TYPE, CLOCK_TYPE, IMAGE_TYPE):
            return
        try:
            if kind == IMAGE_TYPE and self.summary.first_sight is not None \
                    and message.topic == self.summary.camera_topic:
                # Once the ball has been seen, a frame only counts: its seq is the first field.
                self.summary.camera_last_seq = max(self.summary.camera_last_seq,
                                                   struct.unpack_from('<I', message.data)[0])
                self.summary.camera_frames += 1
                return
            msg = self._decode(message)
        except Exception as err:
            # Damaged bytes fail in many ways inside a deserialiser; each such message is
            # counted and skipped, and the rest of the bag is still read.
            self.summary.undecodable += 1
            if self.summary.undecodable == 1:
                self.summary.notes.append('a %s message on %s could not be decoded (%s)'
                                          % (kind, message.topic, err))
            return
        if kind in MODEL_STATES_TYPES:
            names = list(msg.name)
            if self.robot_name in names:
                pose = msg.pose[names.index(self.robot_name)].position
                self.robot_rows.append((received, pose.x, pose.y))
            if self.ball_name in names:
                pose = msg.pose[names.index(self.ball_name)].position
                self.ball_rows.append((received, pose.x, pose.y))
        elif kind == ODOM_TYPE:
            pose = msg.pose.pose.position
            self.odom_rows.append((received, pose.x, pose.y))
        elif kind == CLOCK_TYPE:
            self.clock_pairs.append((received, msg.clock.sec + msg.clock.nanosec * 1e-9))
        else:
            self._add_frame(message, msg)

    def _add_frame(self, message, msg):
        summary = self.summary
        if not summary.camera_topic:
            summary.camera_topic = message.topic
        if message.topic != summary.camera_topic:
            return
        summary.camera_frames += 1
        summary.camera_last_seq = max(summary.camera_last_seq, int(msg.header.seq))
        image = image_to_rgb(msg)
        if image is None:
            if summary.camera_frames == 1:
                summary.notes.append('camera frames on %s are %s, which the report cannot show'
                                     % (message.topic, msg.encoding))
            return
        if np.any(np.all(image == 255, axis=2)):
            summary.first_sight = image
            summary.first_sight_time = message.time_ns * 1e-9
            summary.first_sight_seq = int(msg.header.seq)
        else:
            summary.before_sight_time = message.time_ns * 1e-9
            summary.before_sight_seq = int(msg.header.seq)

    def finish(self):
        summary = self.summary
        to_sim = self._sim_time_map()
        if self.robot_rows:
            summary.robot = _track(self.robot_rows, to_sim)
            summary.robot_source = 'model states'
        elif self.odom_rows:
            summary.robot = _track(self.odom_rows, to_sim)
            summary.robot_source = 'odometry (no model states in the bag)'
        summary.ball = _track(self.ball_rows, to_sim)
        if summary.first_sight_time is not None:
            summary.first_sight_time = float(to_sim(summary.first_sight_time))
        if summary.before_sight_time is not None:
            summary.before_sight_time = float(to_sim(summary.before_sight_time))
        if self.clock_pairs:
            clock = np.array(self.clock_pairs)[:, 1]
            summary.clock = (float(clock.min()), float(clock.max()))
        return summary

    def _sim_time_map(self):
        """Receive time to sim time. rosbag stamps with sim time when use_sim_time is set,
        with wall time otherwise; /clock tells which."""
        if len(self.clock_pairs) < 2:
            return lambda t: t
        pairs = np.array(sorted(self.clock_pairs))
        return lambda t: np.interp(t, pairs[:, 0], pairs[:, 1])


def _track(rows, to_sim):
    track = Track.of(sorted(rows))
    track.t = np.asarray(to_sim(track.t), dtype=float)
    return track


def image_to_rgb(msg):
    """An rgb8 (h, w, 3) array of a sensor_msgs/Image, or None for encodings not shown."""
    channels = {'rgb8': 3, 'bgr8': 3, 'rgba8': 4, 'bgra8': 4, 'mono8': 1}.get(msg.encoding)
    if channels is None or msg.height == 0 or msg.width == 0:
        return None
    data = np.frombuffer(bytes(msg.data), dtype=np.uint8)
    if data.size < msg.step * msg.height or msg.step < msg.width * channels:
        return None
    rows = data[:msg.step * msg.height].reshape(msg.height, msg.step)
    pixels = rows[:, :msg.width * channels].reshape(msg.height, msg.width, channels)
    if msg.encoding == 'mono8':
        return np.repeat(pixels, 3, axis=2)
    if msg.encoding.startswith('bgr'):
        return np.ascontiguousarray(pixels[:, :, 2::-1])
    return np.ascontiguousarray(pixels[:, :, :3])


def read_bag(path, robot_name=ROBOT_NAME, ball_name='white_ball'):
    """A BagSummary of the bag at path. Never raises for a damaged bag: see its notes."""
    summary = BagSummary(path=str(path))
    if not os.path.isfile(path):
        summary.notes.append('there is no bag at %s' % path)
        return summary
    collector = _Collector(summary, robot_name, ball_name)
    try:
        for message in bag_messages(str(path), summary.notes):
            collector.add(message)
    except FlatsimError as err:
        summary.notes.append(str(err))
    except (OSError, ValueError, KeyError, struct.error) as err:
        # UnicodeDecodeError is a ValueError: damaged bytes inside a record.
        summary.notes.append('the bag could not be read past a damaged record: %r' % err)
    summary = collector.finish()
    _note_missing(summary, robot_name, ball_name)
    return summary


def _note_missing(summary, robot_name, ball_name):
    present = {msgtype for msgtype, _ in summary.topics.values()}
    for what, types in EXPECTED:
        if not present.intersection(types):
            summary.notes.append('no %s in the bag (%s)' % (what, ' or '.join(types)))
    if any(t in present for t in MODEL_STATES_TYPES):
        if summary.robot_source != 'model states':
            summary.notes.append('the model states never name the robot %r' % robot_name)
        if not len(summary.ball):
            summary.notes.append('the model states never name the ball %r' % ball_name)
    if summary.undecodable > 1:
        summary.notes.append('%d messages in all could not be decoded and were skipped'
                             % summary.undecodable)
    if summary.camera_topic and summary.first_sight is None:
        summary.notes.append('no recorded camera frame shows a pure white pixel')


# -- the world, the outcome and the pictures ------------------------------------------------
@dataclass
class WorldMap:
    """The world as flatsim sees it: its scene, which primitives stay put, where balls start."""
    scene: Scene
    static: np.ndarray
    balls: Dict[str, tuple]                    # name -> (x, y, radius)
    path: str = ''


def load_world_map(path, notes, model_paths=None):
    """The WorldMap of an SDF world, or an empty one (with a note) if it cannot be read.
    model_paths: where its includes are looked up (by default Gazebo's model path now)."""
    if not path:
        notes.append('no world file given: the map shows the path only')
        return WorldMap(Scene([]), np.zeros(0, dtype=int), {})
    try:
        world = load_world(path, model_paths)
        sim = Simulation(world)
    except (FlatsimError, OSError) as err:
        notes.append('the world could not be read, so the map shows the path only: %s' % err)
        return WorldMap(Scene([]), np.zeros(0, dtype=int), {}, str(path))
    moving = moving_indices(sim)
    static = np.setdiff1d(sim.scene.select(visual=True), moving)
    balls = {model.name: (model.pose.x, model.pose.y,
                          max(g.size[0] for g in model.visuals + model.collisions))
             for model in white_balls(world)}
    return WorldMap(sim.scene, static, balls, str(path))


@dataclass
class Outcome:
    reached: bool
    time_to_reach: Optional[float]             # s of sim time from the start of the bag
    closest: Optional[float]                   # m, robot origin to ball centre
    start_time: float = 0.0


def ball_track(summary, world_map, ball_name):
    """The ball's track from the bag, else its place in the world file, else None."""
    if len(summary.ball):
        return summary.ball
    if ball_name in world_map.balls:
        x, y, _ = world_map.balls[ball_name]
        start = summary.robot.t[0] if len(summary.robot) else 0.0
        return Track.of([(start, x, y)])
    return None


def chase_outcome(summary, ball, reach):
    """Whether and when the robot came within reach of the ball, from the recorded poses."""
    start = summary.clock[0] if summary.clock else (summary.robot.t[0] if len(summary.robot) else 0.0)
    if not len(summary.robot) or ball is None:
        return Outcome(False, None, None, start)
    gaps = np.hypot(*(summary.robot.points() - ball.at(summary.robot.t)).T)
    within = np.flatnonzero(gaps <= reach)
    if within.size:
        return Outcome(True, float(summary.robot.t[within[0]] - start), float(gaps.min()), start)
    return Outcome(False, None, float(gaps.min()), start)


def trajectory_frame(summary, world_map, ball):
    """The MapFrame of trajectory.png: the world plus everything the bag saw."""
    extents = [summary.robot.points()]
    if ball is not None:
        extents.append(ball.points())
    return fit_frame(world_map.scene, [e for e in extents if e.size], MAP_RESOLUTION,
                     max_pixels=MAP_MAX_PIXELS)


def _cv(frame, points):
    return np.round((frame.to_pixel(points) - 0.5) * 16).astype(np.int32)


def _circle(image, frame, point, radius_px, color, thickness):
    centre = _cv(frame, point)
    cv2.circle(image, (int(centre[0]), int(centre[1])), int(radius_px * 16), color, thickness,
               cv2.LINE_AA, 4)


def render_trajectory(summary, world_map, ball, ball_radius=0.1):
    """(image, frame): the world from above with the robot's path and the ball's places."""
    frame = trajectory_frame(summary, world_map, ball)
    image = render_static(world_map.scene, frame, world_map.static)
    robot = summary.robot.points()
    if len(robot):
        cv2.polylines(image, [_cv(frame, robot)], False, PATH_COLOR, 3, cv2.LINE_AA, 4)
        _circle(image, frame, robot[0], MARK_RADIUS_PX + 2, START_COLOR, 3)
        _circle(image, frame, robot[-1], MARK_RADIUS_PX, END_COLOR, -1)
    if ball is not None:
        radius_px = max(MARK_RADIUS_PX, ball_radius / frame.resolution)
        if len(ball) > 1:
            cv2.polylines(image, [_cv(frame, ball.points())], False, BALL_MARK_COLOR, 1,
                          cv2.LINE_AA, 4)
        _circle(image, frame, ball.points()[0], radius_px + 4, BALL_MARK_COLOR, 2)
        _circle(image, frame, ball.points()[-1], radius_px, BALL_MARK_COLOR, -1)
    legend = [('path', PATH_COLOR), ('start', START_COLOR), ('end', END_COLOR),
              ('ball', BALL_MARK_COLOR)]
    for row, (label, color) in enumerate(legend):
        y = 18 + 18 * row
        cv2.rectangle(image, (8, y - 10), (20, y + 2), color, -1)
        cv2.putText(image, label, (26, y), cv2.FONT_HERSHEY_SIMPLEX, 0.45, TEXT_COLOR, 1,
                    cv2.LINE_AA)
    return image, frame


@dataclass
class RunFacts:
    """What the demo knows that a bag does not: wall time, and its own verdict."""
    wall_seconds: Optional[float] = None
    sim_seconds: Optional[float] = None         # sim time that passed in wall_seconds
    reached: Optional[bool] = None
    detail: str = ''


@dataclass
class Report:
    outcome: Outcome
    frame: object                              # overhead.MapFrame of trajectory.png
    ball: Optional[Track]
    notes: List[str]
    files: List[str]


def write_report(summary, out_dir, world_path=None, ball_name='white_ball', reach=REACH_M,
                 run=None):
    """Write trajectory.png, first_sight.png (if the ball was seen) and summary.md."""
    os.makedirs(out_dir, exist_ok=True)
    notes = list(summary.notes)
    world_map = load_world_map(world_path, notes)
    ball = ball_track(summary, world_map, ball_name)
    if not len(summary.ball) and ball is not None:
        notes.append('the ball is drawn where the world file puts it')
    outcome = chase_outcome(summary, ball, reach)
    files = []
    ball_radius = world_map.balls.get(ball_name, (0.0, 0.0, 0.1))[2]
    image, frame = render_trajectory(summary, world_map, ball, ball_radius)
    _write_png(os.path.join(out_dir, 'trajectory.png'), image, files)
    sight = os.path.join(out_dir, 'first_sight.png')
    if summary.first_sight is not None:
        _write_png(sight, summary.first_sight, files)
    elif os.path.exists(sight):
        os.remove(sight)
    text = summary_markdown(summary, world_map, outcome, reach, run or RunFacts(), notes)
    with open(os.path.join(out_dir, 'summary.md'), 'w') as stream:
        stream.write(text)
    files.append(os.path.join(out_dir, 'summary.md'))
    return Report(outcome, frame, ball, notes, files)


def _write_png(path, rgb, files):
    if not cv2.imwrite(path, cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR)):
        raise FlatsimError('could not write %s' % path)
    files.append(path)


def _seconds(value):
    return 'unknown' if value is None else '%.1f s' % value


def summary_markdown(summary, world_map, outcome, reach, run, notes):
    """The text of summary.md."""
    reached = outcome.reached if run.reached is None else run.reached
    sim_span = None
    if summary.clock:
        sim_span = summary.clock[1] - summary.clock[0]
    elif len(summary.robot):
        sim_span = float(summary.robot.t[-1] - summary.robot.t[0])
    lines = ['# Chase report', '',
             '- Bag: `%s`' % summary.path,
             '- World: `%s`' % (world_map.path or 'none'),
             '- Outcome: %s' % ('reached' if reached else 'not reached')
             + (' (%s)' % run.detail if run.detail else ''),
             '- Time to reach (robot origin within %.2f m of the ball centre): %s'
             % (reach, _seconds(outcome.time_to_reach) + ' of sim time'
                if outcome.time_to_reach is not None else 'never, in the recorded poses'),
             '- Closest approach: %s' % ('unknown' if outcome.closest is None
                                         else '%.2f m' % outcome.closest),
             '- Path length: %s' % ('%.2f m (from %s)' % (summary.robot.length(), summary.robot_source)
                                    if len(summary.robot) else 'unknown (%s)' % _NO_ROBOT),
             '- Sim time covered: %s' % _seconds(sim_span),
             '- Real-time factor: %s' % _real_time_factor(summary, sim_span, run),
             '- Camera frames: %s' % _frames_line(summary),
             '- First sight of the ball: %s' % first_sight_line(summary, outcome.start_time),
             '', '## Topics in the bag', '', '| topic | type | messages |', '|---|---|---|']
    for topic, (msgtype, count) in sorted(summary.topics.items()):
        lines.append('| `%s` | %s | %d |' % (topic, msgtype, count))
    if not summary.topics:
        lines.append('| (none) | | 0 |')
    lines += ['', '## Notes', '']
    lines += ['- %s' % note for note in notes] or ['- none: the bag holds every topic the report reads']
    return '\n'.join(lines) + '\n'


def _real_time_factor(summary, sim_span, run):
    sim_seconds = sim_span if run.sim_seconds is None else run.sim_seconds
    if run.wall_seconds and sim_seconds is not None:
        return '%.2f (%.1f s of sim time in %.1f s of wall time)' % (
            sim_seconds / run.wall_seconds, sim_seconds, run.wall_seconds)
    if sim_span is None:
        return 'unknown (no sim time in the bag)'
    if summary.bag_span and summary.clock:
        bag_seconds = summary.bag_span[1] - summary.bag_span[0]
        # rosbag stamps with sim time under use_sim_time; then the bag cannot tell wall time.
        if bag_seconds > 0 and abs(bag_seconds - sim_span) > 0.05 * bag_seconds:
            return '%.2f (%.1f s of sim time in %.1f s of wall time)' % (
                sim_span / bag_seconds, sim_span, bag_seconds)
    return 'unknown (the bag is stamped with sim time; the demo reports it)'


def first_sight_line(summary, start_time):
    """When the camera first saw the ball, as far as the recorded frames tell: the recorder
    may keep only some of the camera's frames (chase_demo thins them to --camera-rate)."""
    if summary.first_sight is None:
        return 'not in the recorded frames'
    seen = summary.first_sight_time - start_time
    if summary.before_sight_time is None:
        return ('by %.1f s of sim time: first_sight.png, the first recorded frame, already shows it'
                % seen)
    skipped = summary.first_sight_seq - summary.before_sight_seq - 1
    if skipped == 0:
        return 'at %.1f s of sim time (first_sight.png, the camera\'s first frame that shows it)' % seen
    between = ('between %.1f s and %.1f s of sim time; first_sight.png is the first recorded frame '
               'that shows it, at %.1f s' % (summary.before_sight_time - start_time, seen, seen))
    # Sequence numbers that do not count up say nothing of how many frames were left out.
    return between + (' (%d camera frames before it were not recorded)' % skipped if skipped > 0 else '')


def _frames_line(summary):
    if not summary.camera_topic:
        return 'none recorded'
    return ('%d published (sequence number of the last recorded frame), %d recorded on `%s`'
            % (summary.camera_last_seq, summary.camera_frames, summary.camera_topic))


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='report', description=__doc__.split('\n')[0])
    parser.add_argument('bag', help='ROS 1 bag recorded from flatsim')
    parser.add_argument('--world', default='', help='SDF world the bag was recorded in')
    parser.add_argument('--output', type=arguments.output_folder, default='out',
                        help='folder for the report (created if missing)')
    parser.add_argument('--robot', default=ROBOT_NAME, help='name of the robot model')
    parser.add_argument('--ball', default='white_ball', help='name of the ball model')
    parser.add_argument('--reach', type=arguments.positive, default=REACH_M,
                        help='distance from the robot base to the ball centre that counts as reached (m)')
    return parser.parse_args(argv)


def build(bag, out_dir, world=None, robot=ROBOT_NAME, ball='white_ball', reach=REACH_M, run=None):
    """Read the bag and write the report; notes go to stderr. Returns the Report."""
    summary = read_bag(bag, robot, ball)
    report = write_report(summary, out_dir, world, ball, reach, run)
    for note in report.notes:
        print('report: %s' % note, file=sys.stderr)
    return report, summary


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        report, summary = build(args.bag, args.output, args.world, args.robot, args.ball, args.reach)
    except FlatsimError as err:
        print('report: %s' % err, file=sys.stderr)
        return 1
    print('report: %s (%s)' % (', '.join(report.files),
                               'reached' if report.outcome.reached else 'not reached'))
    return 0 if summary.topics else 1
