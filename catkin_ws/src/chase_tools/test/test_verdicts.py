"""Each trial's verdict and why it failed, from a record of what the grader saw, and the log
lines that decide a failed item. Pure: no master."""
import math

import numpy as np
import pytest

from chase_tools.grading import trials
from chase_tools.grading.evidence import decisive_lines
from chase_tools.placement import CameraView, FreeSpace, RobotGeometry
from chase_tools.reach import SURFACE_REACH_M
from flatsim.loading.sdf_world import parse_world

# A 0.4 x 0.4 m robot with its camera at its front, in a 10 x 10 m room.
ROBOT = RobotGeometry(((0.2, -0.2), (0.2, 0.2), (-0.2, 0.2), (-0.2, -0.2)),
                      CameraView(0.2, 0.0, 0.1, 0.0, 0.0, 1.4, 1.1))
ROOM = """<?xml version="1.0"?>
<sdf version="1.6"><world name="room"><model name="walls"><static>1</static><link name="l">
  <collision name="n"><pose>0 5.1 0.5 0 0 0</pose><geometry><box><size>10.4 0.2 1</size></box></geometry></collision>
  <collision name="s"><pose>0 -5.1 0.5 0 0 0</pose><geometry><box><size>10.4 0.2 1</size></box></geometry></collision>
  <collision name="e"><pose>5.1 0 0.5 0 0 0</pose><geometry><box><size>0.2 10.4 1</size></box></geometry></collision>
  <collision name="w"><pose>-5.1 0 0.5 0 0 0</pose><geometry><box><size>0.2 10.4 1</size></box></geometry></collision>
</link></model></world></sdf>
"""
BALL = (3.0, 0.0)
TIMEOUT = 30.0


@pytest.fixture(scope='module')
def space():
    return FreeSpace(parse_world(ROOM))


def record(path, commands=(), calls=(), frames=10, white_frames=10, ball_path=None):
    """A trial record: path gives the robot's (x, y, yaw) at each tenth of a second."""
    times = np.arange(len(path)) * 0.1
    balls = np.asarray(ball_path if ball_path is not None else [BALL] * len(path), dtype=float)
    poses = np.column_stack([times, np.asarray(path, dtype=float), balls])
    return trials.TrialRecord(poses, list(commands), None if calls is None else list(calls), frames,
                              white_frames, BALL)


def judge(space, rec):
    return trials.judge(ROBOT, space, rec, 0.1, SURFACE_REACH_M, TIMEOUT)


def drive(start_x, end_x, steps, stay=0):
    return [(x, 0.0, 0.0) for x in np.linspace(start_x, end_x, steps)] + [(end_x, 0.0, 0.0)] * stay


GO = [(0.5, 0.4, 0.0)]


def test_a_robot_whose_outline_comes_within_15_cm_of_the_balls_surface_reached_it(space):
    # The surface gap is 3.0 - x - 0.2 - 0.1; it falls to 0.15 at x = 2.55.
    verdict = judge(space, record(drive(0.0, 2.6, 27), commands=GO, calls=GO))
    assert verdict.reached
    assert verdict.time_to_ball == pytest.approx(2.6)
    assert verdict.reason == 'came within 15 cm of the ball\'s surface'


def test_a_ball_that_moved_was_pushed(space):
    path = drive(0.0, 1.0, 11)
    ball_path = [BALL] * 10 + [(3.2, 0.0)]
    verdict = judge(space, record(path, commands=GO, calls=GO, ball_path=ball_path))
    assert verdict.reached and verdict.reason == 'pushed the ball'


def test_a_camera_that_never_showed_the_ball_says_so(space):
    verdict = judge(space, record(drive(0.0, 0.0, 50), frames=12, white_frames=0))
    assert not verdict.reached
    assert verdict.reason.startswith('the ball never showed in the camera image: no pure-white pixel '
                                     'in the first 12 frames')


def test_seen_but_no_command(space):
    verdict = judge(space, record(drive(0.0, 0.0, 50), calls=[]))
    assert verdict.reason == ('saw the ball but sent no command: no call to '
                              '/ball_chaser/command_robot and no motion command on /cmd_vel')
    assert verdict.closest == pytest.approx(2.7)
    zero = judge(space, record(drive(0.0, 0.0, 50), calls=[(0.1, 0.0, 0.0)] * 4))
    assert zero.reason == 'saw the ball but sent no command: process_image called 4 times, always with (0, 0)'
    uncounted = judge(space, record(drive(0.0, 0.0, 50), calls=None))
    assert uncounted.reason == 'saw the ball but sent no command: no motion command on /cmd_vel'


def test_commands_but_no_motion(space):
    verdict = judge(space, record(drive(0.0, 0.01, 50), commands=[(0.2, 0.3, 0.1)] * 3, calls=[]))
    assert verdict.reason == ('commands but no motion: 3 motion commands on /cmd_vel (the last 0.30 m/s, '
                              '0.10 rad/s), yet the robot moved 1 cm')


def test_a_robot_that_turned_away_from_the_ball(space):
    # It turns left on the spot, a tenth of a radian per step: at 0.7 rad the ball's edge has
    # left the 1.4 rad view. Its corner swings 8 cm closer to the ball on the way.
    path = [(0.0, 0.0, 0.1 * step) for step in range(40)] + [(0.0, 0.0, 3.9)] * 20
    verdict = judge(space, record(path, commands=[(0.1, 0.0, 1.0)], calls=[]))
    assert verdict.reason == ('turned away: the ball left the camera\'s view at 0.7 s and did not come back '
                              '(closest 262 cm of the ball\'s surface)')
    assert verdict.facts['left_view_at'] == pytest.approx(0.7)


def test_a_robot_still_moving_at_the_time_limit(space):
    verdict = judge(space, record(drive(0.0, 1.0, 300), commands=GO, calls=GO))
    assert verdict.reason == ('timed out while moving: still moving at the 30 s limit, 170 cm from the '
                              'ball\'s surface (closest 170 cm)')


def test_a_robot_that_stopped_short_says_where(space):
    # Stops with its outline 40 cm from the ball's surface (x = 2.3).
    verdict = judge(space, record(drive(0.0, 2.3, 30, stay=40), commands=GO, calls=GO))
    assert verdict.reason == ('stopped short at 40 cm of the ball\'s surface (from 2.9 s on), with the '
                              'ball in view')
    assert verdict.closest == pytest.approx(0.4)
    assert verdict.facts['moving_at_end'] is False and verdict.facts['ball_in_view_at_end'] is True


def test_a_white_pixel_is_one_whose_every_channel_is_255():
    image = np.full((4, 5, 3), 200, dtype=np.uint8)
    assert trials.has_white_pixel(image.tobytes(), 5, 4, 15, 'rgb8') is False
    image[2, 3] = (255, 255, 254)
    assert trials.has_white_pixel(image.tobytes(), 5, 4, 15, 'rgb8') is False
    image[1, 4] = 255
    assert trials.has_white_pixel(image.tobytes(), 5, 4, 15, 'bgr8') is True
    # Rows padded to 16 bytes: the padding does not count.
    padded = np.full((4, 16), 255, dtype=np.uint8)
    padded[:, :15] = 0
    assert trials.has_white_pixel(padded.tobytes(), 5, 4, 16, 'rgb8') is False
    assert trials.has_white_pixel(b'', 5, 4, 15, '32FC1') is None


# -- the log lines behind a failed item ---------------------------------------------------

WORLD_LOG = """\
started roslaunch server http://localhost:40000/
process[flatsim-1]: started with pid [10]
process[urdf_spawner-2]: started with pid [11]
[urdf_spawner-2] process has died [pid 11, exit code 1, cmd spawn_model -urdf].
[ WARN] [1.0]: a warning that says little
[ERROR] [1700000000.1]: Spawn service failed. Exiting.
Traceback (most recent call last):
  File "/ws/src/my_robot/scripts/helper.py", line 3, in <module>
    raise_if_error(open('/tmp/x', 'w'))
OSError: [Errno 30] Read-only file system: '/tmp/x'
[drive_bot-3] process has died [pid 12, exit code 1]
[ WARN] [2.0]: Shutdown request received. Reason given for shutdown: [[/drive_bot] Reason: new node registered with same name]
REQUIRED process [rviz-4] has died!
"""


def test_the_decisive_lines_come_first_with_where_they_came_from():
    lines = decisive_lines(WORLD_LOG, 'logs/world_launch.log')
    assert lines[:4] == [
        'logs/world_launch.log:13: REQUIRED process [rviz-4] has died!',
        'logs/world_launch.log:12: [ WARN] [2.0]: Shutdown request received. Reason given for shutdown: '
        '[[/drive_bot] Reason: new node registered with same name]',
        'logs/world_launch.log:6: [ERROR] [1700000000.1]: Spawn service failed. Exiting.',
        "logs/world_launch.log:10: OSError: [Errno 30] Read-only file system: '/tmp/x'"]
    # Then the symptoms, first ones first; the calls inside the traceback are none.
    assert lines[4] == ('logs/world_launch.log:4: [urdf_spawner-2] process has died [pid 11, exit code 1, '
                        'cmd spawn_model -urdf].')
    assert not any('raise_if_error' in line for line in lines)


def test_a_builds_first_error_is_quoted_before_what_follows_from_it():
    log = ('[ 50%] Building CXX object drive_bot.cpp.o\n'
           'make[2]: *** [drive_bot.dir/build.make:63: drive_bot.cpp.o] Error 1\n'
           '/ws/src/ball_chaser/src/drive_bot.cpp:30:5: error: expected \';\' before \'}\' token\n'
           'make: *** [Makefile:141: all] Error 2\n')
    lines = decisive_lines(log, 'logs/build.log')
    assert lines[0] == "logs/build.log:3: /ws/src/ball_chaser/src/drive_bot.cpp:30:5: error: expected ';' before '}' token"
    assert lines[1].startswith('logs/build.log:2: make[2]')


def test_a_cmake_error_brings_the_message_on_its_indented_lines():
    log = ('-- Using these message generators: gencpp;genpy\n'
           'CMake Error at ball_chaser/CMakeLists.txt:7 (generate_message):\n'
           '  Unknown CMake command "generate_message".\n'
           '\n'
           '-- Configuring incomplete, errors occurred!\n')
    assert decisive_lines(log, 'logs/build.log')[:2] == [
        'logs/build.log:2: CMake Error at ball_chaser/CMakeLists.txt:7 (generate_message):',
        'logs/build.log:3: Unknown CMake command "generate_message".']


def test_fatal_comes_before_error():
    lines = decisive_lines('[ERROR] [1.0]: first\n[FATAL] [2.0]: the end\n', 'logs/x.log')
    assert lines == ['logs/x.log:2: [FATAL] [2.0]: the end', 'logs/x.log:1: [ERROR] [1.0]: first']


def test_the_review_robot_stopping_55_cm_from_the_centre_is_judged_reached(space):
    """Front 0.345 m ahead of its base; it creeps up and stops with the ball's centre 0.55 m
    from its base, 11 cm short of touching the ball."""
    review = RobotGeometry(((0.345, -0.15), (0.345, 0.15), (-0.3, 0.15), (-0.3, -0.15)), ROBOT.camera)
    path = drive(0.0, BALL[0] - 0.55, 60, stay=20)
    verdict = trials.judge(review, space, record(path, commands=GO, calls=GO), 0.1, SURFACE_REACH_M,
                           TIMEOUT)
    assert verdict.reached and verdict.closest == pytest.approx(0.105, abs=1e-3)
    assert math.hypot(path[-1][0] - BALL[0], path[-1][1] - BALL[1]) > 0.54


# -- a trial's states, each at its sim time -----------------------------------------------------

def test_states_are_timed_by_their_count_from_the_first_step():
    # flatsim's default: a 2 ms step, states at 50 Hz from the first step on.
    assert trials.state_times(4, 0.002, 0.02) == [0.002, 0.022, 0.042, 0.062]
    # A period that is no whole number of steps: the first step at least a period later.
    assert trials.state_times(3, 0.003, 0.02) == [0.003, 0.024, 0.045]


def test_the_first_state_of_a_trial_is_the_first_that_shows_the_placement():
    placed, ball = (1.0, -2.0, 3.1), (2.0, 0.5)
    rows = [(2.3, 0.4, 0.1, 0.2, 2.0, 0.5),                  # on its way from before the reset
            (0.0, 1.0, -2.0, -3.1832, 2.0, 0.5),            # placed (the yaw wrapped round)
            (0.02, 1.0001, -2.0, 3.1, 2.0, 0.5)]
    assert trials.placed_row(rows, placed, ball) == 1
    assert trials.placed_row(rows[:1], placed, ball) is None


def test_a_trial_ends_where_the_robot_reached_the_ball_or_at_its_last_pose():
    rec = record(drive(0.0, BALL[0] - 0.2, 40, stay=10), commands=[(0.5, 0.4, 0.0), (3.85, 0.0, 0.0)],
                 calls=[(0.5, 0.4, 0.0), (3.85, 0.0, 0.0)])
    cut = trials.cut_at_end(ROBOT, rec, 0.1, SURFACE_REACH_M)
    row, _how = trials.first_reached(ROBOT, rec, 0.1, SURFACE_REACH_M)
    assert len(cut.poses) == row + 1 < len(rec.poses)
    assert cut.commands == cut.calls == [(0.5, 0.4, 0.0)]
    # Closest and the gap at the end are those at the reach, not after the grader looked.
    assert judge(space=None, rec=cut).facts['gap_at_end'] == judge(space=None, rec=cut).closest
    # One that missed: the commands that came after its last pose do not count.
    missed = record(drive(0.0, 1.0, 20), commands=[(0.5, 0.4, 0.0), (1.95, 0.4, 0.0)])
    cut = trials.cut_at_end(ROBOT, missed, 0.1, SURFACE_REACH_M)
    assert len(cut.poses) == 20 and cut.commands == [(0.5, 0.4, 0.0)]


# -- what the grader keeps, and the stop and drive_bot judgments -------------------------------

def test_a_rolling_log_keeps_the_last_items_and_counts_every_one():
    log = trials.RollingLog(keep=100)
    mark = len(log)
    for index in range(100000):                 # a flood on /cmd_vel
        log.append((index, 0.5, 0.0))
    assert len(log) == 100000 and len(log.items) == 100
    kept = log.since(mark)
    assert [row[0] for row in kept] == list(range(99900, 100000))
    assert log.dropped_since(mark) == 99900
    late = len(log)
    log.append((-1, 0.0, 0.0))
    assert log.since(late) == [(-1, 0.0, 0.0)] and log.dropped_since(late) == 0
    rows, next_mark = log.read(late)
    assert rows == [(-1, 0.0, 0.0)] and next_mark == 100001 and log.read(next_mark) == ([], 100001)


STOP_ARGS = dict(still_speed=0.01, still_distance=0.05, still_turn=0.05)


def still_poses(start, end, x=1.0):
    return [(t, x, 0.0, 0.0) for t in np.arange(start, end, 0.02)]


def test_a_robot_that_stops_when_the_ball_goes_is_still():
    commands = [(0.5, 0.4, 0.1), (1.0, 0.4, 0.0), (1.3, 0.0, 0.0), (1.6, 0.0, 0.0), (2.9, 0.0, 0.0)]
    verdict = trials.judge_stop(commands, still_poses(1.0, 4.0), window_start=2.0, **STOP_ARGS)
    assert verdict.still and verdict.moving_commands == 0 and verdict.last_command == (2.9, 0.0, 0.0)


def test_a_robot_that_rocks_and_ends_on_a_stop_command_did_not_stop():
    """Forward, back to where it was, then a stop: its end pose and last command are those of a
    robot that stopped, which is all the grader used to look at."""
    commands = [(1.0, 0.4, 0.0), (1.2, 0.0, 0.0), (2.2, 0.3, 0.0), (3.0, -0.3, 0.0), (3.8, 0.0, 0.0)]
    poses = still_poses(1.0, 2.2)
    poses += [(t, 1.0 + 0.3 * (t - 2.2), 0.0, 0.0) for t in np.arange(2.2, 3.0, 0.02)]
    poses += [(t, 1.24 - 0.3 * (t - 3.0), 0.0, 0.0) for t in np.arange(3.0, 3.8, 0.02)]
    poses += still_poses(3.8, 4.0)
    verdict = trials.judge_stop(commands, poses, window_start=2.0, **STOP_ARGS)
    assert abs(poses[-1][1] - poses[0][1]) < 0.05 and commands[-1][1:] == (0.0, 0.0)
    assert not verdict.still
    assert verdict.moving_commands == 2 and verdict.first_moving == (2.2, 0.3, 0.0)
    assert verdict.path_m > 0.4


def test_a_command_that_persists_into_the_window_is_motion():
    """The last command persists (Gazebo's diff drive): a node that sends nothing once the ball
    is gone keeps the robot driving, whatever its poses show at the window's ends."""
    verdict = trials.judge_stop([(1.0, 0.4, 0.0)], still_poses(1.0, 4.0), window_start=2.0, **STOP_ARGS)
    assert not verdict.still and verdict.first_moving == (1.0, 0.4, 0.0)


def test_a_move_overridden_by_a_stop_in_the_same_frame_was_never_in_effect():
    """A node that sends "move" and then "stop" from one callback, on every frame: under
    lockstep both come while time is held (the same sim time), in real time a millisecond
    apart. Only the stop was in effect; the robot stayed where it was."""
    frames = np.arange(1.0, 4.0, 0.1)
    for apart in (0.0, 0.001):
        commands = [command for t in frames for command in ((t, 0.5, 0.0), (t + apart, 0.0, 0.0))]
        verdict = trials.judge_stop(commands, still_poses(1.0, 4.0), window_start=2.0, **STOP_ARGS)
        assert verdict.still and verdict.moving_commands == 0, apart
        assert trials.moving(trials.in_effect(commands)) == []
    # A move that stands for a frame or longer is motion.
    commands = [(2.5, 0.5, 0.0), (2.6, 0.0, 0.0)]
    assert trials.in_effect(commands) == commands


def clock_stamp(ticks):
    """Sim time as the grader reads it from /clock: seconds and nanoseconds summed."""
    return ticks // 100 + (ticks % 100) * 10000000 * 1e-9


def test_a_stop_one_clock_tick_after_its_move_overrides_it_however_the_stamps_round():
    """Two ticks 0.01 s apart often differ by a hair more than 0.01 once summed: within 0.01 s
    still means the same answer."""
    pairs = [(clock_stamp(ticks), clock_stamp(ticks + 1)) for ticks in range(100, 400)]
    assert any(stop - move > 0.01 for move, stop in pairs)
    for move, stop in pairs:
        assert trials.in_effect([(move, 0.4, 0.4), (stop, 0.0, 0.0)]) == [(stop, 0.0, 0.0)]


def test_a_robot_has_set_off_once_it_moved_as_much_as_a_trial_needs_to_count_as_motion():
    """By its poses, along its path: a robot that drives off and comes back has set off."""
    def poses(points):
        return [(k * 0.1, x, y, yaw, 2.0, 0.0) for k, (x, y, yaw) in enumerate(points)]
    assert not trials.set_off([]) and not trials.set_off(poses([(0.0, 0.0, 0.0)]))
    assert not trials.set_off(poses([(0.0, 0.0, 0.0), (0.02, 0.0, 0.04), (0.04, 0.0, 0.09)]))
    assert trials.set_off(poses([(0.0, 0.0, 0.0), (0.03, 0.0, 0.0), (0.0, 0.0, 0.0)]))
    # Turned in place, across the yaw's wrap.
    assert trials.set_off(poses([(0.0, 0.0, math.pi - 0.05), (0.0, 0.0, -math.pi + 0.06)]))
    assert trials.path_and_turn(poses([(0.0, 0.0, 0.0), (0.3, 0.4, 0.0)])) == pytest.approx((0.5, 0.0))


def test_a_window_without_poses_is_not_still():
    verdict = trials.judge_stop([(1.0, 0.0, 0.0)], [], window_start=2.0, **STOP_ARGS)
    assert not verdict.still and verdict.poses == 0


def test_the_command_that_matches_the_request_counts_not_the_first():
    commands = [(0.1, 0.0, 0.0), (0.2, 0.4, 0.3), (0.3, 0.25, -0.35000001)]
    assert trials.matching_command(commands, (0.25, -0.35), 1e-4) == commands[2]
    assert trials.matching_command(commands[:2], (0.25, -0.35), 1e-4) is None
