"""The main job end to end: chase_demo chases the ball, records a bag and writes its report."""
import os
import pathlib
import subprocess

import cv2
import numpy as np
import pytest

from chase_tools import report
from rosproc import free_port

TOP = pathlib.Path(__file__).resolve().parent.parent
WORLD = TOP / 'catkin_ws' / 'src' / 'my_robot' / 'worlds' / 'chase_house.world'
CAMERA_SHAPE = (800, 800, 3)


def read_png(path):
    image = cv2.imread(str(path), cv2.IMREAD_COLOR)
    assert image is not None, '%s is missing or not a PNG' % path
    return cv2.cvtColor(image, cv2.COLOR_BGR2RGB)


@pytest.fixture(scope='module')
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp('demo')
    # A master port of its own, so that a demo running elsewhere on the machine does not collide.
    result = subprocess.run(['rosrun', 'chase_tools', 'chase_demo', '--output', str(out),
                             '--port', str(free_port()), '--timeout', '40'],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            timeout=300, check=False)
    return result, out


def test_demo_reaches_the_ball(demo):
    result, out = demo
    assert result.returncode == 0, result.stdout
    assert 'reached the ball' in result.stdout
    assert 'distance to ball' in result.stdout
    summary = (out / 'summary.md').read_text()
    assert '- Outcome: reached' in summary, summary
    assert 'Real-time factor: unknown' not in summary


def test_first_sight_is_a_camera_frame_with_the_ball(demo):
    _, out = demo
    image = read_png(out / 'first_sight.png')
    assert image.shape == CAMERA_SHAPE
    assert np.all(image == 255, axis=2).sum() > 10


def test_trajectory_shows_the_path_and_the_ball(demo):
    _, out = demo
    summary = report.read_bag(str(out / 'chase.bag'))
    assert summary.robot_source == 'model states'
    notes = []
    world_map = report.load_world_map(str(WORLD), notes)
    assert notes == []
    ball = report.ball_track(summary, world_map, 'white_ball')
    frame = report.trajectory_frame(summary, world_map, ball)
    image = read_png(out / 'trajectory.png')
    assert image.shape == frame.shape
    on_path = np.all(image == report.PATH_COLOR, axis=2)
    # At least a metre of path, drawn three pixels wide at about 1 cm a pixel.
    assert on_path.sum() > 1.0 / frame.resolution
    col, row = frame.pixel_of(ball.x[-1], ball.y[-1])
    assert tuple(image[row, col]) == report.BALL_MARK_COLOR
    start_col, start_row = frame.pixel_of(summary.robot.x[0], summary.robot.y[0])
    ring = image[start_row - 12:start_row + 13, start_col - 12:start_col + 13]
    assert np.all(ring == report.START_COLOR, axis=2).any()


def test_report_of_a_cut_copy_of_the_bag(demo, tmp_path):
    _, out = demo
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
    whole = report.read_bag(str(out / 'chase.bag'))
    part = report.read_bag(str(cut))
    assert 0 < len(part.robot) < len(whole.robot)
