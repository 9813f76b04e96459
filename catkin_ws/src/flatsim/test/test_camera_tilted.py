"""The camera pitched and rolled: horizon, faces seen from above and below, spheres, culling."""
import math

import numpy as np
import pytest

from flatsim.loading.config import CameraConfig
from flatsim.sensors.camera import PinholeCamera
from flatsim.sensors.raster import camera_axes
from flatsim.world.scene import DEFAULT_FLOOR_COLOR, DEFAULT_SKY_COLOR, Prim, Scene

WIDTH, HEIGHT, HFOV = 640, 480, 1.4
SKY = np.rint(np.array(DEFAULT_SKY_COLOR) * 255)
FLOOR = np.rint(np.array(DEFAULT_FLOOR_COLOR) * 255)


def camera(**overrides):
    values = dict(width=WIDTH, height=HEIGHT, hfov=HFOV, near=0.02, far=300.0)
    values.update(overrides)
    return PinholeCamera(CameraConfig(**values))


def is_floor(image):
    return (image == FLOOR).all(axis=2)


def project(cam, eye, roll, pitch, yaw, point):
    """Pixel (column, row) of a world point, as the pinhole model puts it."""
    forward, left, up = camera_axes(roll, pitch, yaw)
    rel = np.asarray(point, dtype=float) - eye
    depth = forward @ rel
    return cam.centre_u - cam.focal * (left @ rel) / depth, cam.centre_v - cam.focal * (up @ rel) / depth


@pytest.mark.parametrize('roll, pitch', [(0.0, 0.3), (0.0, -0.5), (0.2, 0.1), (-0.4, -0.2),
                                         (0.3, 1.0)])
def test_floor_ends_at_the_analytic_horizon_in_every_column(roll, pitch):
    cam = camera()
    image = cam.render(Scene([]), 0.0, 0.0, 1.2, 0.7, roll=roll, pitch=pitch)
    floor = is_floor(image)
    assert (floor | (image == SKY).all(axis=2)).all()
    forward, left, up = camera_axes(roll, pitch, 0.7)
    columns = np.arange(WIDTH)
    # The ray through (column, row) points down where f fz + (cu - column) lz + (cv - row) uz < 0.
    horizon = cam.centre_v + (cam.focal * forward[2] + (cam.centre_u - columns) * left[2]) / up[2]
    expected = np.clip(np.floor(horizon) + 1, 0, HEIGHT)   # first row below the line
    first_floor = np.where(floor.any(axis=0), floor.argmax(axis=0), HEIGHT)
    assert np.abs(first_floor - expected).max() <= 1
    # Below the horizon it is floor all the way down.
    assert all(floor[row:, column].all() for column, row in enumerate(first_floor) if row < HEIGHT)


def test_looking_straight_up_sees_uniform_sky():
    scene = Scene([Prim.box('counter', 0.0, 2.5, 0.0, 3.0, 0.8, 0.0, 1.0, color=(0.6, 0.4, 0.2))])
    image = camera().render(scene, 0.0, 0.0, 1.2, 0.0, pitch=-math.pi / 2)
    assert (image == SKY).all()


def test_nearly_level_camera_matches_the_column_renderer():
    scene = Scene([Prim.box('wall', 3.0, 0.0, 0.3, 0.2, 4.0, 0.0, 1.5, color=(0.8, 0.2, 0.2)),
                   Prim.box('shelf', 2.0, -1.0, 0.0, 0.5, 0.5, 0.8, 0.9, color=(0.2, 0.2, 0.8)),
                   Prim.cylinder('post', 2.0, 1.0, 0.2, 0.0, 1.0, color=(0.2, 0.8, 0.2)),
                   # Straight ahead, where the level camera's disc is the exact outline.
                   Prim.sphere('ball', 1.5, 0.0, 0.5, 0.1, unlit_white=True)])
    cam = camera()
    level = cam.render(scene, 0.0, 0.0, 0.5, 0.0)
    tilted = cam.render(scene, 0.0, 0.0, 0.5, 0.0, pitch=1e-6)
    same = (level == tilted).all(axis=2)
    # Outlines may differ by a pixel (a cylinder is a 32-sided prism here).
    assert same.mean() > 0.99
    assert (tilted == 255).all(axis=2).sum() == pytest.approx((level == 255).all(axis=2).sum(), rel=0.05)


def test_box_seen_from_above_shows_its_top_face_inside_its_projected_corners():
    box = Prim.box('block', 2.0, 0.0, 0.4, 0.6, 0.4, 0.0, 0.5, color=(0.9, 0.1, 0.1))
    cam = camera()
    eye, pitch, yaw = np.array([0.0, 0.0, 2.0]), 0.7, 0.0
    image = cam.render(Scene([box]), *eye, yaw, pitch=pitch)
    red = (image[..., 0] > 100) & (image[..., 1] < 60)
    corners = [(2.0 + math.cos(0.4) * sx * 0.3 - math.sin(0.4) * sy * 0.2,
                math.sin(0.4) * sx * 0.3 + math.cos(0.4) * sy * 0.2, 0.5)
               for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    pixels = np.array([project(cam, eye, 0.0, pitch, yaw, corner) for corner in corners])
    centre = pixels.mean(axis=0)
    assert red[int(round(centre[1])), int(round(centre[0]))]
    # The top face's shade is the sun from above: ambient plus diffuse times its z part.
    top = image[int(round(centre[1])), int(round(centre[0]))]
    side_of_level_camera = camera().render(Scene([box]), 0.0, 0.0, 0.25, 0.0)[HEIGHT // 2, WIDTH // 2]
    assert top[0] > side_of_level_camera[0]
    # Nothing red outside the box's projected outline (top corners and bottom corners).
    bottoms = [(x, y, 0.0) for x, y, _ in corners]
    outline = np.vstack([pixels, [project(cam, eye, 0.0, pitch, yaw, c) for c in bottoms]])
    rows, columns = np.nonzero(red)
    assert columns.min() >= outline[:, 0].min() - 1 and columns.max() <= outline[:, 0].max() + 1
    assert rows.min() >= outline[:, 1].min() - 1 and rows.max() <= outline[:, 1].max() + 1


def test_ball_below_a_pitched_camera_is_a_white_disc_at_its_projection():
    ball = (1.5, 0.3, 0.1)
    scene = Scene([Prim.sphere('ball', *ball, 0.1, unlit_white=True)])
    cam = camera()
    eye, roll, pitch, yaw = np.array([0.0, 0.0, 1.5]), 0.3, 0.6, 0.1
    image = cam.render(scene, *eye, yaw, roll=roll, pitch=pitch)
    rows, columns = np.nonzero((image == 255).all(axis=2))
    column, row = project(cam, eye, roll, pitch, yaw, ball)
    assert columns.mean() == pytest.approx(column, abs=1.5)
    assert rows.mean() == pytest.approx(row, abs=1.5)
    distance = np.linalg.norm(np.asarray(ball) - eye)
    disc_radius = cam.focal * 0.1 / math.sqrt(distance ** 2 - 0.1 ** 2)
    assert len(rows) == pytest.approx(math.pi * disc_radius ** 2, rel=0.25)


def test_looking_up_at_a_floating_shelf_shows_its_underside():
    shelf = Prim.box('shelf', 1.0, 0.0, 0.0, 1.0, 1.0, 1.5, 1.6, color=(0.1, 0.1, 0.9))
    image = camera().render(Scene([shelf]), 0.0, 0.0, 1.0, 0.0, pitch=-0.6)
    blue = (image[..., 2] > 20) & (image[..., 0] < 20)
    assert blue[HEIGHT // 2, WIDTH // 2]
    # Sky shows around it: only the shelf blocks the view.
    assert (image == SKY).all(axis=2).sum() > WIDTH * HEIGHT // 4


def test_geometry_below_the_floor_is_hidden_and_behind_the_camera_is_not_drawn():
    sunk = Prim.box('sunk', 2.0, 0.0, 0.0, 1.0, 1.0, -1.0, -0.1, color=(0.9, 0.1, 0.1))
    behind = Prim.box('behind', -2.0, 0.0, 0.0, 1.0, 1.0, 0.0, 3.0, color=(0.1, 0.9, 0.1))
    image = camera().render(Scene([sunk, behind]), 0.0, 0.0, 1.0, 0.0, pitch=0.5)
    assert (is_floor(image) | (image == SKY).all(axis=2)).all()


def test_a_wall_crossing_the_near_plane_is_clipped_not_lost():
    wall = Prim.box('wall', 0.0, 0.0, 0.0, 6.0, 0.1, 0.0, 2.0, color=(0.2, 0.7, 0.2))
    image = camera().render(Scene([wall]), 0.0, -0.5, 1.0, math.pi / 2 + 0.6, pitch=0.3)
    green = (image[..., 1] > image[..., 0] + 30)
    assert green.mean() > 0.2
