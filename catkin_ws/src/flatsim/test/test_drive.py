"""Drive plugin kinematics against gazebo_ros's diff drive and skid steer arithmetic.

These drive the plugin with an ideal body that always moves at the target the
plugin sets, so only the plugin's own behaviour is under test.
"""
import math

import pytest

from flatsim.errors import FlatsimError
from flatsim.loading.config import DriveConfig
from flatsim.pose import Pose
from flatsim.world.drive import DiffDrive, InvalidCommand, SkidSteerDrive, make_drive

STEP = 0.002


def update(drive, linear, angular):
    """One step with the body moving at (linear, angular); returns the target (linear, angular)."""
    target_x, target_y, target_angular = drive.update(STEP, linear, 0.0, angular)
    assert target_y == pytest.approx(0.0, abs=1e-9)
    return target_x, target_angular


def run_ideal(drive, seconds, start=(0.0, 0.0)):
    """Step the drive with the body twist equal to last step's target; return the last target."""
    target = start
    for _ in range(round(seconds / STEP)):
        target = update(drive, *target)
    return target


def diff_drive(**overrides):
    settings = dict(update_rate=0.0, wheel_separation=0.4, wheel_diameter=0.2)
    settings.update(overrides)
    return make_drive(DriveConfig(**settings))


def test_wheel_speeds_follow_separation():
    drive = diff_drive()
    drive.set_command(0.5, 1.0)
    linear, angular = update(drive, 0.0, 0.0)
    assert drive.wheel_targets == pytest.approx((0.3, 0.7))
    assert (linear, angular) == pytest.approx((0.5, 1.0))


def test_update_rate_holds_targets_between_updates():
    drive = diff_drive(update_rate=10.0)
    drive.set_command(1.0, 0.0)
    outputs = [update(drive, 0.0, 0.0)[0] for _ in range(60)]
    # The plugin acts once more than a period (0.1 s) has passed: at the 51st step (0.102 s).
    assert outputs[49] == 0.0
    assert outputs[50] == pytest.approx(1.0)
    drive.set_command(2.0, 0.0)  # at 0.12 s: waits for the next update, at 0.202 s
    outputs = [update(drive, 1.0, 0.0)[0] for _ in range(40)]
    assert outputs[-1] == pytest.approx(1.0)
    assert update(drive, 1.0, 0.0)[0] == pytest.approx(2.0)


def test_publish_due_once_per_period():
    drive = diff_drive(update_rate=50.0)
    due = [update(drive, 0.0, 0.0) and drive.publish_due for _ in range(1000)]
    # Updates at 0.022 s, 0.042 s, ... as in gazebo: 99 of them in 2 s.
    assert sum(due) == 99
    assert due[10] and not due[9] and due[20]


def test_last_command_persists():
    drive = diff_drive(update_rate=100.0)
    drive.set_command(0.3, -0.2)
    assert run_ideal(drive, 30.0) == pytest.approx((0.3, -0.2))


@pytest.mark.parametrize('command', [
    (math.nan, 0.0), (0.0, math.nan), (math.inf, 0.0), (0.0, -math.inf), ('nan', 1.0), (None, 0.0)])
def test_non_finite_command_rejected_and_state_kept(command):
    drive = diff_drive()
    drive.set_command(0.4, 0.1)
    run_ideal(drive, 0.1)
    with pytest.raises(InvalidCommand):
        drive.set_command(*command)
    assert (drive.linear_command, drive.angular_command) == (0.4, 0.1)
    assert run_ideal(drive, 0.1, start=(0.4, 0.1)) == pytest.approx((0.4, 0.1))


def test_invalid_command_is_a_flatsim_error():
    assert issubclass(InvalidCommand, FlatsimError)


@pytest.mark.parametrize('acceleration', [0.0, 1.0])
def test_huge_command_stays_finite(acceleration):
    drive = diff_drive(wheel_acceleration=acceleration)
    drive.set_command(-1e308, -1e308)
    assert all(math.isfinite(v) for v in run_ideal(drive, 0.1))
    drive.reset()
    drive.set_command(0.0, 1.7e308)
    linear, angular = run_ideal(drive, 1.0)
    assert all(math.isfinite(v) for v in (linear, angular, *drive.wheel_targets))
    assert angular > 0.0
    if acceleration:
        # Each wheel ramped for 1 s at 1 m/s^2: -1 and +1 m/s.
        assert drive.wheel_targets == pytest.approx((-1.0, 1.0))


def test_ramp_rises_at_wheel_acceleration_then_holds():
    drive = diff_drive(wheel_acceleration=2.0)
    drive.set_command(1.0, 0.0)
    assert run_ideal(drive, 0.2)[0] == pytest.approx(0.4, abs=1e-9)
    assert run_ideal(drive, 0.2, start=(0.4, 0.0))[0] == pytest.approx(0.8, abs=1e-9)
    assert run_ideal(drive, 1.0, start=(0.8, 0.0))[0] == pytest.approx(1.0)


def test_ramp_down_is_limited_too():
    drive = diff_drive(wheel_acceleration=2.0)
    drive.set_command(1.0, 0.0)
    run_ideal(drive, 1.0)
    drive.set_command(-1.0, 0.0)
    assert run_ideal(drive, 0.25, start=(1.0, 0.0))[0] == pytest.approx(0.5, abs=1e-9)


def test_ramp_skipped_when_one_wheel_is_already_at_target():
    # gazebo_ros_diff_drive sets both wheels straight to target once either is within 1 cm/s.
    drive = diff_drive(wheel_acceleration=0.1)
    drive.set_command(0.2, 1.0)  # left wheel target 0.0 equals its current speed
    assert update(drive, 0.0, 0.0) == pytest.approx((0.2, 1.0))


def test_ramp_steps_at_update_rate():
    drive = diff_drive(wheel_acceleration=1.0, update_rate=10.0)
    drive.set_command(1.0, 0.0)
    # Updates at 0.102 s and 0.202 s, each ramping by the time since the last one.
    assert run_ideal(drive, 0.2)[0] == pytest.approx(0.102)
    assert run_ideal(drive, 0.004, start=(0.102, 0.0))[0] == pytest.approx(0.202)


def test_encoder_odometry_integrates_an_arc():
    drive = diff_drive(odometry_source='encoder')
    linear, angular, seconds = 0.5, 0.4, 5.0
    for _ in range(round(seconds / STEP)):
        update(drive, linear, angular)
    pose, twist = drive.odometry(Pose(9.0, 9.0, 0.0, 0.0, 0.0, 1.0), (0.0, 0.0, 0.0))
    radius = linear / angular
    heading = angular * seconds
    assert pose.x == pytest.approx(radius * math.sin(heading), abs=1e-6)
    assert pose.y == pytest.approx(radius * (1.0 - math.cos(heading)), abs=1e-6)
    assert pose.yaw == pytest.approx(heading, abs=1e-9)
    assert twist == pytest.approx((linear, 0.0, angular), abs=1e-6)


def test_encoder_twist_is_negative_when_reversing():
    drive = diff_drive(odometry_source='encoder')
    for _ in range(10):
        update(drive, -0.3, 0.0)
    pose, twist = drive.odometry(Pose(), (0.0, 0.0, 0.0))
    assert pose.x == pytest.approx(-0.3 * 10 * STEP)
    assert twist[0] == pytest.approx(-0.3)


def test_world_odometry_twist_is_in_the_base_frame():
    drive = diff_drive()
    world_pose = Pose(1.0, 2.0, 0.0, 0.0, 0.0, math.pi / 2)
    pose, twist = drive.odometry(world_pose, (0.0, 1.0, 0.2))
    assert pose == world_pose
    assert twist == pytest.approx((1.0, 0.0, 0.2))


def test_wheel_joints_turn_with_the_body():
    drive = diff_drive(left_joints=['left'], right_joints=['right'])
    for _ in range(500):
        update(drive, 0.2, 1.0)
    names, positions, velocities = drive.wheel_states()
    assert names == ['left', 'right']
    # Rim speeds 0.0 and 0.4 m/s on 0.1 m wheels, for 1 s.
    assert positions == pytest.approx([0.0, 4.0])
    assert velocities == pytest.approx([0.0, 4.0])


def test_reset_clears_command_and_odometry():
    drive = diff_drive(odometry_source='encoder')
    drive.set_command(1.0, 0.0)
    run_ideal(drive, 1.0)
    drive.reset()
    pose, _ = drive.odometry(Pose(5.0, 5.0, 0.0), (0.0, 0.0, 0.0))
    assert (pose.x, pose.y, pose.yaw) == (0.0, 0.0, 0.0)
    assert update(drive, 0.0, 0.0) == pytest.approx((0.0, 0.0))


def test_force_limits_from_wheel_torque():
    drive = diff_drive(wheel_torque=5.0)
    assert drive.max_force == pytest.approx(2 * 5.0 / 0.1)
    assert drive.max_torque == pytest.approx(2 * 5.0 / 0.1 * 0.2)


def skid_steer(**overrides):
    settings = dict(plugin='skid_steer', update_rate=0.0, wheel_separation=0.4, wheel_diameter=0.2,
                    left_joints=['lf', 'lr'], right_joints=['rf', 'rr'])
    settings.update(overrides)
    return make_drive(DriveConfig(**settings))


def test_skid_steer_has_four_wheels_no_ramp_and_world_odometry():
    drive = skid_steer(wheel_acceleration=0.5, odometry_source='encoder')
    assert isinstance(drive, SkidSteerDrive) and not isinstance(drive, DiffDrive)
    assert drive.max_force == pytest.approx(4 * 5.0 / 0.1)
    drive.set_command(1.0, 0.5)
    assert update(drive, 0.0, 0.0) == pytest.approx((1.0, 0.5))
    names, _, _ = drive.wheel_states()
    assert names == ['lf', 'lr', 'rf', 'rr']
    pose, twist = drive.odometry(Pose(3.0, 0.0, 0.0), (1.0, 0.0, 0.0))
    assert pose.x == 3.0 and twist == pytest.approx((1.0, 0.0, 0.0))


@pytest.mark.parametrize('overrides', [
    dict(wheel_separation=0.0), dict(wheel_diameter=-0.1), dict(wheel_torque=math.nan),
    dict(wheel_acceleration=-1.0), dict(update_rate='fast'), dict(odometry_source='gps'),
    dict(plugin='tracked')])
def test_bad_config_raises(overrides):
    with pytest.raises(FlatsimError):
        diff_drive(**overrides)
