"""The overhead picture: world-to-pixel mapping, the world in its colours, robots at their poses."""
import math
import pathlib

import numpy as np
import pytest

from flatsim.errors import FlatsimError
from flatsim.loading.config import CameraConfig, DriveConfig, LaserConfig, Link, RobotSpec
from flatsim.loading.sdf_world import load_world
from flatsim.pose import Pose
from flatsim.ros.overhead import (CONE_COLOR, CONE_OPACITY, HEADING_COLOR, ROBOT_COLORS,
                                  SCAN_HIT_COLOR, MapFrame, OverheadView, fit_frame,
                                  footprint_points, render, rgb8, scan_hits)
from flatsim.world.scene import Prim, Scene
from flatsim.world.sim import Simulation

WORLD = pathlib.Path(__file__).parent / 'fixtures' / 'worlds' / 'marker_room.world'
# A 0.4 m x 0.3 m box robot with a camera looking ahead and a 180 degree lidar.
FOOTPRINT = [(0.2, 0.15), (-0.2, 0.15), (-0.2, -0.15), (0.2, -0.15)]


def box_robot_spec():
    return RobotSpec(
        name='box_bot', root_link='base', links={'base': Link('base')}, joints={},
        drive=DriveConfig(left_joints=['left'], right_joints=['right'], wheel_separation=0.3,
                          wheel_diameter=0.1),
        cameras=[CameraConfig(link='base', pose=Pose(0.2, 0.0, 0.2), hfov=1.2, far=20.0)],
        lasers=[LaserConfig(link='base', pose=Pose(0.0, 0.0, 0.3), samples=181,
                            min_angle=-math.pi / 2, max_angle=math.pi / 2, range_min=0.1,
                            range_max=10.0)],
        footprint=FOOTPRINT, mass=2.0)


def pixel(image, frame, x, y):
    col, row = frame.pixel_of(x, y)
    return tuple(int(v) for v in image[row, col])


# MapFrame

def test_image_size_is_bounds_over_resolution():
    frame = MapFrame(-1.0, -2.0, 3.0, 1.0, 0.05)
    assert (frame.width, frame.height) == (80, 60)
    assert frame.shape == (60, 80, 3)
    assert MapFrame(0.0, 0.0, 1.01, 1.0, 0.1).width == 11


def test_pixel_mapping_puts_y_up_and_round_trips():
    frame = MapFrame(-1.0, -2.0, 3.0, 1.0, 0.05)
    assert frame.pixel_of(-1.0, 1.0 - 1e-9) == (0, 0)
    assert frame.pixel_of(3.0 - 1e-9, -2.0 + 1e-9) == (79, 59)
    assert frame.pixel_of(0.0, 0.0) == (20, 20)
    assert frame.to_world(20, 20) == pytest.approx((0.025, -0.025))
    points = np.array([[0.31, -1.27], [2.9, 0.8]])
    pixels = np.floor(frame.to_pixel(points)).astype(int)
    back = np.array([frame.to_world(c, r) for c, r in pixels])
    assert np.all(np.abs(back - points) <= 0.025 + 1e-12)


@pytest.mark.parametrize('bounds, resolution', [((0, 0, 0, 1), 0.1), ((0, 0, 1, 1), 0.0),
                                                ((0, 0, math.inf, 1), 0.1)])
def test_bad_frames_are_refused(bounds, resolution):
    with pytest.raises(FlatsimError):
        MapFrame(*bounds, resolution)


def test_frame_coarsens_rather_than_exceed_max_pixels():
    frame = MapFrame.around(0.0, 0.0, 100.0, 10.0, 0.01, margin=0.0, max_pixels=500)
    assert frame.resolution == pytest.approx(0.2)
    assert frame.width == 500


# Drawing

def test_box_fills_exactly_its_footprint_in_its_colour():
    scene = Scene([Prim.box('wall', 1.0, 0.5, 0.0, 1.0, 0.4, 0.0, 1.0, color=(0.2, 0.4, 0.6))])
    frame = MapFrame(0.0, 0.0, 2.0, 1.0, 0.01)
    image, same = render(scene, frame)
    assert same is frame
    assert image.shape == (100, 200, 3)
    wall = rgb8((0.2, 0.4, 0.6))
    floor = rgb8(scene.floor_color)
    assert pixel(image, frame, 1.0, 0.5) == wall
    assert pixel(image, frame, 0.505, 0.305) == wall
    assert pixel(image, frame, 1.495, 0.695) == wall
    assert pixel(image, frame, 0.49, 0.5) == floor
    assert pixel(image, frame, 1.0, 0.71) == floor
    # Exactly the pixels whose centres lie inside: rows 30..69, columns 50..149.
    is_wall = np.all(image == wall, axis=2)
    expected = np.zeros((100, 200), dtype=bool)
    expected[30:70, 50:150] = True
    assert np.array_equal(is_wall, expected)


def test_higher_visual_covers_lower_one():
    scene = Scene([Prim.box('top', 1.0, 1.0, 0.0, 1.0, 1.0, 0.7, 0.75, color=(0.5, 0.3, 0.1)),
                   Prim.cylinder('leg', 1.0, 1.0, 0.1, 0.0, 0.7, color=(0.0, 0.0, 1.0))])
    image, frame = render(scene, MapFrame(0.0, 0.0, 2.0, 2.0, 0.02))
    assert pixel(image, frame, 1.0, 1.0) == rgb8((0.5, 0.3, 0.1))


def test_robot_is_drawn_at_its_pose_with_heading_mark():
    scene = Scene([])
    frame = MapFrame(-2.0, -2.0, 2.0, 2.0, 0.01)
    yaw = 2.0
    outline = footprint_points(FOOTPRINT, 0.5, -0.3, yaw)
    image, _ = render(scene, frame, robots=[(outline, (0.5, -0.3, yaw))])
    assert pixel(image, frame, 0.5, -0.3) == ROBOT_COLORS[0]
    ahead = (0.5 + 0.15 * math.cos(yaw), -0.3 + 0.15 * math.sin(yaw))
    assert pixel(image, frame, *ahead) == HEADING_COLOR
    behind = (0.5 - 0.15 * math.cos(yaw), -0.3 - 0.15 * math.sin(yaw))
    assert pixel(image, frame, *behind) == ROBOT_COLORS[0]
    # The long side lies across the heading: 0.13 m to the side is still robot, 0.25 m is not.
    side = (-math.sin(yaw), math.cos(yaw))
    assert pixel(image, frame, 0.5 + 0.13 * side[0], -0.3 + 0.13 * side[1]) == ROBOT_COLORS[0]
    assert pixel(image, frame, 0.5 + 0.25 * side[0], -0.3 + 0.25 * side[1]) == \
        rgb8(scene.floor_color)


def test_scan_hits_mark_the_finite_ranges_only():
    angles = np.array([0.0, math.pi / 2, math.pi])
    hits = scan_hits(np.array([1.0, np.inf, 0.5]), angles, 0.2, 0.1, math.pi / 2)
    assert hits == pytest.approx(np.array([[0.2, 1.1], [0.2, 0.1 - 0.5]]))
    frame = MapFrame(-2.0, -2.0, 2.0, 2.0, 0.02)
    image, _ = render(Scene([]), frame, scans=[hits])
    assert pixel(image, frame, 0.2, 1.1) == SCAN_HIT_COLOR
    assert pixel(image, frame, 0.2, -0.4) == SCAN_HIT_COLOR
    assert np.count_nonzero(np.all(image == SCAN_HIT_COLOR, axis=2)) == 2 * 9


def test_camera_cone_tints_what_the_camera_sees():
    scene = Scene([])
    frame = MapFrame(-2.0, -2.0, 2.0, 2.0, 0.02)
    image, _ = render(scene, frame, cameras=[(0.0, 0.0, 0.0, math.pi / 2, 1.5)])
    floor = np.array(rgb8(scene.floor_color), dtype=float)
    tinted = tuple(int(v) for v in np.round(floor * (1 - CONE_OPACITY)
                                            + np.array(CONE_COLOR) * CONE_OPACITY))
    assert pixel(image, frame, 1.0, 0.3) == tinted
    assert pixel(image, frame, 1.0, 0.0) == tinted
    assert pixel(image, frame, 1.0, 1.2) == rgb8(scene.floor_color)    # outside the 45 degree edge
    assert pixel(image, frame, -0.5, 0.0) == rgb8(scene.floor_color)   # behind the camera
    assert pixel(image, frame, 1.7, 0.0) == rgb8(scene.floor_color)    # beyond its length


def test_fit_frame_holds_the_world_and_the_robots():
    scene = Scene([Prim.box('wall', 0.0, 0.0, 0.0, 2.0, 1.0, 0.0, 1.0)])
    frame = fit_frame(scene, [footprint_points(FOOTPRINT, 3.0, 0.0, 0.0)], 0.05, margin=0.5)
    assert (frame.x_min, frame.y_min, frame.x_max, frame.y_max) == \
        pytest.approx((-1.5, -1.0, 3.7, 1.0))
    empty = fit_frame(Scene([]), [], 0.05, margin=0.0)
    assert (empty.width, empty.height) == (120, 120)


# A whole simulation

@pytest.fixture
def driven_sim():
    """The fixture room with a robot that has driven a curve away from its spawn pose."""
    sim = Simulation(load_world(str(WORLD)))
    robot = sim.spawn_robot('box_bot', box_robot_spec(), Pose(0.0, 0.5, 0.0, yaw=0.3))
    robot.drive.set_command(0.3, 0.5)
    for _ in range(500):
        sim.step()
    return sim, robot


def test_overhead_shows_the_robot_at_its_model_pose(driven_sim):
    sim, _ = driven_sim
    view = OverheadView(resolution=0.02)
    image = view.render(sim)
    frame = view.frame
    assert image.shape == (frame.height, frame.width, 3)
    assert frame.width == math.ceil((frame.x_max - frame.x_min) / 0.02 - 1e-9)
    pose = sim.model_pose('box_bot')
    assert math.hypot(pose.x - 0.0, pose.y - 0.5) > 0.2 and abs(pose.yaw - 0.3) > 0.3
    assert pixel(image, frame, pose.x, pose.y) == ROBOT_COLORS[0]
    ahead = (pose.x + 0.15 * math.cos(pose.yaw), pose.y + 0.15 * math.sin(pose.yaw))
    assert pixel(image, frame, *ahead) == HEADING_COLOR
    assert pixel(image, frame, 0.0, 0.5) != ROBOT_COLORS[0]


def test_overhead_draws_the_world_ball_and_lidar_hits(driven_sim):
    sim, robot = driven_sim
    laser = next(slot for slot in robot.sensors if slot.kind == 'laser')
    ranges = sim.sense(laser)
    eye = sim.sensor_pose(laser)
    view = OverheadView(resolution=0.02)
    image = view.render(sim, [(ranges, laser.impl.angles, (eye.x, eye.y, eye.yaw))])
    frame = view.frame
    assert pixel(image, frame, -1.0, 1.0) == rgb8((0.1, 0.6, 0.2))       # the post
    assert pixel(image, frame, 0.5, -1.0) == (255, 255, 255)             # the ball
    hits = scan_hits(ranges, laser.impl.angles, eye.x, eye.y, eye.yaw)
    assert len(hits) > 10
    on_image = [pixel(image, frame, x, y) for x, y in hits
                if frame.contains_pixel(*frame.pixel_of(x, y))]
    assert on_image and all(color == SCAN_HIT_COLOR for color in on_image)


def test_overhead_keeps_its_size_while_the_ball_moves(driven_sim):
    sim, _ = driven_sim
    view = OverheadView(resolution=0.02)
    first = view.render(sim)
    sim.set_model_state('white_ball', Pose(1.5, 0.0, 0.1))
    second = view.render(sim)
    assert second.shape == first.shape
    assert pixel(second, view.frame, 1.5, 0.0) == (255, 255, 255)
    assert pixel(second, view.frame, 0.5, -1.0) == rgb8(sim.scene.floor_color)


def test_overhead_draws_a_static_model_where_it_was_moved(driven_sim):
    sim, _ = driven_sim
    view = OverheadView(resolution=0.02)
    first = view.render(sim)
    post = rgb8((0.1, 0.6, 0.2))
    assert pixel(first, view.frame, -1.0, 1.0) == post
    assert pixel(first, view.frame, -1.0, -1.0) == rgb8(sim.scene.floor_color)
    sim.set_model_state('post', Pose(-1.0, -1.0, 0.0))
    second = view.render(sim)
    assert second.shape == first.shape
    assert pixel(second, view.frame, -1.0, -1.0) == post
    assert pixel(second, view.frame, -1.0, 1.0) == rgb8(sim.scene.floor_color)
