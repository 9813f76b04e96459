import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from flatsim.errors import FlatsimError
from flatsim.loading.config import CameraConfig
from flatsim.sensors.camera import AMBIENT, FALLOFF_PER_METRE, PinholeCamera
from flatsim.sensors.raycast import nearest, surface_normal
from flatsim.world.scene import Prim, Scene

WIDTH, HEIGHT, HFOV = 640, 480, 1.3962634
CAMERA_Z = 0.3


def camera(image_format='R8G8B8', **overrides):
    values = dict(width=WIDTH, height=HEIGHT, hfov=HFOV, image_format=image_format)
    values.update(overrides)
    return PinholeCamera(CameraConfig(**values))


def focal():
    return WIDTH / (2 * math.tan(HFOV / 2))


def white_mask(image):
    return (image == 255).all(axis=2)


def to_camera_frame(point, x, y, yaw):
    dx, dy = point[0] - x, point[1] - y
    return dx * math.cos(yaw) + dy * math.sin(yaw), dy * math.cos(yaw) - dx * math.sin(yaw)


@pytest.mark.parametrize('ball, pose', [
    ((2.0, 0.0, 0.1), (0.0, 0.0, 0.0)),
    ((1.5, 0.6, 0.1), (0.0, 0.0, 0.0)),            # left of centre
    ((3.0, -1.4, 0.1), (0.0, 0.0, 0.0)),           # right, far
    ((0.9, 0.2, 0.5), (0.0, 0.0, 0.0)),            # near, above the camera
    ((1.0, 3.0, 0.1), (0.5, 1.0, 1.2)),            # camera moved and turned
    ((-2.0, -1.0, 0.25), (0.0, 0.0, math.pi + 0.3)),
])
def test_ball_projects_to_the_analytic_disc(ball, pose):
    radius = 0.1
    scene = Scene([Prim.sphere('ball', ball[0], ball[1], ball[2], radius, color=(1, 1, 1),
                               unlit_white=True)])
    image = camera().render(scene, pose[0], pose[1], CAMERA_Z, pose[2])
    rows, columns = np.nonzero(white_mask(image))
    depth, left = to_camera_frame(ball, *pose)
    f = focal()
    expected_u = (WIDTH - 1) / 2 - f * left / depth
    expected_v = (HEIGHT - 1) / 2 - f * (ball[2] - CAMERA_Z) / depth
    expected_radius = f * radius / math.sqrt(depth ** 2 - radius ** 2)
    assert columns.size > 50
    assert abs(columns.mean() - expected_u) < 1.0
    assert abs(rows.mean() - expected_v) < 1.0
    assert abs(math.sqrt(columns.size / math.pi) - expected_radius) < 1.0
    assert abs((columns.max() - columns.min() + 1) / 2 - expected_radius) < 1.0
    assert abs((rows.max() - rows.min() + 1) / 2 - expected_radius) < 1.0


def test_ball_to_the_left_renders_on_the_left():
    scene = Scene([Prim.sphere('ball', 2.0, 0.5, 0.1, 0.1, unlit_white=True)])
    columns = np.nonzero(white_mask(camera().render(scene, 0, 0, CAMERA_Z, 0)))[1]
    assert columns.max() < WIDTH / 2


def colourful_room(ball_unlit=True):
    colors = [(1.0, 1.0, 1.0), (0.999, 1.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0),
              (0.0, 0.0, 1.0), (1.0, 1.0, 0.9), (0.3, 0.3, 0.3), (1.0, 1.0, 1.0)]
    prims = []
    for i, color in enumerate(colors):
        angle = 2 * math.pi * i / len(colors)
        prims.append(Prim.box('wall_%d' % i, 3 * math.cos(angle), 3 * math.sin(angle), angle,
                              0.2, 2.6, 0.0, 2.0, color=color))
    prims.append(Prim.cylinder('white_post', 1.2, -0.9, 0.15, 0.0, 1.0, color=(1, 1, 1)))
    prims.append(Prim.box('white_table', 1.5, 0.8, 0.3, 0.6, 0.6, 0.5, 0.55,
                          color=(1, 1, 1)))
    ball_color = (1.0, 1.0, 1.0) if ball_unlit else (1.0, 0.0, 0.0)
    prims.append(Prim.sphere('ball', 1.4, 0.1, 0.1, 0.1, color=ball_color,
                             unlit_white=ball_unlit))
    return Scene(prims, sky_color=(1, 1, 1), floor_color=(1, 1, 1))


@pytest.mark.parametrize('yaw', [0.0, 0.8, 2.4, -1.6])
def test_only_the_unlit_white_ball_is_pure_white(yaw):
    cam = camera()
    with_ball = cam.render(colourful_room(), 0.0, 0.0, CAMERA_Z, yaw)
    red_ball = cam.render(colourful_room(ball_unlit=False), 0.0, 0.0, CAMERA_Z, yaw)
    ball_pixels = (with_ball != red_ball).any(axis=2)
    np.testing.assert_array_equal(white_mask(with_ball), ball_pixels)
    assert not white_mask(red_ball).any()
    # Light surfaces do come out near white, so the test would see a leak.
    assert (red_ball.min(axis=2) >= 250).any()
    if yaw == 0.0:
        assert ball_pixels.sum() > 500


def test_nearer_object_occludes_a_farther_one():
    scene = Scene([
        Prim.box('far_blue', 4.0, 0.0, 0.0, 0.2, 6.0, 0.0, 2.0, color=(0, 0, 1)),
        Prim.box('near_red', 2.0, 0.0, 0.0, 0.2, 0.5, 0.0, 1.0, color=(1, 0, 0)),
    ])
    image = camera().render(scene, 0.0, 0.0, CAMERA_Z, 0.0)
    centre = image[:, WIDTH // 2]
    red = (centre[:, 0] > 0) & (centre[:, 2] == 0)
    blue = (centre[:, 2] > 0) & (centre[:, 0] == 0)
    f = focal()
    near_top = (HEIGHT - 1) / 2 - f * (1.0 - CAMERA_Z) / 1.9
    # The red box covers the centre column from its top down to the floor line at 2 m;
    # the taller blue wall shows above it, and nothing blue shows through it.
    assert red.any() and blue.any()
    assert np.flatnonzero(red).min() == math.ceil(near_top)
    assert np.flatnonzero(blue).max() < np.flatnonzero(red).min()
    # Beside the red box the blue wall reaches down to its own floor line.
    side = image[:, WIDTH // 2 + 100]
    assert not ((side[:, 0] > 0) & (side[:, 2] == 0)).any()
    assert ((side[:, 2] > 0) & (side[:, 0] == 0)).sum() > np.count_nonzero(blue)


def test_floating_table_top_lets_the_wall_show_above_and_below():
    scene = Scene([
        Prim.box('wall', 4.0, 0.0, 0.0, 0.2, 6.0, 0.0, 2.0, color=(0, 0, 1)),
        Prim.box('table_top', 2.0, 0.0, 0.0, 1.0, 1.0, 0.7, 0.75, color=(1, 0, 0)),
    ])
    centre = camera().render(scene, 0.0, 0.0, CAMERA_Z, 0.0)[:, WIDTH // 2]
    red_rows = np.flatnonzero((centre[:, 0] > 0) & (centre[:, 2] == 0))
    blue_rows = np.flatnonzero((centre[:, 2] > 0) & (centre[:, 0] == 0))
    assert red_rows.size > 0
    assert (blue_rows < red_rows.min()).any() and (blue_rows > red_rows.max()).any()
    # The table top's underside is seen from below: it spans from the projection of
    # its top edge at the near side down to its underside at the far side.
    f = focal()
    assert red_rows.min() == math.ceil((HEIGHT - 1) / 2 - f * (0.75 - CAMERA_Z) / 1.5)
    assert red_rows.max() == math.floor((HEIGHT - 1) / 2 - f * (0.7 - CAMERA_Z) / 2.5)


@pytest.mark.parametrize('distance, height', [(2.0, 1.0), (3.3, 1.5), (5.0, 0.6)])
def test_wall_top_row_matches_the_projection_of_its_height(distance, height):
    scene = Scene([Prim.box('wall', distance + 0.1, 0.0, 0.0, 0.2, 20.0, 0.0, height,
                            color=(0.2, 0.6, 0.2))], sky_color=(0.5, 0.5, 0.9))
    image = camera().render(scene, 0.0, 0.0, CAMERA_Z, 0.0)
    sky = image[0, 0]
    not_sky = ~(image == sky).all(axis=2)
    top_rows = np.argmax(not_sky, axis=0)
    expected = (HEIGHT - 1) / 2 - focal() * (height - CAMERA_Z) / distance
    # Depth is measured along the optical axis, so the wall's top is one straight row.
    assert (top_rows == top_rows[0]).all()
    assert top_rows[0] == math.ceil(expected)


def test_floor_below_the_horizon_and_sky_above():
    scene = Scene([], sky_color=(0.2, 0.4, 0.6), floor_color=(0.5, 0.5, 0.5))
    image = camera().render(scene, 0.0, 0.0, CAMERA_Z, 0.0)
    np.testing.assert_array_equal(image[:HEIGHT // 2], np.broadcast_to([51, 102, 153],
                                                                       (HEIGHT // 2, WIDTH, 3)))
    np.testing.assert_array_equal(image[HEIGHT // 2:], 128)


def test_excluded_prims_are_not_drawn():
    scene = Scene([Prim.box('own_body', 0.5, 0.0, 0.0, 0.2, 2.0, 0.0, 1.0, color=(1, 0, 0))])
    cam = camera()

    def red_pixels(image):
        return np.count_nonzero((image[..., 0] > 0) & (image[..., 1] == 0))

    assert red_pixels(cam.render(scene, 0, 0, CAMERA_Z, 0)) > WIDTH * HEIGHT / 4
    assert red_pixels(cam.render(scene, 0, 0, CAMERA_Z, 0, exclude=[0])) == 0


def test_bgr8_swaps_channels_and_mono8_is_one_channel():
    scene = colourful_room()
    rgb = camera('R8G8B8').render(scene, 0.0, 0.0, CAMERA_Z, 0.5)
    bgr = camera('B8G8R8').render(scene, 0.0, 0.0, CAMERA_Z, 0.5)
    mono_camera = camera('L8')
    mono = mono_camera.render(scene, 0.0, 0.0, CAMERA_Z, 0.5)
    assert not np.array_equal(rgb[..., 0], rgb[..., 2])
    np.testing.assert_array_equal(bgr, rgb[..., ::-1])
    assert mono.shape == (HEIGHT, WIDTH) and mono.dtype == np.uint8
    assert mono_camera.encoding() == 'mono8'
    np.testing.assert_array_equal(mono == 255, white_mask(rgb))


def test_render_into_a_given_buffer():
    out = np.zeros((HEIGHT, WIDTH, 3), dtype=np.uint8)
    cam = camera()
    scene = colourful_room()
    result = cam.render(scene, 0.0, 0.0, CAMERA_Z, 0.0, out=out)
    assert result is out or np.shares_memory(result, out)
    np.testing.assert_array_equal(out, cam.render(scene, 0.0, 0.0, CAMERA_Z, 0.0))


@pytest.mark.parametrize('shape, dtype', [((HEIGHT, WIDTH), np.uint8), ((HEIGHT, WIDTH, 3), float),
                                          ((WIDTH, HEIGHT, 3), np.uint8)])
def test_render_into_a_wrong_buffer_raises(shape, dtype):
    with pytest.raises(FlatsimError, match='render buffer'):
        camera().render(colourful_room(), 0.0, 0.0, CAMERA_Z, 0.0, out=np.zeros(shape, dtype))


wall_layouts = st.lists(st.tuples(st.floats(-4.0, 4.0), st.floats(-4.0, 4.0),
                                  st.floats(-math.pi, math.pi), st.floats(0.1, 2.0),
                                  st.floats(0.1, 2.0)), min_size=1, max_size=24)


@settings(max_examples=60, deadline=None)
@given(walls=wall_layouts, yaw=st.floats(-math.pi, math.pi), layers=st.integers(1, 24))
def test_horizon_row_shows_the_wall_each_column_ray_meets_first(walls, yaw, layers):
    # Full-height walls hide everything behind them, so at the camera's own height
    # each column must show the first wall its ray enters, whatever the layer count.
    scene = Scene([Prim.box('wall_%d' % i, x, y, wall_yaw, size_x, size_y, 0.0, 2.0,
                            color=((i + 1) / 25.0, 0.5, 1.0 - (i + 1) / 25.0))
                   for i, (x, y, wall_yaw, size_x, size_y) in enumerate(walls)])
    cam = PinholeCamera(CameraConfig(width=64, height=48, hfov=HFOV), layers=layers)
    row = cam.render(scene, 0.0, 0.0, CAMERA_Z, yaw)[int(cam.centre_v)]
    angles = yaw + np.arctan2(cam.centre_u - np.arange(cam.width), cam.focal)
    distance, first = nearest(scene, 0.0, 0.0, np.cos(angles), np.sin(angles),
                              np.arange(len(walls)))
    palette, sky, _ = cam._colors(scene)
    packed = row[:, 0].astype(np.uint32) | (row[:, 1].astype(np.uint32) << 8) \
        | (row[:, 2].astype(np.uint32) << 16)
    depth = distance * np.cos(angles - yaw)
    # A wall nearer than the near clip plane is not drawn and shows what lies behind
    # it; one grazed exactly at that plane may round either way.
    clear = depth > cam.config.near + 1e-6
    for column in np.flatnonzero(clear):
        if first[column] < 0 or depth[column] > cam.config.far:
            assert packed[column] == sky
        else:
            assert packed[column] in palette[first[column]], column


def test_camera_info_matches_gazebo_ros_camera():
    cam = camera(width=800, height=600, hfov=1.3962634, hack_baseline=0.07,
                 distortion=(0.1, -0.2, 0.001, 0.002, 0.03))
    info = cam.info()
    f = 800 / (2 * math.tan(1.3962634 / 2))
    assert cam.encoding() == 'rgb8'
    assert info['width'] == 800 and info['height'] == 600
    assert info['distortion_model'] == 'plumb_bob'
    assert info['D'] == [0.1, -0.2, 0.001, 0.002, 0.03]
    np.testing.assert_allclose(info['K'], [f, 0, 400.5, 0, f, 300.5, 0, 0, 1])
    np.testing.assert_allclose(info['R'], np.eye(3).ravel())
    np.testing.assert_allclose(info['P'], [f, 0, 400.5, -f * 0.07, 0, f, 300.5, 0, 0, 0, 1, 0])
    assert f == pytest.approx(476.7, abs=0.05)


@pytest.mark.parametrize('image_format', ['R16G16B16', 'BAYER_RGGB8', 'L16', 'rgb8', ''])
def test_unsupported_format_raises(image_format):
    with pytest.raises(FlatsimError, match='not supported'):
        camera(image_format)


@pytest.mark.parametrize('overrides', [dict(width=0), dict(hfov=0.0), dict(hfov=4.0),
                                       dict(near=0.0), dict(far=0.05)])
def test_bad_geometry_raises(overrides):
    with pytest.raises(FlatsimError):
        camera(**overrides)


def test_surface_normal_points_out_of_the_face_hit():
    yaw = 0.3
    scene = Scene([Prim.box('crate', 2.0, 0.0, yaw, 1.0, 0.5, 0.0, 1.0),
                   Prim.cylinder('post', 0.0, 3.0, 0.5, 0.0, 1.0)])
    c, s = math.cos(yaw), math.sin(yaw)
    local_points = [(0.5, 0.1), (0.1, -0.25), (-0.5, -0.2)]
    local_normals = [(1, 0), (0, -1), (-1, 0)]
    hit_x = [2.0 + px * c - py * s for px, py in local_points] + [0.5 * math.cos(2.0)]
    hit_y = [px * s + py * c for px, py in local_points] + [3.0 + 0.5 * math.sin(2.0)]
    normals = [surface_normal(scene.kind[prim], scene.x[prim], scene.y[prim], scene.cos_yaw[prim],
                              scene.sin_yaw[prim], scene.half_x[prim], scene.half_y[prim],
                              scene.radius[prim], px, py)
               for prim, px, py in zip([0, 0, 0, 1], hit_x, hit_y)]
    expected = [(nx * c - ny * s, nx * s + ny * c) for nx, ny in local_normals]
    expected.append((math.cos(2.0), math.sin(2.0)))
    np.testing.assert_allclose(normals, expected, atol=1e-12)


def test_faces_turned_towards_the_light_are_brighter():
    # Gazebo's default sun lies towards +x, so a face looking along +x is lit and
    # one looking along -x gets only ambient light.
    scene = Scene([Prim.box('crate', 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 1.0, color=(0.8, 0.8, 0.8))])
    cam = camera()
    lit = cam.render(scene, 2.0, 0.0, CAMERA_Z, math.pi)[HEIGHT // 2, WIDTH // 2]
    shaded = cam.render(scene, -2.0, 0.0, CAMERA_Z, 0.0)[HEIGHT // 2, WIDTH // 2]
    assert lit[0] > shaded[0] + 50
    # Shades come from a 256-level palette, so allow one grey level of rounding.
    assert abs(int(shaded[0]) - 0.8 * 255 * AMBIENT / (1 + FALLOFF_PER_METRE * 1.75)) <= 1
