"""What a ball chaser's process_image works with, for the studio's chase view (Window > Chase).

The course's rule: a pixel is the ball when its red, green and blue are all
exactly 255 (in a mono8 image, when it is 255), and the image is cut into
thirds by column: column c is in the left third when c < width / 3, in the
middle one when c < 2 * width / 3, else in the right one. This is the rule of
ball_chaser.detect.find_ball with its defaults and of
ball_chaser.control.CourseController; tests/test_studio_chase_rule.py checks
that both count alike. flatsim holds the rule itself because the project's
ball_chaser is not there in student mode, where a student's own package has
its name.

CommandLog keeps the drive commands (/cmd_vel) a robot received over the last
COMMAND_WINDOW seconds of sim time, only while a chase view is open.

A call to /ball_chaser/command_robot cannot be seen on the wire: a ROS 1
service call is a direct connection from the caller to the server, which the
master never sees, and there is no `rosservice echo`. It is seen through what
the serving node logs: while a view is open, the simulator asks the master
which node serves the service and keeps that node's lines on /rosout in a
LineLog (course drive_bots log each request and its feedback; the project's
logs each call at DEBUG, and the simulator raises the node's loggers to DEBUG
through its standard set_logger_level service while the view is open, then
puts them back). flatsim.studio.service_watch holds that watch;
loggers_to_raise and line_time are its rules.

No ROS here.
"""
import collections
import json
import math
import struct
import threading
from dataclasses import dataclass

import numpy as np

# Seconds of sim time that the chase view's strip shows.
COMMAND_WINDOW = 10.0
# The most commands kept (a node publishing /cmd_vel at 100 Hz fills 10 s with 1000).
MAX_COMMANDS = 2000
# The most logged lines kept (a drive_bot logging every call of a 30 Hz camera fills 10 s with 300).
MAX_LINES = 1000
# The page lists the newest of them, with at most this many characters of each.
LINES_LISTED = 10
MAX_LINE_TEXT = 400
# The chase image goes to the page at most this wide, as the camera panel's.
CHASE_MAX_WIDTH = 480
JPEG_QUALITY = 80
# Ball pixels are painted in this colour (RGB) over the dimmed image.
HIGHLIGHT = (255, 0, 255)
DIM = 0.45


def ball_pixels(pixels):
    """uint8 mask, 255 where a pixel is exactly white: (h, w, 3) rgb8 or (h, w) mono8."""
    import cv2  # only a page with the chase view open pays for it
    if pixels.ndim == 2:
        return cv2.inRange(pixels, 255, 255)
    return cv2.inRange(pixels, (255, 255, 255), (255, 255, 255))


def third_starts(width):
    """(first column of the middle third, first column of the right third) for an image
    width columns wide: the integer c with c < width / 3 are the left third."""
    return -(-width // 3), -(-2 * width // 3)


def counts_by_third(mask):
    """(left, middle, right): how many non-zero pixels of mask lie in each third of its columns."""
    middle, right = third_starts(mask.shape[1])
    per_column = np.count_nonzero(mask, axis=0)
    return (int(per_column[:middle].sum()), int(per_column[middle:right].sum()),
            int(per_column[right:].sum()))


def highlighted(pixels, mask, max_width=CHASE_MAX_WIDTH):
    """The rgb8 picture the view shows: the image dimmed, the ball pixels in HIGHLIGHT, at most
    max_width wide. A ball pixel stays visible however small the picture gets."""
    import cv2
    rgb = cv2.cvtColor(pixels, cv2.COLOR_GRAY2RGB) if pixels.ndim == 2 else pixels
    height, width = mask.shape
    if width > max_width:
        size = (max_width, max(1, round(height * max_width / width)))
        rgb = cv2.resize(rgb, size, interpolation=cv2.INTER_AREA)
        # INTER_NEAREST takes image pixel floor(i * scale) for picture pixel i: each ball pixel
        # is spread up and left over a square one scale wide, so that some sample falls on it
        # and none is lost by shrinking.
        reach = math.ceil(max(width / size[0], height / size[1]))
        spread = cv2.dilate(mask, np.ones((reach, reach), np.uint8), anchor=(0, 0))
        mask = cv2.resize(spread, size, interpolation=cv2.INTER_NEAREST)
    picture = cv2.convertScaleAbs(rgb, alpha=DIM)
    picture[mask > 0] = HIGHLIGHT
    return picture


@dataclass(frozen=True)
class DriveCommand:
    """One command a robot's drive received: sim time (s), linear.x (m/s), angular.z (rad/s),
    the node that published it, and why it was refused (empty if applied)."""
    sim_time: float
    model: str
    linear_x: float
    angular_z: float
    sender: str
    refused: str = ''

    def as_json(self):
        return {'t': round(self.sim_time, 4), 'linear_x': _number(self.linear_x),
                'angular_z': _number(self.angular_z), 'sender': self.sender,
                'refused': self.refused}


def _number(value):
    """A finite value rounded for the page; NaN and infinities as their names (JSON has none)."""
    value = float(value)
    return round(value, 4) if math.isfinite(value) else str(value)


class SimTimeLog:
    """Entries (each with a sim_time) of the last `window` seconds of sim time, at most limit of
    them; safe across threads (a ROS callback adds, the studio reads)."""

    def __init__(self, window=COMMAND_WINDOW, limit=MAX_COMMANDS):
        self.window = window
        self.entries = collections.deque(maxlen=limit)
        self.lock = threading.Lock()

    def add(self, entry):
        with self.lock:
            if self.entries and entry.sim_time < self.entries[-1].sim_time:
                # Time went back (Reset World): what came before belongs to another run.
                self.entries.clear()
            self.entries.append(entry)

    def clear(self):
        with self.lock:
            self.entries.clear()

    def _recent(self, keep, now):
        """The entries since now - window for which keep(entry), oldest first. Those a little
        after now are kept: one may come in between the camera frame at now and this call."""
        with self.lock:
            if self.entries and self.entries[-1].sim_time > now + self.window:
                # Far ahead of now: time went back, and nothing came since.
                self.entries.clear()
            while self.entries and self.entries[0].sim_time < now - self.window:
                self.entries.popleft()
            return [entry for entry in self.entries if keep(entry)]


class CommandLog(SimTimeLog):
    """The drive commands of the last `window` seconds of sim time (the simulator's /cmd_vel
    subscribers add, the studio reads)."""

    def recent(self, model, now):
        """The commands model received since now - window, oldest first."""
        return self._recent(lambda command: command.model == model, now)


@dataclass(frozen=True)
class LoggedLine:
    """One line a node logged (rosgraph_msgs/Log): sim time (s), the node, its level's name
    (DEBUG, INFO, WARN, ERROR, FATAL) and its text."""
    sim_time: float
    node: str
    level: str
    text: str

    def as_json(self):
        return {'t': round(self.sim_time, 4), 'node': self.node, 'level': self.level,
                'text': self.text}


class LineLog(SimTimeLog):
    """The lines nodes logged over the last `window` seconds of sim time (the simulator's
    /rosout subscriber adds, the studio reads)."""

    def __init__(self, window=COMMAND_WINDOW, limit=MAX_LINES):
        super().__init__(window, limit)

    def recent(self, node, now):
        """The lines node logged since now - window, oldest first."""
        return self._recent(lambda line: line.node == node, now)


# rosgraph_msgs/Log's level constants, by name.
LOG_LEVELS = {1: 'DEBUG', 2: 'INFO', 4: 'WARN', 8: 'ERROR', 16: 'FATAL'}


def line_time(stamp, received_at, window=COMMAND_WINDOW):
    """The sim time to show a logged line at: its stamp (the node's own time, sim time under
    /use_sim_time), or received_at (the simulator's sim time when it came) for a node whose
    stamps are far ahead of sim time (one on wall time); None for a line stamped more than
    window before it came, which /rosout's latched last message of each node is on subscribing."""
    if stamp < received_at - window:
        return None
    if stamp > received_at + window:
        return received_at
    return stamp


def loggers_to_raise(loggers):
    """[(name, level)] of a node's loggers (roscpp/GetLoggers: name, level), those to raise to
    DEBUG for its log lines to reach /rosout, with their level now: rospy's `rosout` (the
    logger of rospy.loginfo and the rest) and roscpp's `ros.<package>...` (ROS_INFO's), not
    roscpp's own `ros.roscpp...`, and only those not at DEBUG already."""
    return [(name, level) for name, level in loggers
            if (name == 'rosout' or name.startswith('ros.')) and not name.startswith('ros.roscpp')
            and level.upper() != 'DEBUG']


@dataclass(frozen=True)
class ServiceCalls:
    """What the chase view shows of a service's calls: the service, the node that serves it
    (None: no node does, or not looked up yet), whether it was looked up, and the lines that
    node logged over the window, oldest first."""
    service: str
    server: object = None
    looked_up: bool = False
    lines: tuple = ()

    def as_json(self):
        """Every line as a mark ([t, level]) for the strip, and the text of the newest
        LINES_LISTED, each cut to MAX_LINE_TEXT characters, for the list under it."""
        return {'service': self.service, 'server': self.server, 'looked_up': self.looked_up,
                'marks': [[round(line.sim_time, 4), line.level] for line in self.lines],
                'lines': [dict(line.as_json(), text=_shortened(line.text))
                          for line in self.lines[-LINES_LISTED:]]}


def _shortened(text):
    return text if len(text) <= MAX_LINE_TEXT else text[:MAX_LINE_TEXT - 1] + '…'


def chase_frame(sensor, sim_time, pixels, commands, calls=None, max_width=CHASE_MAX_WIDTH):
    """The binary frame for the chase view: header length, JSON header, JPEG.

    The header: {type: "chase_image", sensor, sim_time, width, height (the JPEG's),
    image_width, image_height (the camera's), thirds: [first middle column, first right
    column], counts: [left, middle, right] ball pixels, window (s), commands: [...],
    calls: ServiceCalls.as_json() or null (nothing watches service calls)}.
    """
    import cv2
    pixels = np.ascontiguousarray(pixels)    # a bgr8 camera's pixels come as a reversed view
    mask = ball_pixels(pixels)
    counts = counts_by_third(mask)
    picture = highlighted(pixels, mask, max_width)
    ok, jpeg = cv2.imencode('.jpg', cv2.cvtColor(picture, cv2.COLOR_RGB2BGR),
                            [cv2.IMWRITE_JPEG_QUALITY, JPEG_QUALITY])
    if not ok:
        raise ValueError('the chase image could not be encoded')
    height, width = mask.shape
    header = json.dumps({
        'type': 'chase_image', 'sensor': sensor, 'sim_time': round(sim_time, 4),
        'width': picture.shape[1], 'height': picture.shape[0],
        'image_width': width, 'image_height': height, 'thirds': list(third_starts(width)),
        'counts': list(counts), 'window': COMMAND_WINDOW,
        'commands': [command.as_json() for command in commands],
        'calls': None if calls is None else calls.as_json()},
        separators=(',', ':'), allow_nan=False).encode()
    return struct.pack('>I', len(header)) + header + jpeg.tobytes()
