"""What a chase bag says: the robot's and the ball's tracks, the sim clock, the camera's frames
and its first sight of the ball, with notes of what the bag lacks. Topics are found by message
type, so that remapped names work.

No ROS here: the bag is read with rosbags (bag_scan).
"""
import os
import struct
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.msg import get_types_from_msg

from chase_tools.bag_scan import bag_messages
from flatsim.errors import FlatsimError

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
        except Exception as err:  # noqa: BLE001 - damaged bytes fail in many ways inside a deserialiser
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
