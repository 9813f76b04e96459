"""The main job end to end: chase_demo chases the ball, records a bag and writes its report."""
import os
import pathlib
import re
import subprocess

import cv2
import numpy as np
import pytest

from chase_tools import bag_tracks, drawing, report
from chase_tools.procs import port_taken
from rosproc import RosSystem

TOP = pathlib.Path(__file__).resolve().parent.parent
WORLD = TOP / 'catkin_ws' / 'src' / 'my_robot' / 'worlds' / 'chase_house.world'
CAMERA_SHAPE = (800, 800, 3)


def read_png(path):
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert image is not None, '%s is missing or not a PNG' % path
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


def run_demo(*args, env=None, timeout=300):
    return subprocess.run(['rosrun', 'chase_tools', 'chase_demo'] + list(args), env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=timeout, check=False)


@pytest.fixture(scope='module')
def running_master(tmp_path_factory):
    """A roscore already running, as a student's would be, and the shell pointing at it."""
    with RosSystem(tmp_path_factory.mktemp('roscore')) as ros:
        yield ros


def parameter_names(ros):
    return sorted(ros.graph.master().getParamNames())


@pytest.fixture(scope='module')
def demo(tmp_path_factory, running_master):
    out = tmp_path_factory.mktemp('demo')
    before = parameter_names(running_master)
    result = run_demo('--output', str(out), '--timeout', '40', env=running_master.env)
    return result, out, before


def test_demo_starts_a_master_of_its_own_and_leaves_nothing_behind(demo, running_master):
    result, _, before = demo
    ports = re.findall(r'a ROS master of its own on port (\d+)', result.stdout)
    assert len(ports) == 1 and int(ports[0]) != running_master.port, result.stdout
    assert parameter_names(running_master) == before
    assert not port_taken(int(ports[0])), 'the demo\'s master outlived it'


def test_a_taken_port_is_an_argument_error_and_the_master_there_is_untouched(running_master, tmp_path):
    before = parameter_names(running_master)
    result = run_demo('--port', str(running_master.port), '--output', str(tmp_path), timeout=120)
    assert result.returncode == 2, result.stdout
    assert ('chase_demo: error: argument --port: port %d is taken, most likely by another ROS master'
            % running_master.port) in result.stdout
    assert 'Traceback' not in result.stdout
    assert parameter_names(running_master) == before


@pytest.mark.parametrize('argument, value, message', [
    ('--timeout', 'nan', "'nan' is not a finite number"),
    ('--timeout', '-5', '-5 must be more than 0'),
    ('--camera-rate', '0', '0 must be more than 0'),
    ('--camera-rate', 'nan', "'nan' is not a finite number"),
    ('--port', '99999', '99999 must be at most 65535'),
    ('--output', '/proc/nope', 'cannot make the folder /proc/nope'),
])
def test_bad_arguments_are_argument_errors(argument, value, message, tmp_path):
    args = [argument, value] if argument == '--output' else [argument, value, '--output', str(tmp_path)]
    result = run_demo(*args, timeout=120)
    assert result.returncode == 2, result.stdout
    assert 'chase_demo: error: argument %s: %s' % (argument, message) in result.stdout, result.stdout
    assert 'Traceback' not in result.stdout


def test_demo_reaches_the_ball(demo):
    result, out, _ = demo
    assert result.returncode == 0, result.stdout
    assert 'reached the ball' in result.stdout
    assert 'distance to ball' in result.stdout
    summary = (out / 'summary.md').read_text()
    assert '- Outcome: reached' in summary, summary
    assert 'Real-time factor: unknown' not in summary


def test_first_sight_is_a_camera_frame_with_the_ball(demo):
    _, out, _ = demo
    image = read_png(out / 'first_sight.png')
    assert image.shape == CAMERA_SHAPE
    assert np.all(image == 255, axis=2).sum() > 10


def test_trajectory_shows_the_path_and_the_ball(demo):
    _, out, _ = demo
    summary = bag_tracks.read_bag(str(out / 'chase.bag'))
    assert summary.robot_source == 'model states'
    notes = []
    world_map = drawing.load_world_map(str(WORLD), notes)
    assert notes == []
    ball = report.ball_track(summary, world_map, 'white_ball')
    frame = drawing.trajectory_frame(summary, world_map, ball)
    image = read_png(out / 'trajectory.png')
    assert image.shape == frame.shape
    on_path = np.all(image == drawing.PATH_COLOR, axis=2)
    # At least a metre of path, drawn three pixels wide at about 1 cm a pixel.
    assert on_path.sum() > 1.0 / frame.resolution
    col, row = frame.pixel_of(ball.x[-1], ball.y[-1])
    assert tuple(image[row, col]) == drawing.BALL_MARK_COLOR
    start_col, start_row = frame.pixel_of(summary.robot.x[0], summary.robot.y[0])
    ring = image[start_row - 12:start_row + 13, start_col - 12:start_col + 13]
    assert np.all(ring == drawing.START_COLOR, axis=2).any()


def test_report_of_a_cut_copy_of_the_bag(demo, tmp_path):
    _, out, _ = demo
    data = (out / 'chase.bag').read_bytes()
    cut = tmp_path / 'cut.bag'
    cut.write_bytes(data[:len(data) * 3 // 5])
    result = subprocess.run(['rosrun', 'chase_tools', 'report', str(cut), '--world', str(WORLD),
                             '--output', str(tmp_path / 'report')],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            timeout=120, check=False, env=dict(os.environ))
    assert result.returncode == 0, result.stderr
    assert 'cut short' in result.stderr and 'Traceback' not in result.stderr
    summary = (tmp_path / 'report' / 'summary.md').read_text()
    assert 'cut short' in summary
    assert read_png(tmp_path / 'report' / 'trajectory.png').ndim == 3
    whole = bag_tracks.read_bag(str(out / 'chase.bag'))
    part = bag_tracks.read_bag(str(cut))
    assert 0 < len(part.robot) < len(whole.robot)
