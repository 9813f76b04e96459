"""A trial's picture: zoomed on the trial, with a scale bar, what flatsim simulates (a table's
legs, not its top), the robot's outline and heading at the start and the end, its camera's view
at the start, and the trial's number and outcome."""
import math

import numpy as np
import pytest

from chase_tools import drawing
from flatsim.ros.overhead import CONE_COLOR, CONE_OPACITY

# A 30 m hall with one table (top 1.6 x 0.9 m at 0.74 m, four legs 4 cm across) and a ball.
WORLD = """<?xml version="1.0"?>
<sdf version="1.6"><world name="hall">
  <model name="walls"><static>1</static><link name="l">
    <collision name="n"><pose>0 15 0.5 0 0 0</pose><geometry><box><size>30 0.2 1</size></box></geometry></collision>
    <collision name="s"><pose>0 -15 0.5 0 0 0</pose><geometry><box><size>30 0.2 1</size></box></geometry></collision>
  </link></model>
  <model name="table"><static>1</static><pose>1 0 0 0 0 0</pose><link name="l">
    <collision name="top"><pose>0 0 0.74 0 0 0</pose>
      <geometry><box><size>1.6 0.9 0.03</size></box></geometry></collision>
    <visual name="top"><pose>0 0 0.74 0 0 0</pose>
      <geometry><box><size>1.6 0.9 0.03</size></box></geometry></visual>
    %s
  </link></model>
  <model name="white_ball"><pose>2 0.2 0.1 0 0 0</pose>
    <link name="l"><collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision>
      <visual name="v"><geometry><sphere><radius>0.1</radius></sphere></geometry>
        <material><ambient>1 1 1 1</ambient><diffuse>1 1 1 1</diffuse><emissive>1 1 1 1</emissive></material>
      </visual></link>
  </model>
</world></sdf>
"""
LEG = ('<collision name="leg%d"><pose>%r %r 0.36 0 0 0</pose><geometry><cylinder><radius>0.02</radius>'
       '<length>0.72</length></cylinder></geometry></collision>')
LEGS = [(0.75, 0.4), (0.75, -0.4), (-0.75, 0.4), (-0.75, -0.4)]
FOOTPRINT = ((0.2, -0.15), (0.2, 0.15), (-0.2, 0.15), (-0.2, -0.15))
HFOV = 1.047


@pytest.fixture(scope='module')
def world_map(tmp_path_factory):
    path = tmp_path_factory.mktemp('hall') / 'hall.world'
    path.write_text(WORLD % ''.join(LEG % (index, x, y) for index, (x, y) in enumerate(LEGS)))
    notes = []
    found = drawing.load_world_map(str(path), notes)
    assert notes == []
    return found


def trial_picture(title='trial 3: not reached, closest 0.42 m'):
    # The robot drives from (-1, 0) east, under the table's edge, and stops at (0.6, 0.1).
    xs = np.linspace(-1.0, 0.6, 30)
    robot = np.column_stack([xs, np.linspace(0.0, 0.1, 30), np.zeros(30)])
    ball = np.tile([2.0, 0.2], (30, 1))
    return drawing.TrialPicture(robot=robot, ball=ball, ball_radius=0.1, footprint=FOOTPRINT,
                                camera=(-0.9, 0.0, 0.0, HFOV), title=title)


def pixel(image, frame, x, y):
    col, row = frame.pixel_of(x, y)
    return tuple(int(v) for v in image[row, col])


def test_a_trial_picture_is_zoomed_on_the_trial_not_the_whole_world(world_map):
    image, frame = drawing.render_trial(world_map, trial_picture())
    # The trial spans 3 m (robot start to the ball's far side); the hall spans 30 m.
    assert frame.x_max - frame.x_min < 6.0
    assert frame.x_min <= -1.2 and frame.x_max >= 2.1
    assert frame.resolution <= 0.01
    assert image.shape == frame.shape


def test_a_trial_picture_draws_the_table_s_legs_and_not_its_top(world_map):
    image, frame = drawing.render_trial(world_map, trial_picture())
    for x, y in LEGS:
        assert pixel(image, frame, 1.0 + x, y) == drawing.OBSTACLE_COLOR
    # Under the top, between the legs, the robot could drive: the floor shows there (in the
    # camera's view, as it lies).
    for x, y in ((1.0, 0.25), (1.5, -0.3)):
        assert np.abs(np.array(pixel(image, frame, x, y)) - in_view(world_map)).max() <= 2


def in_view(world_map):
    """The floor's colour under the camera's view wedge."""
    floor = np.array([int(round(255 * c)) for c in world_map.scene.floor_color])
    return np.round(floor * (1 - CONE_OPACITY) + np.array(CONE_COLOR) * CONE_OPACITY)


def test_a_trial_picture_shows_the_camera_s_view_at_the_start_and_the_heading(world_map):
    image, frame = drawing.render_trial(world_map, trial_picture())
    floor = tuple(int(round(255 * c)) for c in world_map.scene.floor_color)
    in_wedge = np.array(pixel(image, frame, 0.0, -0.35))     # inside the 60 degree view, clear of all else
    assert np.abs(in_wedge - in_view(world_map)).max() <= 2
    assert pixel(image, frame, -0.9, 1.2) == floor           # outside the view
    # The start's heading arrow points east (yaw 0): dark pixels ahead of the start, none behind.
    ahead = [pixel(image, frame, -1.0 + d, 0.0) for d in np.arange(0.22, 0.28, 0.01)]
    assert any(max(value) < 60 for value in ahead)


def test_a_trial_picture_has_a_scale_bar_of_a_round_length_and_its_title(world_map):
    image, frame = drawing.render_trial(world_map, trial_picture())
    length = drawing.scale_bar_length(frame)
    assert length in drawing.SCALE_BAR_STEPS_M
    assert length <= (frame.x_max - frame.x_min) / 5.0 < 2.5 * length + 1e-9
    # The bar: a dark line length / resolution pixels long, 12 pixels above the bottom.
    row = image.shape[0] - 12
    dark = np.flatnonzero(image[row, :, :].max(axis=1) < 60)
    assert abs(dark.min() - 10) <= 2
    assert abs((dark.max() - dark.min()) - length / frame.resolution) <= 4
    # The title's white box at the top left.
    assert (image[8:28, 6:120] == 255).all(axis=2).mean() > 0.4


@pytest.mark.parametrize('span', [0.3, 12.0])
def test_a_trial_picture_keeps_its_size_bounded_and_its_surroundings_shown(world_map, span):
    picture = trial_picture()
    picture.robot = np.array([[-span / 2, 0.0, math.pi / 2], [span / 2, 0.0, math.pi / 2]])
    picture.ball = np.array([[span / 2 + 0.3, 0.0]])
    image, frame = drawing.render_trial(world_map, picture)
    assert max(image.shape[:2]) <= drawing.TRIAL_MAX_PIXELS
    assert frame.x_max - frame.x_min >= drawing.TRIAL_MIN_SPAN_M


def test_a_world_with_no_placement_is_drawn_whole_with_its_colliders_and_the_robot(world_map):
    image, frame = drawing.render_world(world_map, (-1.0, 0.0, 0.0), FOOTPRINT, 'no placement')
    # The whole hall: its walls 30 m apart, each drawn in the obstacle colour.
    assert frame.y_min <= -15.1 and frame.y_max >= 15.1
    assert pixel(image, frame, 0.0, 15.0) == drawing.OBSTACLE_COLOR
    assert pixel(image, frame, 0.0, -15.0) == drawing.OBSTACLE_COLOR
    # The robot where it stands, filled in the end's colour, and the ball where the world puts it.
    assert pixel(image, frame, -1.1, 0.1) == drawing.END_COLOR
    assert pixel(image, frame, 2.0, 0.2) == drawing.BALL_MARK_COLOR
