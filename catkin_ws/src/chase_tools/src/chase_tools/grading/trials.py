"""A chase trial's verdict, and why it failed, from what the grader saw. Pure: no ROS.

The grader records, for each trial, the robot's and the ball's poses from the
simulator's model states, every command on /cmd_vel, process_image's calls to
the service, and whether the camera's first frames showed the ball (a
pure-white pixel). judge() turns that record into the verdict:

  reached   the robot's outline came within the reach of the ball's surface, or
            the ball was pushed (reach.surface_reached_how);
  otherwise the first of these that holds says why:
    the ball never showed in the camera's image;
    seen, but no command (no call, nothing on /cmd_vel, or only zero commands);
    commands, but no motion;
    turned away (the ball left the camera's view and did not come back);
    timed out while moving;
    stopped short at X cm of the ball's surface.
"""
import collections
import itertools
import math
import threading
from dataclasses import dataclass, field
from typing import List, Optional

import numpy as np

from chase_tools.placement import robot_view
from chase_tools.reach import BALL_PUSHED_M, surface_gaps, surface_reached_how

# A command this small (m/s, rad/s) counts as "stop".
STILL_COMMAND = 0.01
# Less than this over the whole trial is no motion.
NO_MOTION_M = 0.05
NO_MOTION_RAD = 0.1
# Over the last MOVING_WINDOW_S of the trial, more than this is still moving.
MOVING_WINDOW_S = 1.0
MOVING_M = 0.02
MOVING_RAD = 0.05
# m and rad: a model state this close to the placement shows the robot and ball as placed.
PLACED_TOLERANCE = 1e-3


class RollingLog:
    """The last `keep` of what came, and how many came in all, so that a submission that floods a
    topic or a service costs the grader bounded memory. A mark (count at some moment) gives what
    came since, as far as it is still kept."""

    def __init__(self, keep):
        self.keep = keep
        self.items = collections.deque(maxlen=keep)
        self.count = 0
        self.lock = threading.Lock()

    def append(self, item):
        with self.lock:
            self.items.append(item)
            self.count += 1

    def since(self, mark):
        """What came from mark (an earlier count) on, oldest first; the part of it no longer kept
        is left out (dropped_since says how much)."""
        return self.read(mark)[0]

    def read(self, mark):
        """(what came from mark on, still kept; the count now, the mark to read from next).
        Only the new part is copied: the grader polls this while a trial runs."""
        with self.lock:
            new = min(len(self.items), max(0, self.count - mark))
            return list(itertools.islice(reversed(self.items), new))[::-1], self.count

    def dropped_since(self, mark):
        with self.lock:
            return max(0, (self.count - mark) - len(self.items))

    def __len__(self):
        return self.count

    def __bool__(self):
        return self.count > 0


@dataclass
class TrialRecord:
    """What the grader saw during one trial; times in sim seconds from its start."""
    poses: np.ndarray                   # (N, 6): t, robot x, y, yaw, ball x, y
    commands: List[tuple]               # (t, linear, angular) seen on /cmd_vel
    calls: Optional[List[tuple]]        # (t, linear, angular) of process_image's calls; None: not counted
    frames: int = 0                     # camera frames looked at, early in the trial
    white_frames: int = 0               # of them, frames with a pure-white pixel
    ball_start: tuple = (0.0, 0.0)      # where the ball was placed


@dataclass
class Verdict:
    reached: bool
    time_to_ball: Optional[float]       # s of sim time, when reached
    closest: Optional[float]            # m, the smallest gap from the robot's outline to the ball's surface
    reason: str                         # for the report: how it reached the ball, or why it did not
    facts: dict = field(default_factory=dict)   # the figures behind the reason, for grade.json


def state_times(count, step, period):
    """Sim times of the first count model states after a reset: the simulator publishes them
    at its first step (t = step), then at the first step at least period after the last one.
    Counted this way, a state's time does not depend on when the grader received it."""
    times, steps = [], 1
    per_period = period / step
    for _ in range(count):
        times.append(round(steps * step, 9))
        steps = math.ceil(steps + per_period - 1e-6)
    return times


def placed_row(rows, robot_pose, ball_xy, tolerance=PLACED_TOLERANCE):
    """Index of the first row (t, robot x, y, yaw, ball x, y) with the robot and the ball where
    they were placed: the first state of the trial. Rows before it were on their way from
    before the reset. None if no row shows the placement."""
    for index, (_t, x, y, yaw, ball_x, ball_y) in enumerate(rows):
        if (abs(x - robot_pose[0]) <= tolerance and abs(y - robot_pose[1]) <= tolerance
                and abs(math.remainder(yaw - robot_pose[2], 2 * math.pi)) <= tolerance
                and abs(ball_x - ball_xy[0]) <= tolerance and abs(ball_y - ball_xy[1]) <= tolerance):
            return index
    return None


# Commands this close in sim time are one frame's answer (flatsim publishes /clock every 0.01 s
# of sim time, and under lockstep a frame's answers all come while time is held): only the
# last of them was ever in effect.
SAME_FRAME_S = 0.01


def in_effect(commands, same_frame=SAME_FRAME_S):
    """The (t, linear, angular) commands that were in effect: each one not overridden by the
    next within same_frame seconds of sim time (a node that sends "move" then "stop" from one
    callback commanded a stop). Within means however the stamps' float sums round: two
    /clock ticks 0.01 s apart differ by a hair more than 0.01."""
    return [command for command, following in zip(commands, list(commands[1:]) + [None])
            if following is None or (following[0] - command[0] > same_frame
                                     and not math.isclose(following[0] - command[0], same_frame))]


def path_and_turn(poses):
    """(metres travelled along the path, radians turned) over poses (t, x, y, yaw, ...),
    oldest first: a robot that drives off and comes back has moved."""
    rows = np.array([pose[:4] for pose in poses], dtype=float).reshape(-1, 4)
    path = float(np.sum(np.hypot(np.diff(rows[:, 1]), np.diff(rows[:, 2]))))
    turned = float(np.sum(np.abs(np.remainder(np.diff(rows[:, 3]) + math.pi, 2 * math.pi) - math.pi)))
    return path, turned


def set_off(poses):
    """Has the robot moved, over poses (t, x, y, yaw, ...): past NO_MOTION_M along its path or
    NO_MOTION_RAD turned, what a whole trial needs to count as motion."""
    path, turned = path_and_turn(poses)
    return path >= NO_MOTION_M or turned >= NO_MOTION_RAD


def moving(values, threshold=STILL_COMMAND):
    return [row for row in values if abs(row[1]) > threshold or abs(row[2]) > threshold]


def has_white_pixel(data, width, height, step, encoding):
    """True when an image has a pixel whose every channel is 255; None for encodings it cannot read."""
    channels = {'rgb8': 3, 'bgr8': 3, 'rgba8': 4, 'bgra8': 4, 'mono8': 1}.get(encoding)
    if channels is None or height * step > len(data) or width * channels > step:
        return None
    pixels = np.frombuffer(data, dtype=np.uint8, count=height * step).reshape(height, step)
    pixels = pixels[:, :width * channels].reshape(height, width, channels)[:, :, :min(channels, 3)]
    return bool(np.any(np.all(pixels == 255, axis=2)))


def first_reached(robot, record, ball_radius, reach):
    """(index of the first pose row that reaches the ball, how) or (None, '')."""
    poses = record.poses
    if not len(poses):
        return None, ''
    gaps = surface_gaps(robot, poses[:, 1:4], poses[:, 4:6], ball_radius)
    pushed = np.hypot(poses[:, 4] - record.ball_start[0], poses[:, 5] - record.ball_start[1])
    hits = np.flatnonzero((gaps <= reach) | (pushed >= BALL_PUSHED_M))
    if not hits.size:
        return None, ''
    row = int(hits[0])
    return row, surface_reached_how(gaps[row], pushed[row], reach)


def judge(robot, space, record, ball_radius, reach, timeout):
    """The Verdict of one trial: robot is a placement.RobotGeometry, space its FreeSpace."""
    poses = record.poses
    facts = {'frames': record.frames, 'white_frames': record.white_frames,
             'commands': len(record.commands), 'moving_commands': len(moving(record.commands)),
             'calls': None if record.calls is None else len(record.calls),
             'moving_calls': None if record.calls is None else len(moving(record.calls))}
    if not len(poses):
        return Verdict(False, None, None, 'the simulator reported no pose during the trial', facts)
    gaps = surface_gaps(robot, poses[:, 1:4], poses[:, 4:6], ball_radius)
    closest = round(float(np.min(gaps)), 3)
    facts['gap_at_end'] = round(float(gaps[-1]), 3)
    row, how = first_reached(robot, record, ball_radius, reach)
    if row is not None:
        return Verdict(True, round(float(poses[row, 0]), 3), closest, how, facts)
    seen = robot_view(robot, space, poses[:, 1:4], poses[:, 4:6], ball_radius)
    facts['ball_in_view_at_start'] = bool(seen[0])
    facts['ball_in_view_at_end'] = bool(seen[-1])
    travelled = np.hypot(np.diff(poses[:, 1]), np.diff(poses[:, 2]))
    turned = np.abs(np.remainder(np.diff(poses[:, 3]) + math.pi, 2 * math.pi) - math.pi)
    facts['moved_m'] = round(float(np.sum(travelled)), 3)
    facts['turned_rad'] = round(float(np.sum(turned)), 3)
    recent = poses[1:, 0] >= poses[-1, 0] - MOVING_WINDOW_S
    still_moving = (float(np.sum(travelled[recent])) > MOVING_M or float(np.sum(turned[recent])) > MOVING_RAD)
    facts['moving_at_end'] = still_moving
    reason = _why_not(record, facts, poses, seen, gaps, closest, still_moving, timeout)
    return Verdict(False, None, closest, reason, facts)


def cut_at_end(robot, record, ball_radius, reach):
    """The record as far as the trial went: to where the robot reached the ball, else to its
    last pose (the time limit), with the commands and calls that came by then. What came after,
    until the grader paused the world, depends on how soon it looked."""
    row, _how = first_reached(robot, record, ball_radius, reach)
    poses = record.poses if row is None else record.poses[:row + 1]
    if not len(poses):
        return record
    end = poses[-1, 0]
    return TrialRecord(poses, [c for c in record.commands if c[0] <= end],
                       None if record.calls is None else [c for c in record.calls if c[0] <= end],
                       record.frames, record.white_frames, record.ball_start)


def _cm(metres):
    return '%.0f cm' % (100 * metres)


def _why_not(record, facts, poses, seen, gaps, closest, still_moving, timeout):
    if record.frames > 0 and record.white_frames == 0:
        return ('the ball never showed in the camera image: no pure-white pixel in the first %d '
                'frames, though the whole ball stood in the camera\'s field of view' % record.frames)
    commands, calls = moving(record.commands), moving(record.calls or [])
    if not commands and not calls:
        if record.calls:
            return ('saw the ball but sent no command: process_image called %d times, always '
                    'with (0, 0)' % len(record.calls))
        if record.calls is not None:
            return ('saw the ball but sent no command: no call to /ball_chaser/command_robot and '
                    'no motion command on /cmd_vel')
        return 'saw the ball but sent no command: no motion command on /cmd_vel'
    if facts['moved_m'] < NO_MOTION_M and facts['turned_rad'] < NO_MOTION_RAD:
        if commands:
            _t, linear, angular = commands[-1]
            return ('commands but no motion: %d motion commands on /cmd_vel (the last %.2f m/s, '
                    '%.2f rad/s), yet the robot moved %s' % (len(commands), linear, angular,
                                                            _cm(facts['moved_m'])))
        _t, linear, angular = calls[-1]
        return ('commands but no motion: process_image asked for motion %d times (the last %.2f m/s, '
                '%.2f rad/s), but nothing of it came on /cmd_vel and the robot moved %s'
                % (len(calls), linear, angular, _cm(facts['moved_m'])))
    if not seen[-1] and np.any(seen):
        left = int(np.flatnonzero(seen)[-1]) + 1
        facts['left_view_at'] = round(float(poses[left, 0]), 3)
        return ('turned away: the ball left the camera\'s view at %.1f s and did not come back '
                '(closest %s of the ball\'s surface)' % (poses[left, 0], _cm(closest)))
    if still_moving:
        return ('timed out while moving: still moving at the %g s limit, %s from the ball\'s surface '
                '(closest %s)' % (timeout, _cm(gaps[-1]), _cm(closest)))
    stopped = _stopped_since(poses)
    facts['stopped_at'] = round(stopped, 3)
    return ('stopped short at %s of the ball\'s surface (from %.1f s on), with the ball in view'
            % (_cm(gaps[-1]), stopped))


def _stopped_since(poses):
    """Sim time since which the robot has stayed within MOVING_M and MOVING_RAD of its last pose."""
    end = poses[-1]
    away = (np.hypot(poses[:, 1] - end[1], poses[:, 2] - end[2]) > MOVING_M) | \
        (np.abs(np.remainder(poses[:, 3] - end[3] + math.pi, 2 * math.pi) - math.pi) > MOVING_RAD)
    moved = np.flatnonzero(away)
    return float(poses[moved[-1] + 1, 0]) if moved.size else float(poses[0, 0])


@dataclass
class StopVerdict:
    still: bool
    moving_commands: int        # motion commands in effect during the window
    first_moving: Optional[tuple]   # (t, linear, angular): the first of them
    last_command: Optional[tuple]
    path_m: float               # distance the base travelled over the window, along its path
    turned_rad: float           # the sum of its turns over the window
    poses: int                  # states the window held


def judge_stop(commands, poses, window_start, still_speed, still_distance, still_turn):
    """Did the robot stay still from window_start on? commands: (t, linear, angular) on /cmd_vel
    since before the ball went, oldest first; poses: (t, x, y, yaw) of the robot over the same
    time. The command in effect when the window opens counts (the last command persists, as
    with Gazebo's diff drive), and so does every command in the window, not only the last: a
    robot that rocks and ends on a zero command did not stop. A command overridden within the
    same frame (in_effect) was never in effect and does not count. Motion is measured along the
    path, so a robot that drives off and comes back is seen moving."""
    commands = in_effect(commands)
    before = [c for c in commands if c[0] < window_start]
    during = [c for c in commands if c[0] >= window_start]
    effective = before[-1:] + during
    moving_commands = moving(effective, still_speed)
    rows = [p for p in poses if p[0] >= window_start]
    path, turned = path_and_turn(rows)
    still = not moving_commands and path <= still_distance and turned <= still_turn and len(rows) > 1
    return StopVerdict(still, len(moving_commands), moving_commands[0] if moving_commands else None,
                       effective[-1] if effective else None, round(path, 3), round(turned, 3), len(rows))


def matching_command(commands, request, tolerance):
    """The first (t, linear, angular) whose linear and angular are the request's, or None."""
    for command in commands:
        if abs(command[1] - request[0]) <= tolerance and abs(command[2] - request[1]) <= tolerance:
            return command
    return None


# -- what no chase can do ---------------------------------------------------------------
# A teleport: between two model states the robot's origin moved farther than TELEPORT_SLACK_M
# plus what it covers at TELEPORT_MIN_SPEED plus the fastest command of the trial (its
# linear speed, and its turn rate times TELEPORT_ARM_M, the farthest a course robot's
# origin sits from the point it turns about). A robot that drives does not jump: its
# wheels' torque limit caps its acceleration, and flatsim's solver moves it by millimetres
# when it meets a wall.
TELEPORT_SLACK_M = 0.05
TELEPORT_MIN_SPEED = 1.0       # m/s: beyond any course robot's top speed
TELEPORT_ARM_M = 0.5


@dataclass
class Jump:
    """A pose change faster than the robot could drive."""
    time: float                         # sim time of the state after the jump
    distance: float                     # m its origin moved
    interval: float                     # sim seconds between the two states
    bound: float                        # m/s: the fastest it could have driven

    def describe(self, robot):
        return ('%s moved %.2f m in %.3f s of sim time at %.2f s (%.0f m/s), faster than it '
                'could drive (at most %.1f m/s)' % (robot, self.distance, self.interval, self.time,
                                                    self.distance / self.interval, self.bound))


def first_jump(poses, commands, min_interval):
    """The first Jump of the robot among poses [(t, x, y, ...)], in order, given the trial's
    commands [(t, linear, angular)]; None if it never moved faster than it could drive.
    min_interval (sim seconds, the states' period) stands in for a smaller or no interval
    between two states, whose times may come from a clock that lags."""
    fastest = max((abs(linear) + abs(angular) * TELEPORT_ARM_M for _t, linear, angular in commands),
                  default=0.0)
    bound = TELEPORT_MIN_SPEED + fastest
    for before, after in zip(poses, poses[1:]):
        interval = max(after[0] - before[0], min_interval)
        distance = math.hypot(after[1] - before[1], after[2] - before[2])
        if math.isfinite(distance) and distance > TELEPORT_SLACK_M + bound * interval:
            return Jump(after[0], distance, interval, bound)
    return None


@dataclass
class Move:
    """A model moved through the simulator's API (flatsim's ~model_moves)."""
    time: float
    by: str
    through: str
    target: str

    def describe(self):
        return '%s moved %s through %s at %.2f s' % (self.by or 'a node that gave no name',
                                                     self.target, self.through, self.time)


def moves_not_made_by(moves, grader, own_moves):
    """Of the moves seen during a trial, those the grader did not make: every move by another
    caller, and beyond the grader's own own_moves, those that gave the grader's name (a caller
    names itself)."""
    foreign = [move for move in moves if move.by != grader]
    claimed = [move for move in moves if move.by == grader]
    return foreign + claimed[own_moves:]
