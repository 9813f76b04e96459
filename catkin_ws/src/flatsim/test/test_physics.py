"""Physics: driven robots follow the unicycle model, obey the torque limit and stop at walls."""
import math

import numpy as np
import pytest

from flatsim.errors import FlatsimError
from flatsim.loading.config import DriveConfig
from flatsim.pose import Pose
from flatsim.world.drive import InvalidCommand, make_drive
from flatsim.world.physics import Physics

STEP = 0.002
HALF_LENGTH, HALF_WIDTH = 0.2, 0.15
FOOTPRINT = [(-HALF_LENGTH, -HALF_WIDTH), (HALF_LENGTH, -HALF_WIDTH),
             (HALF_LENGTH, HALF_WIDTH), (-HALF_LENGTH, HALF_WIDTH)]
MASS = 15.0
# Wheels strong enough that reaching the commanded speed takes a few milliseconds.
STRONG = dict(update_rate=0.0, wheel_torque=100.0, wheel_diameter=0.2, wheel_separation=0.4)


def robot_world(x=0.0, y=0.0, yaw=0.0, **drive_settings):
    physics = Physics(step=STEP)
    drive = make_drive(DriveConfig(**drive_settings))
    robot = physics.add_robot('robot', FOOTPRINT, MASS, x, y, yaw, drive)
    return physics, robot, drive


def run(physics, seconds):
    for _ in range(round(seconds / STEP)):
        physics.step()


def unicycle(linear, angular, seconds):
    if angular == 0.0:
        return linear * seconds, 0.0, 0.0
    radius = linear / angular
    heading = angular * seconds
    return radius * math.sin(heading), radius * (1.0 - math.cos(heading)), heading


def angle_difference(a, b):
    return math.atan2(math.sin(a - b), math.cos(a - b))


@pytest.mark.parametrize('linear, angular', [(0.5, 0.0), (0.5, 0.4), (-0.3, -0.8), (0.0, 1.0)],
                         ids=['straight', 'arc', 'reverse-arc', 'spin'])
def test_held_command_follows_the_unicycle_within_one_percent(linear, angular):
    physics, robot, drive = robot_world(**STRONG)
    drive.set_command(linear, angular)
    run(physics, 5.0)
    x, y, yaw = physics.pose(robot)
    expected_x, expected_y, expected_yaw = unicycle(linear, angular, 5.0)
    assert math.hypot(x - expected_x, y - expected_y) <= 0.01 * abs(linear) * 5.0 + 1e-9
    assert abs(angle_difference(yaw, expected_yaw)) <= 0.01 * max(abs(angular) * 5.0, 0.1)
    # pymunk moves along the chord of each step's arc, so the body sees a sideways
    # velocity of about v * w * step / 2.
    assert physics.body_twist(robot) == pytest.approx((linear, 0.0, angular), abs=1e-3)


def test_unicycle_from_a_turned_start_pose():
    physics, robot, drive = robot_world(x=1.0, y=-2.0, yaw=math.pi / 2, **STRONG)
    drive.set_command(0.4, 0.0)
    run(physics, 5.0)
    x, y, yaw = physics.pose(robot)
    assert (x, y) == pytest.approx((1.0, 0.0), abs=0.02)
    assert yaw == pytest.approx(math.pi / 2, abs=1e-6)


def test_speed_ramps_at_wheel_acceleration_then_saturates():
    physics, robot, drive = robot_world(wheel_acceleration=2.0, update_rate=0.0)
    drive.set_command(1.0, 0.0)
    speeds = []
    for _ in range(400):
        physics.step()
        speeds.append(physics.body_twist(robot)[0])
    times = STEP * np.arange(1, 401)
    ramp = times < 0.45
    assert np.allclose(np.array(speeds)[ramp], 2.0 * times[ramp], atol=0.01)
    assert speeds[-1] == pytest.approx(1.0, abs=1e-6)


def test_speed_ramp_at_plugin_update_rate():
    physics, robot, drive = robot_world(wheel_acceleration=2.0, update_rate=100.0)
    drive.set_command(1.0, 0.0)
    for step in range(1, 401):
        physics.step()
        if step % 25 == 0:
            # Targets change every 10 ms, so the speed trails the ramp by at most one period.
            expected = min(2.0 * step * STEP, 1.0)
            assert expected - 0.021 <= physics.body_twist(robot)[0] <= expected + 1e-9


def test_torque_limit_bounds_acceleration():
    torque, radius = 0.5, 0.1
    physics, robot, drive = robot_world(update_rate=0.0, wheel_torque=torque, wheel_diameter=2 * radius)
    drive.set_command(1.0, 0.0)
    acceleration = 2 * torque / radius / MASS  # two wheels at the torque limit
    run(physics, 0.5)
    assert physics.body_twist(robot)[0] == pytest.approx(acceleration * 0.5, rel=0.01)
    run(physics, 2.0)
    assert physics.body_twist(robot)[0] == pytest.approx(1.0, abs=1e-6)


def test_torque_limit_bounds_turning():
    physics, robot, drive = robot_world(update_rate=0.0, wheel_torque=0.05, wheel_diameter=0.2,
                                        wheel_separation=0.4)
    drive.set_command(0.0, 3.0)
    run(physics, 0.2)
    angular_acceleration = drive.max_torque / robot.body.moment
    assert physics.twist(robot)[2] == pytest.approx(angular_acceleration * 0.2, rel=0.01)


def test_huge_command_is_bounded_by_the_torque_limit():
    physics, robot, drive = robot_world(update_rate=0.0)
    drive.set_command(1e300, 1e300)
    run(physics, 1.0)
    vx, vy, wz = physics.twist(robot)
    assert all(math.isfinite(v) for v in (*physics.pose(robot), vx, vy, wz))
    assert math.hypot(vx, vy) <= drive.max_force / MASS * 1.0 + 1e-6
    assert abs(wz) <= drive.max_torque / robot.body.moment * 1.0 + 1e-6


def test_invalid_command_leaves_the_motion_unchanged():
    reference, reference_robot, reference_drive = robot_world(**STRONG)
    physics, robot, drive = robot_world(**STRONG)
    for world_drive in (reference_drive, drive):
        world_drive.set_command(0.3, 0.2)
    run(reference, 0.5)
    run(physics, 0.25)
    with pytest.raises(InvalidCommand):
        drive.set_command(math.nan, math.inf)
    run(physics, 0.25)
    assert physics.pose(robot) == pytest.approx(reference.pose(reference_robot), abs=1e-12)


@pytest.mark.parametrize('approach_yaw', [0.0, 0.4])
def test_fast_robot_stops_at_a_thin_wall(approach_yaw):
    physics, robot, drive = robot_world(update_rate=0.0)
    wall_x, half_thickness = 2.0, 0.025
    physics.add_static_box(wall_x, 0.0, 0.0, half_thickness, 3.0)
    physics.set_pose(robot, 0.0, 0.0, approach_yaw)
    drive.set_command(2.0, 0.0)
    frontmost = -math.inf
    for _ in range(2000):
        physics.step()
        corners = robot.shapes[0].get_vertices()
        frontmost = max(frontmost, max(robot.body.local_to_world(c).x for c in corners))
    assert frontmost < wall_x
    assert frontmost < wall_x - half_thickness + 0.01
    # Pressed against the wall and no longer moving forward.
    assert frontmost > wall_x - half_thickness - 0.01
    assert physics.twist(robot)[0] == pytest.approx(0.0, abs=0.01)


def test_robot_pushes_the_ball_which_rolls_to_rest():
    physics, robot, drive = robot_world(update_rate=0.0)
    ball = physics.add_ball('ball', 0.5, 0.0, 0.1, 0.5)
    drive.set_command(0.8, 0.0)
    run(physics, 1.0)
    ball_x, _, _ = physics.pose(ball)
    assert ball_x > 0.75
    drive.set_command(0.0, 0.0)
    run(physics, 0.5)
    robot_stop_x = physics.pose(robot)[0]
    assert physics.twist(ball)[0] > 0.3  # coasting on after the robot stopped
    run(physics, 8.0)
    ball_x, ball_y, _ = physics.pose(ball)
    assert physics.twist(ball) == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    gap = ball_x - robot_stop_x
    assert 0.4 < gap < 4.0
    assert abs(ball_y) < 0.05


def test_ball_bounces_a_little_off_a_wall():
    physics = Physics(step=STEP)
    physics.add_static_box(1.0, 0.0, 0.0, 0.05, 2.0)
    ball = physics.add_ball('ball', 0.0, 0.0, 0.1, 0.5)
    physics.set_twist(ball, 1.0, 0.0, 0.0)
    speeds = []
    for _ in range(1000):
        physics.step()
        speeds.append(physics.twist(ball)[0])
    rebound = min(speeds)
    assert -0.7 < rebound < -0.1
    assert physics.pose(ball)[0] < 0.85


def test_encoder_odometry_matches_ground_truth_on_a_straight_run():
    physics, robot, drive = robot_world(odometry_source='encoder', update_rate=100.0)
    drive.set_command(0.5, 0.0)
    run(physics, 4.0)
    x, y, yaw = physics.pose(robot)
    pose, twist = drive.odometry(Pose(x, y, 0.0, 0.0, 0.0, yaw), physics.twist(robot))
    assert x > 1.8
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((x, y, yaw), abs=0.002)
    assert twist == pytest.approx((0.5, 0.0, 0.0), abs=1e-6)


def test_skid_steer_drives_straight_and_turns():
    settings = dict(plugin='skid_steer', update_rate=100.0, wheel_separation=0.4, wheel_diameter=0.2,
                    wheel_torque=20.0, left_joints=['lf', 'lr'], right_joints=['rf', 'rr'])
    physics, robot, drive = robot_world(**settings)
    drive.set_command(0.5, 0.0)
    run(physics, 2.0)
    x, y, yaw = physics.pose(robot)
    assert x == pytest.approx(1.0, abs=0.02) and y == pytest.approx(0.0, abs=1e-9)
    drive.set_command(0.0, 1.0)
    run(physics, 1.0)
    assert physics.pose(robot)[2] == pytest.approx(1.0, abs=0.02)
    assert physics.pose(robot)[0] == pytest.approx(x, abs=0.01)


def test_undriven_robot_brakes_to_a_stop():
    physics = Physics(step=STEP)
    robot = physics.add_robot('cart', FOOTPRINT, MASS, 0.0, 0.0, 0.0, None)
    physics.set_twist(robot, 1.0, 0.0, 0.0)
    run(physics, 1.0)
    assert physics.twist(robot) == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert 0.0 < physics.pose(robot)[0] < 0.2


def test_ten_thousand_static_boxes():
    physics = Physics(step=STEP)
    rng = np.random.default_rng(1)
    centres = rng.uniform(-50.0, 50.0, size=(10000, 2))
    centres = centres[np.hypot(*centres.T) > 3.0]  # keep the middle clear
    for (x, y), yaw in zip(centres, rng.uniform(0.0, math.pi, len(centres))):
        physics.add_static_box(x, y, yaw, 0.1, 0.2)
    drive = make_drive(DriveConfig(**STRONG))
    robot = physics.add_robot('robot', FOOTPRINT, MASS, 0.0, 0.0, 0.0, drive)
    assert physics.static_count() == len(centres)
    assert len(physics.space.shapes) == len(centres) + 1
    drive.set_command(0.5, 0.5)
    run(physics, 2.0)
    x, y, yaw = physics.pose(robot)
    expected_x, expected_y, expected_yaw = unicycle(0.5, 0.5, 2.0)
    assert math.hypot(x - expected_x, y - expected_y) < 0.01
    assert yaw == pytest.approx(expected_yaw, abs=0.01)


def test_model_bookkeeping():
    physics, robot, _ = robot_world()
    ball = physics.add_ball('ball', 1.0, 1.0, 0.1, 0.5)
    assert physics.bodies() == [robot, ball]
    assert physics.handle('ball') is ball
    with pytest.raises(FlatsimError):
        physics.add_ball('ball', 0.0, 2.0, 0.1, 0.5)
    physics.set_pose(ball, 3.0, -1.0, 4.0)
    assert physics.pose(ball) == pytest.approx((3.0, -1.0, 4.0 - 2 * math.pi))
    physics.set_twist(ball, 0.1, 0.2, 0.3)
    assert physics.twist(ball) == pytest.approx((0.1, 0.2, 0.3))
    physics.remove(ball)
    assert physics.bodies() == [robot]
    assert set(physics.space.bodies) == {robot.body, robot.control}
    with pytest.raises(FlatsimError):
        physics.handle('ball')


def test_sensor_filter_leaves_out_the_robots_own_shape():
    physics, robot, _ = robot_world()
    physics.add_static_box(2.0, 0.0, 0.0, 0.05, 1.0)
    hit = physics.space.segment_query_first((0.0, 0.0), (5.0, 0.0), 0.0, robot.shape_filter)
    assert hit.shape.body is physics.space.static_body
    assert hit.point.x == pytest.approx(1.95)


@pytest.mark.parametrize('call', [
    lambda p: p.add_static_box(math.nan, 0.0, 0.0, 1.0, 1.0),
    lambda p: p.add_static_box(0.0, 0.0, 0.0, 0.0, 1.0),
    lambda p: p.add_static_circle(0.0, 0.0, -1.0),
    lambda p: p.add_ball('b', 0.0, 0.0, 0.1, 0.0),
    lambda p: p.add_robot('r', [(0, 0), (1, 0), (2, 0)], 1.0, 0.0, 0.0, 0.0),
    lambda p: p.add_robot('r', [(0, 0), (1, 0)], 1.0, 0.0, 0.0, 0.0),
    lambda p: p.add_robot('r', FOOTPRINT, 1.0, 0.0, math.inf, 0.0),
    lambda p: Physics(step=0.0),
])
def test_bad_input_raises_flatsim_error(call):
    with pytest.raises(FlatsimError):
        call(Physics(step=STEP))


# Bounds: what no course world needs is refused, and what a step produces beyond it slowed.

def test_requests_beyond_flatsims_bounds_are_refused():
    physics = Physics(step=STEP)
    ball = physics.add_ball('ball', 0.0, 0.0, 0.1, 0.5)
    for twist in [(1e308, 0.0, 0.0), (60.0, 90.0, 0.0), (0.0, 0.0, 1e4)]:
        with pytest.raises(FlatsimError, match='beyond the 100 m/s and 1000 rad/s'):
            physics.set_twist(ball, *twist)
    with pytest.raises(FlatsimError, match='beyond the 100000 m from the origin'):
        physics.set_pose(ball, 2e5, 0.0, 0.0)
    with pytest.raises(FlatsimError, match='below the 0.0001 m flatsim simulates'):
        physics.add_ball('dust', 0.0, 0.0, 1e-300, 1.0)


@pytest.mark.parametrize('mass', [1.3407807929942597e+154, 1e-320])
def test_a_mass_no_step_could_hold_is_refused(mass):
    # A fuzzed URDF's chassis of 1.3e154 kg loaded, then diverged at the first step.
    physics = Physics(step=STEP)
    with pytest.raises(FlatsimError, match='outside the 1e-09 to 1e\\+09 kg flatsim simulates'):
        physics.add_robot('heavy', FOOTPRINT, mass, 0.0, 0.0, 0.0)
    with pytest.raises(FlatsimError, match='outside the 1e-09 to 1e\\+09 kg'):
        physics.add_ball('heavy_ball', 0.0, 0.0, 0.1, mass)


def test_a_body_pushed_past_the_speed_bound_is_slowed_and_named():
    physics = Physics(step=STEP)
    ball = physics.add_ball('ball', 0.0, 0.0, 0.1, 0.5)
    for _ in range(10):
        physics.apply_force(ball, (1e9, 0.0), (0.0, 0.0), 1e9)
        physics.step()
    vx, vy, wz = physics.twist(ball)
    assert math.hypot(vx, vy) == pytest.approx(100.0) and wz == pytest.approx(1000.0)
    assert physics.slowed == {'ball'}


def test_a_restarted_body_forgets_its_non_finite_state():
    physics = Physics(step=STEP)
    ball = physics.add_ball('ball', 0.0, 0.0, 0.1, 0.5)
    physics.add_static_box(0.15, 0.0, 0.0, 0.1, 1.0)   # in contact, so pymunk caches an arbiter
    physics.step()
    ball.body.velocity = (math.nan, 0.0)
    with pytest.raises(FlatsimError, match='physics diverged'):
        physics.step()
    physics.restart(ball, -1.0, 0.0, 0.0)
    for _ in range(10):
        physics.step()
    assert physics.pose(ball) == pytest.approx((-1.0, 0.0, 0.0))
