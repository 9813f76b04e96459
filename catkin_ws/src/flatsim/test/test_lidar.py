import math

import numpy as np
import pytest

from flatsim.errors import FlatsimError
from flatsim.loading.config import LaserConfig
from flatsim.sensors.lidar import Lidar, beam_angles, scan_msg_fields
from flatsim.world.scene import Prim, Scene

# Inside faces of a walled room: x in [X_MIN, X_MAX], y in [Y_MIN, Y_MAX].
X_MIN, X_MAX, Y_MIN, Y_MAX = -2.0, 3.0, -1.5, 2.5
WALL = 0.2


def room(height=1.0):
    mid_x, mid_y = (X_MIN + X_MAX) / 2, (Y_MIN + Y_MAX) / 2
    span_x, span_y = X_MAX - X_MIN + 2 * WALL, Y_MAX - Y_MIN + 2 * WALL
    return [
        Prim.box('north', mid_x, Y_MAX + WALL / 2, 0.0, span_x, WALL, 0.0, height),
        Prim.box('south', mid_x, Y_MIN - WALL / 2, 0.0, span_x, WALL, 0.0, height),
        # A yawed box: east and west walls are x-long boxes turned a quarter turn.
        Prim.box('east', X_MAX + WALL / 2, mid_y, math.pi / 2, span_y, WALL, 0.0, height),
        Prim.box('west', X_MIN - WALL / 2, mid_y, -math.pi / 2, span_y, WALL, 0.0, height),
    ]


def room_distance(x, y, angle):
    """Distance from (x, y) inside the room to its walls along a world angle."""
    c, s = math.cos(angle), math.sin(angle)
    candidates = []
    if c > 1e-12:
        candidates.append((X_MAX - x) / c)
    if c < -1e-12:
        candidates.append((X_MIN - x) / c)
    if s > 1e-12:
        candidates.append((Y_MAX - y) / s)
    if s < -1e-12:
        candidates.append((Y_MIN - y) / s)
    return min(candidates)


def config(**overrides):
    values = dict(samples=360, min_angle=-math.pi, max_angle=math.pi * 179 / 180,
                  range_min=0.1, range_max=30.0)
    values.update(overrides)
    return LaserConfig(**values)


def test_room_ranges_equal_the_analytic_distances_without_noise():
    x, y, yaw = 0.3, 0.2, 0.4
    lidar = Lidar(config())
    ranges = lidar.scan(Scene(room()), x, y, 0.25, yaw)
    expected = [room_distance(x, y, yaw + a) for a in beam_angles(lidar.config)]
    assert ranges.dtype == np.float32
    np.testing.assert_allclose(ranges, expected, rtol=1e-6, atol=1e-5)


def test_noisy_room_ranges_stay_within_the_configured_noise():
    x, y, yaw = -0.5, 1.0, -2.0
    sigma = 0.01
    lidar = Lidar(config(samples=720, noise_stddev=sigma), seed=3)
    scene = Scene(room())
    expected = np.array([room_distance(x, y, yaw + a) for a in beam_angles(lidar.config)])
    residual = np.concatenate([lidar.scan(scene, x, y, 0.25, yaw) - expected for _ in range(5)])
    # 3600 draws: 3 sigma would be crossed about ten times by chance, 5 sigma practically never.
    assert np.abs(residual).max() < 5 * sigma
    assert np.mean(np.abs(residual) < 3 * sigma) > 0.99
    assert residual.std() == pytest.approx(sigma, rel=0.1)
    assert abs(residual.mean()) < sigma / 10


def test_noise_mean_shifts_the_ranges():
    lidar = Lidar(config(samples=1, min_angle=0.0, max_angle=0.0, noise_mean=0.05,
                         noise_stddev=0.001))
    ranges = np.array([lidar.scan(Scene(room()), 0.0, 0.0, 0.5, 0.0)[0] for _ in range(200)])
    assert ranges.mean() == pytest.approx(X_MAX + 0.05, abs=0.001)


def test_cylinder_ranges_follow_the_circle():
    centre_x, centre_y, radius = 2.0, 1.0, 0.25
    x, y = 0.0, 0.0
    lidar = Lidar(config(samples=181, min_angle=-0.2, max_angle=0.2))
    heading = math.atan2(centre_y - y, centre_x - x)
    ranges = lidar.scan(Scene([Prim.cylinder('post', centre_x, centre_y, radius, 0.0, 1.0)]),
                        x, y, 0.5, heading)
    distance = math.hypot(centre_x - x, centre_y - y)
    off_axis = distance * np.sin(beam_angles(lidar.config))
    chord = np.sqrt(np.maximum(radius ** 2 - off_axis ** 2, 0.0))
    expected = np.where(np.abs(off_axis) < radius,
                        distance * np.cos(beam_angles(lidar.config)) - chord, np.inf)
    assert np.isfinite(expected).sum() > 20 and np.isinf(expected).sum() > 20
    np.testing.assert_allclose(ranges, expected, rtol=1e-6)
    assert ranges[90] == pytest.approx(distance - radius, rel=1e-6)


def test_no_return_and_beyond_range_max_are_positive_infinity():
    lidar = Lidar(config(samples=3, min_angle=-math.pi / 2, max_angle=math.pi / 2,
                         range_max=5.0, noise_stddev=0.01))
    scene = Scene([Prim.box('far_ahead', 7.0, 0.0, 0.0, 1.0, 4.0, 0.0, 1.0),
                   Prim.box('near_left', 0.0, 3.0, 0.0, 4.0, 1.0, 0.0, 1.0)])
    ranges = lidar.scan(scene, 0.0, 0.0, 0.5, 0.0)
    assert ranges[0] == np.inf         # right: nothing there
    assert ranges[1] == np.inf         # ahead: the box is beyond range_max
    assert abs(ranges[2] - 2.5) < 0.05  # left: a normal return


def test_return_at_or_below_range_min_is_negative_infinity():
    lidar = Lidar(config(samples=1, min_angle=0.0, max_angle=0.0, range_min=0.5))
    scene = Scene([Prim.box('close', 0.4, 0.0, 0.0, 0.2, 1.0, 0.0, 1.0)])
    assert lidar.scan(scene, 0.0, 0.0, 0.5, 0.0)[0] == -np.inf


def test_noise_never_pushes_a_range_outside_the_limits():
    lidar = Lidar(config(samples=100, min_angle=-0.1, max_angle=0.1, range_min=0.1,
                         range_max=3.05, noise_stddev=0.5))
    ranges = lidar.scan(Scene(room()), 0.0, 0.0, 0.5, 0.0)
    assert ranges.min() >= 0.1 and ranges.max() <= 3.05
    assert (ranges == np.float32(3.05)).any()


def test_beam_count_and_angles():
    cfg = config(samples=5, min_angle=-1.0, max_angle=1.0)
    lidar = Lidar(cfg)
    np.testing.assert_allclose(lidar.angles, [-1.0, -0.5, 0.0, 0.5, 1.0])
    assert lidar.scan(Scene(room()), 0.0, 0.0, 0.5, 0.0).shape == (5,)
    fields = scan_msg_fields(cfg)
    assert fields == {'angle_min': -1.0, 'angle_max': 1.0, 'angle_increment': 0.5,
                      'range_min': 0.1, 'range_max': 30.0}
    # Beam 1 points 0.5 rad right of the sensor, which itself faces +y.
    ranges = lidar.scan(Scene(room()), 0.0, 0.0, 0.5, math.pi / 2)
    assert ranges[1] == pytest.approx(room_distance(0.0, 0.0, math.pi / 2 - 0.5), rel=1e-6)


def test_single_beam_points_at_min_angle():
    cfg = config(samples=1, min_angle=0.3, max_angle=0.9)
    np.testing.assert_allclose(Lidar(cfg).angles, [0.3])
    assert scan_msg_fields(cfg)['angle_increment'] == 0.0


def test_seeded_noise_is_repeatable():
    scene = Scene(room())
    first = Lidar(config(noise_stddev=0.01), seed=7)
    second = Lidar(config(noise_stddev=0.01), seed=7)
    other = Lidar(config(noise_stddev=0.01), seed=8)
    a = [first.scan(scene, 0.0, 0.0, 0.5, 0.0) for _ in range(3)]
    b = [second.scan(scene, 0.0, 0.0, 0.5, 0.0) for _ in range(3)]
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a[0], other.scan(scene, 0.0, 0.0, 0.5, 0.0))
    assert not np.array_equal(a[0], a[1])


def test_objects_above_or_below_the_sensor_height_are_not_seen():
    lidar = Lidar(config(samples=1, min_angle=0.0, max_angle=0.0))
    scene = Scene(room() + [
        Prim.box('table_top', 1.0, 0.0, 0.0, 0.5, 1.0, 0.7, 0.75),
        Prim.box('step', 1.5, 0.0, 0.0, 0.5, 1.0, 0.0, 0.2),
        Prim.box('glass', 2.0, 0.0, 0.0, 0.2, 1.0, 0.0, 1.0, collision=False),
    ])
    assert lidar.scan(scene, 0.0, 0.0, 0.5, 0.0)[0] == pytest.approx(X_MAX)
    assert lidar.scan(scene, 0.0, 0.0, 0.72, 0.0)[0] == pytest.approx(0.75)
    assert lidar.scan(scene, 0.0, 0.0, 0.1, 0.0)[0] == pytest.approx(1.25)


def test_sphere_is_cut_at_the_sensor_height():
    lidar = Lidar(config(samples=1, min_angle=0.0, max_angle=0.0))
    scene = Scene([Prim.sphere('ball', 2.0, 0.0, 0.5, 0.2)])
    assert lidar.scan(scene, 0.0, 0.0, 0.5, 0.0)[0] == pytest.approx(1.8)
    assert lidar.scan(scene, 0.0, 0.0, 0.62, 0.0)[0] == pytest.approx(2.0 - 0.16)
    assert lidar.scan(scene, 0.0, 0.0, 0.8, 0.0)[0] == np.inf


def test_own_shapes_and_enclosing_shapes_do_not_block_the_beams():
    lidar = Lidar(config(samples=1, min_angle=0.0, max_angle=0.0))
    scene = Scene(room())
    housing = scene.add(Prim.box('housing', 0.0, 0.0, 0.0, 0.3, 0.3, 0.0, 1.0))
    chassis = scene.add(Prim.box('chassis', 0.3, 0.0, 0.0, 0.2, 0.4, 0.0, 1.0))
    assert lidar.scan(scene, 0.0, 0.0, 0.5, 0.0)[0] == pytest.approx(0.2)
    assert lidar.scan(scene, 0.0, 0.0, 0.5, 0.0, exclude=[chassis])[0] == pytest.approx(X_MAX)
    scene.remove(chassis)
    assert lidar.scan(scene, 0.0, 0.0, 0.5, 0.0)[0] == pytest.approx(X_MAX)
    scene.set_pose(housing, 1.0, 0.0, 0.3)
    # A 0.3 m box turned 0.3 rad: the beam enters its face at 0.15 / cos(0.3) from its centre.
    assert lidar.scan(scene, 0.0, 0.0, 0.5, 0.0)[0] == pytest.approx(1.0 - 0.15 / math.cos(0.3))


@pytest.mark.parametrize('overrides', [dict(samples=0), dict(range_min=2.0, range_max=1.0),
                                       dict(range_max=math.inf), dict(noise_stddev=-1.0)])
def test_bad_configuration_raises(overrides):
    with pytest.raises(FlatsimError):
        Lidar(config(**overrides))
