"""Drive plugins move the robot from where its wheel joints are, as in Gazebo.

The plugins set speeds on the joints they name; the motion comes from where
the URDF (after xacro) puts those joints and how their axes point, not from
their names. The fixture robot drive_bot.urdf.xacro has its wheels 0.3 m apart
with radius 0.1 m; its arguments make the usual mistakes.
"""
import math
import pathlib
import re

import pytest

from flatsim.errors import Adjusted
from flatsim.inspect_cli import describe
from flatsim.loading.config import Wheel
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.studio.world import skipped_items
from flatsim.world.drive import joint_rates, twist_matrix
from flatsim.world.sim import Simulation

DRIVE_BOT = pathlib.Path(__file__).resolve().parent / 'fixtures' / 'robots' / 'drive_bot.urdf.xacro'


def load(**args):
    return load_robot(expand_xacro(DRIVE_BOT, {k: str(v) for k, v in args.items()}), name='drive_bot')


def drive_for(spec, seconds, linear=0.0, angular=0.0, sideways=0.0):
    """Spawn the robot at the origin, hold a command for `seconds`; return its pose and the sim."""
    sim = Simulation()
    robot = sim.spawn_robot('drive_bot', spec, Pose())
    robot.drive.set_command(linear, angular, sideways)
    for _ in range(round(seconds / sim.step_size)):
        sim.step()
    return sim.model_pose('drive_bot'), sim


def skipped_text(spec):
    return [str(item) for item in spec.skipped]


# -- the kinematics, without a robot file ------------------------------------------------

def test_two_wheels_on_one_axle_give_the_textbook_diff_drive():
    left, right = Wheel('l', 0.0, 0.2, 0.1, 0.0, 0.1), Wheel('r', 0.0, -0.2, 0.1, 0.0, 0.1)
    matrix = twist_matrix([left, right])
    # Rim speeds 0.3 and 0.7 m/s: forward 0.5 m/s, turning (0.7 - 0.3) / 0.4 = 1 rad/s.
    assert matrix @ [3.0, 7.0] == pytest.approx([0.5, 0.0, 1.0])


def test_an_axle_ahead_of_the_base_swings_the_base_sideways():
    # Wheels 0.1 m ahead of the base origin: turning on the spot about the axle's middle,
    # the base origin (behind it) moves towards the outside of the turn.
    left, right = Wheel('l', 0.1, 0.2, 0.1, 0.0, 0.1), Wheel('r', 0.1, -0.2, 0.1, 0.0, 0.1)
    vx, vy, wz = twist_matrix([left, right]) @ [-2.0, 2.0]
    assert (vx, wz) == pytest.approx((0.0, 1.0))
    assert vy == pytest.approx(-0.1 * wz)


def test_joint_rates_are_what_the_wheels_roll_at():
    left, right = Wheel('l', 0.0, 0.2, 0.1, 0.0, 0.1), Wheel('r', 0.0, -0.2, -0.1, 0.0, 0.1)
    # The right wheel's axis points the other way (-y): it turns backwards to roll forwards.
    assert joint_rates([left, right], 0.5, 0.0, 1.0) == pytest.approx([3.0, -7.0])


# -- the robot file: where the joints are ------------------------------------------------

@pytest.mark.parametrize('drive', ['diff', 'skid'])
def test_left_joint_on_the_robots_right_turns_it_clockwise(drive):
    pose, _ = drive_for(load(drive=drive, left_side=-1), 1.0, angular=1.0)
    # The plugin gives the left joint the slower wheel; that wheel is on the right.
    assert pose.yaw == pytest.approx(-1.0, abs=0.05)
    assert math.hypot(pose.x, pose.y) < 0.01
    # The same robot with its left joint on the left turns anticlockwise.
    pose, _ = drive_for(load(drive=drive), 1.0, angular=1.0)
    assert pose.yaw == pytest.approx(1.0, abs=0.05)


def test_joint_rpy_and_axis_are_followed_through_the_chain():
    # Turned by -90 degrees about x, an axis along z points along +y: the same robot.
    turned = load(hinge_rpy='-1.5707963267948966 0 0', hinge_axis='0 0 1')
    pose, _ = drive_for(turned, 1.0, linear=0.3)
    assert pose.x == pytest.approx(0.3, abs=0.01)
    # Axes along -y turn every wheel the other way: the robot backs off.
    backwards = load(hinge_axis='0 -1 0')
    pose, _ = drive_for(backwards, 1.0, linear=0.3)
    assert pose.x == pytest.approx(-0.3, abs=0.01)


def test_a_wheel_separation_tag_wider_than_the_wheels_turns_faster_than_commanded():
    # The plugin spreads 1 rad/s over 0.6 m (wheels at -+0.3 m/s); 0.3 m apart they turn 2 rad/s.
    pose, _ = drive_for(load(separation=0.6), 0.5, angular=1.0)
    assert pose.yaw == pytest.approx(1.0, abs=0.05)


# -- legacyMode --------------------------------------------------------------------------

def test_legacy_mode_does_not_swap_the_wheels_in_noetic():
    for legacy_mode in ('true', 'false', ''):
        spec = load(legacy_mode=legacy_mode)
        pose, _ = drive_for(spec, 1.0, angular=1.0)
        assert pose.yaw == pytest.approx(1.0, abs=0.05), legacy_mode
        notes = [text for text in skipped_text(spec) if 'legacyMode' in text]
        if legacy_mode == 'true':
            # Its author expected kinetic's swap: flatsim says noetic does not make it.
            assert len(notes) == 1 and 'not swapped' in notes[0], skipped_text(spec)
        else:
            assert notes == [], legacy_mode


# -- planar move -------------------------------------------------------------------------

def test_planar_move_reads_its_tags_with_the_plugins_defaults():
    drive = load(drive='planar').drive
    assert drive.plugin == 'planar_move'
    assert (drive.command_topic, drive.odometry_topic) == ('cmd_vel', 'odom')
    assert (drive.odometry_frame, drive.robot_base_frame) == ('odom', 'base_footprint')
    assert drive.update_rate == 50.0
    assert drive.publish_tf is True


def test_planar_move_moves_the_body_as_commanded_sideways_too():
    pose, sim = drive_for(load(drive='planar'), 1.0, linear=0.2, sideways=0.3, angular=0.0)
    assert (pose.x, pose.y, pose.yaw) == pytest.approx((0.2, 0.3, 0.0), abs=0.01)
    drive = sim.models['drive_bot'].drive
    _, twist = drive.odometry(sim.model_pose('drive_bot'), sim.model_twist('drive_bot'))
    assert twist == pytest.approx((0.2, 0.3, 0.0), abs=0.01)


def test_planar_move_publishes_odometry_at_odometry_rate():
    sim = Simulation()
    robot = sim.spawn_robot('drive_bot', load(drive='planar'), Pose())
    due = 0
    for _ in range(round(1.0 / sim.step_size)):
        sim.step()
        due += robot.drive.publish_due
    # Every 0.022 s (more than 1/50 s has passed), as the plugin counts.
    assert due == 45


# -- tricycle ------------------------------------------------------------------------------

def test_tricycle_reads_its_joints_and_places_them():
    spec = load(drive='tricycle')
    drive = spec.drive
    assert drive.plugin == 'tricycle', skipped_text(spec)
    assert drive.robot_base_frame == 'base_footprint'
    assert drive.steering.joint == 'steering_hinge'
    assert (drive.steering.x, drive.steering.y) == pytest.approx((0.3, 0.0))
    assert [w.joint for w in drive.wheels] == ['front_wheel_hinge']
    assert [w.joint for w in drive.encoder_wheels] == ['left_wheel_hinge', 'right_wheel_hinge']


def test_tricycle_angular_z_is_the_steering_angle():
    speed, angle, wheelbase = 0.2, 0.5, 0.3
    pose, sim = drive_for(load(drive='tricycle'), 2.0, linear=speed, angular=angle)
    drive = sim.models['drive_bot'].drive
    assert drive.steering_angle == pytest.approx(angle)
    # The rear axle cannot slide sideways: the robot turns about a point on it, at the
    # wheel's rim speed times sin(angle) over the wheelbase.
    _, (_, _, yaw_rate) = drive.odometry(sim.model_pose('drive_bot'), sim.model_twist('drive_bot'))
    assert yaw_rate == pytest.approx(speed * math.sin(angle) / wheelbase, rel=0.02)
    assert pose.yaw == pytest.approx(2.0 * speed * math.sin(angle) / wheelbase, rel=0.05)


def test_tricycle_with_steering_speed_turns_the_wheel_gradually():
    spec = load(drive='tricycle')
    spec.drive.steering_speed = 1.0
    sim = Simulation()
    robot = sim.spawn_robot('drive_bot', spec, Pose())
    robot.drive.set_command(0.0, 0.5)
    for _ in range(round(0.2 / sim.step_size)):
        sim.step()
    assert robot.drive.steering_angle == pytest.approx(0.2, abs=0.02)
    for _ in range(round(0.5 / sim.step_size)):
        sim.step()
    assert robot.drive.steering_angle == pytest.approx(0.5, abs=0.02)


# -- a drive plugin flatsim cannot run ------------------------------------------------------

def test_an_unknown_drive_plugin_is_named_with_its_command_topic():
    spec = load(drive='own')
    assert spec.drive is None
    notes = [text for text in skipped_text(spec) if 'libmy_four_wheel_steering.so' in text]
    assert len(notes) == 1
    assert 'a drive plugin flatsim cannot run' in notes[0]
    assert 'steer_cmd' in notes[0]
    sim = Simulation()
    robot = sim.spawn_robot('drive_bot', spec, Pose())
    report = describe(sim, robot)
    assert 'a drive plugin flatsim cannot run (its commands come on steer_cmd)' in report


def test_a_wheel_without_a_round_collision_takes_the_plugins_diameter_and_says_so():
    text = re.sub(r'<cylinder[^>]*/>', '<box size="0.2 0.04 0.2"/>', expand_xacro(DRIVE_BOT))
    spec = load_robot(text, name='drive_bot')
    notes = [item for item in spec.skipped if isinstance(item, Adjusted) and 'wheelDiameter' in str(item)]
    assert len(notes) == 2
    assert [w.radius for w in spec.drive.wheels] == [0.1, 0.1]


def test_inspect_shows_where_the_drive_wheels_really_are():
    sim = Simulation()
    robot = sim.spawn_robot('drive_bot', load(left_side=-1), Pose())
    report = describe(sim, robot)
    assert 'wheel left_wheel_hinge at (0.000, -0.150), radius 0.100 m, rolls towards 0 deg' in report
    assert 'wheel right_wheel_hinge at (0.000, 0.150), radius 0.100 m, rolls towards 0 deg' in report


def test_the_studio_lists_an_unknown_drive_plugin_under_skipped():
    sim = Simulation()
    sim.spawn_robot('drive_bot', load(drive='own'), Pose())
    items = [item for item in skipped_items(sim) if 'libmy_four_wheel_steering.so' in item['subject']]
    assert len(items) == 1
    assert items[0]['subject'].startswith('robot drive_bot: plugin four_wheel_steering')
    assert 'a drive plugin flatsim cannot run (its commands come on steer_cmd)' in items[0]['reason']


# -- ros_control's diff_drive_controller ------------------------------------------------------

def controlled(seconds, command, **params):
    """drive_bot on gazebo_ros_control, its diff_drive_controller given one command at t = 0."""
    sim = Simulation()
    robot = sim.spawn_robot('drive_bot', load(drive='control', **params.pop('robot', {})), Pose())
    manager = robot.control.manager
    settings = dict(type='diff_drive_controller/DiffDriveController', left_wheel='left_wheel_hinge',
                    right_wheel='right_wheel_hinge')
    settings.update(params)
    assert manager.load('base_controller', settings), manager.errors
    assert manager.switch(['base_controller'], [], 2, sim.time), manager.errors
    controller = manager.controllers['base_controller']
    controller.set_twist(*command, sim.time)
    for _ in range(round(seconds / sim.step_size)):
        sim.step()
    return sim.model_pose('drive_bot'), controller


def test_diff_drive_controller_moves_the_robot_on_its_wheels():
    pose, controller = controlled(1.0, (0.2, 0.5), cmd_vel_timeout=5.0)
    # Separation 0.3 m and radius 0.1 m from the URDF, as the controller looks them up.
    assert (controller.separation, controller.radius) == pytest.approx((0.3, 0.1))
    assert pose.yaw == pytest.approx(0.5, abs=0.03)
    assert pose.x == pytest.approx(0.2 * math.sin(0.5) / 0.5, abs=0.01)
    # Its odometry, dead reckoned from the wheel joints, agrees with where the robot is.
    assert controller.odometry.heading == pytest.approx(pose.yaw, abs=0.01)
    assert (controller.odometry.x, controller.odometry.y) == pytest.approx((pose.x, pose.y), abs=0.01)


def test_diff_drive_controller_with_its_left_wheel_on_the_right_turns_clockwise():
    pose, controller = controlled(1.0, (0.0, 1.0), cmd_vel_timeout=5.0, robot=dict(left_side=-1))
    assert pose.yaw == pytest.approx(-1.0, abs=0.05)
    # Its odometry believes the names, as in Gazebo: it reports the turn the other way.
    assert controller.odometry.heading == pytest.approx(1.0, abs=0.05)


def test_diff_drive_controller_stops_once_the_command_is_older_than_cmd_vel_timeout():
    pose, _ = controlled(2.0, (0.0, 1.0))
    # The default cmd_vel_timeout, 0.5 s: half a radian, then the wheels hold.
    assert pose.yaw == pytest.approx(0.5, abs=0.03)


def test_diff_drive_controller_limits_acceleration():
    pose, controller = controlled(0.5, (1.0, 0.0), cmd_vel_timeout=5.0,
                                  linear={'x': {'has_acceleration_limits': True, 'max_acceleration': 1.0}})
    # From rest at 1 m/s^2 for 0.5 s: 0.125 m.
    assert pose.x == pytest.approx(0.125, abs=0.01)


def test_inspect_describes_a_diff_drive_controller_from_a_controllers_file():
    sim = Simulation()
    robot = sim.spawn_robot('drive_bot', load(drive='control'), Pose())
    params = {'drive_bot': {'base_controller': {
        'type': 'diff_drive_controller/DiffDriveController', 'left_wheel': 'left_wheel_hinge',
        'right_wheel': 'right_wheel_hinge'}}}
    report = describe(sim, robot, [('controllers.yaml', params)])
    assert ('base_controller: diff_drive_controller/DiffDriveController on left_wheel_hinge / '
            'right_wheel_hinge (VelocityJointInterface); /drive_bot/base_controller/cmd_vel '
            '(geometry_msgs/Twist) -> /drive_bot/base_controller/odom and /tf odom -> base_link; '
            'separation 0.3 m, radius 0.1 m, cmd_vel_timeout 0.5 s') in report
    assert ('drive: the ros_control velocity joints left_wheel_hinge, right_wheel_hinge roll the '
            'robot on the floor') in report


def test_a_plugin_that_is_no_drive_is_not_called_one():
    text = expand_xacro(DRIVE_BOT).replace(
        '</robot>', '<gazebo><plugin name="slip" filename="libgazebo_ros_wheel_slip.so"/>'
        '<plugin name="lights" filename="libmy_blinking_lights.so"><period>1</period></plugin>'
        '</gazebo></robot>')
    notes = [str(item) for item in load_robot(text, name='drive_bot').skipped]
    assert [n for n in notes if 'wheel_slip' in n] == [
        'plugin slip (libgazebo_ros_wheel_slip.so): flatsim does not provide '
        'libgazebo_ros_wheel_slip.so; the robot runs without it']
    assert not any('drive plugin' in n for n in notes)
