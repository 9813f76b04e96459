"""Kinematics of gazebo_plugins' drive plugins (noetic): diff drive, skid steer,
tricycle drive and planar move.

A wheel drive turns the last velocity command into joint speed targets the way
its plugin does, and reports the body twist those joints give where the URDF
puts them: each driven wheel rolls without slip along the direction its joint
axis and radius give, and grips the ground across it (twist_matrix). So a
robot whose leftJoint sits on its right side turns clockwise for a positive
angular.z, and one whose wheelSeparation tag differs from its wheels' true
separation turns at another rate than commanded, as in Gazebo. Physics
realises that twist with the force the wheel torque limit allows
(flatsim.world.physics). Wheel joints roll without slip, so their speeds
follow the body's actual twist.

Planar move sets the body's velocity outright, as the plugin does.
"""
import math

import numpy as np

from flatsim.errors import FlatsimError
from flatsim.loading.config import Wheel
from flatsim.pose import Pose

# Beyond any speed a wheel torque limit reaches, yet small enough that squaring
# it in the physics solver stays finite.
COMMAND_LIMIT = 1.0e6

# gazebo_ros_diff_drive stops ramping when a wheel is this close to its target (m/s).
RAMP_DONE_TOLERANCE = 0.01

# Simulation time in integer nanoseconds, as gazebo's common::Time counts it,
# so "more than one update period has passed" does not depend on float rounding.
# Slower than once in 1000 s is no drive (and 1e-300 Hz overflows the period).
MIN_UPDATE_RATE = 1e-3
NANOSECONDS = 1_000_000_000


class InvalidCommand(FlatsimError):
    """A velocity command with a NaN or infinite component; the drive keeps its last command."""


def _number(config_value, what):
    try:
        return float(config_value)
    except (TypeError, ValueError):
        raise FlatsimError('%s must be a number, not %r' % (what, config_value)) from None


def _positive(config_value, what):
    value = _number(config_value, what)
    if not (math.isfinite(value) and value > 0.0):
        raise FlatsimError('%s must be a positive number, not %r' % (what, config_value))
    return value


def _non_negative(config_value, what):
    value = _number(config_value, what)
    if not (math.isfinite(value) and value >= 0.0):
        raise FlatsimError('%s must be zero or a positive number, not %r' % (what, config_value))
    return value


def _clamp(value, limit):
    return max(-limit, min(limit, value))


def _unit_rows(wheels):
    """Rows of the rolling and sideways constraints of each wheel that can roll the robot.

    A wheel at p rolling along g (ground velocity per rad/s of its joint) allows
    a body twist (vx, vy, wz) whose velocity at p, (vx - wz py, vy + wz px), has
    the component |g| * rate along g and none across it.
    """
    rolling, sideways, gains, used = [], [], [], []
    for index, wheel in enumerate(wheels):
        gain = math.hypot(wheel.roll_x, wheel.roll_y)
        if gain < 1e-12:
            continue                      # an axis upright: the wheel spins in place
        ux, uy = wheel.roll_x / gain, wheel.roll_y / gain
        rolling.append((ux, uy, wheel.x * uy - wheel.y * ux))
        sideways.append((-uy, ux, wheel.x * ux + wheel.y * uy))
        gains.append(gain)
        used.append(index)
    return rolling, sideways, gains, used


def twist_matrix(driven, held=()):
    """The 3 x n matrix that turns the driven wheels' joint rates into the body twist.

    The driven wheels roll as their joints turn; where their rolling leaves the
    body free (sideways, for two wheels on one axle), the wheels' and the held
    (passive) wheels' grip across their rolling direction decides. Rolling
    constraints that disagree (four wheels, skid steering) are met in the least
    squares sense, the body scrubbing its wheels sideways as it turns.
    """
    rolling, sideways, gains, used = _unit_rows(driven)
    matrix = np.zeros((3, len(driven)))
    if not rolling:
        return matrix
    a = np.array(rolling)
    solve = np.linalg.pinv(a)                                   # 3 x k
    _, singular, vt = np.linalg.svd(a)
    rank = int(np.sum(singular > 1e-9 * max(1.0, singular[0])))
    free = vt[rank:].T                                          # 3 x (3 - rank)
    grip = sideways + _unit_rows(held)[1]
    if free.size and grip:
        lateral = np.array(grip)
        solve = (np.eye(3) - free @ np.linalg.pinv(lateral @ free) @ lateral) @ solve
    matrix[:, used] = solve * np.array(gains)
    return matrix


def joint_rates(wheels, linear_x, linear_y, angular):
    """Each wheel's joint rate (rad/s) when the body moves at (vx, vy, wz) and the wheel rolls."""
    rates = []
    for wheel in wheels:
        gain_squared = wheel.roll_x ** 2 + wheel.roll_y ** 2
        if gain_squared < 1e-24:
            rates.append(0.0)
            continue
        vx = linear_x - angular * wheel.y
        vy = linear_y + angular * wheel.x
        rates.append((vx * wheel.roll_x + vy * wheel.roll_y) / gain_squared)
    return rates


def ideal_wheels(config, per_side):
    """The wheels the plugin's parameters describe: axles along +y, wheelSeparation apart."""
    radius = config.wheel_diameter / 2.0
    half = config.wheel_separation / 2.0
    return ([Wheel(name, 0.0, half, radius, 0.0, radius) for name in config.left_joints[:per_side]]
            + [Wheel(name, 0.0, -half, radius, 0.0, radius) for name in config.right_joints[:per_side]])


class Drive:
    """What the wheel plugins share: command, update clock, wheel joints and odometry.

    Per physics step the owner calls update(dt, vx, vy, wz) with the body's
    actual twist in its own frame; it returns the twist the wheels now drive
    the body at. The plugin computes wheel speeds from its parameters and sets
    them on the joints it names; where those joints are, and how their axes
    point, decide how the body moves (flatsim.world.drive.twist_matrix), as
    the wheels do in Gazebo.
    """

    wheels_per_side = 1

    def __init__(self, config):
        self.config = config
        self.wheel_separation = _positive(config.wheel_separation, 'wheelSeparation')
        self.wheel_radius = _positive(config.wheel_diameter, 'wheelDiameter') / 2.0
        self.wheel_torque = _non_negative(config.wheel_torque, 'wheel torque')
        update_rate = _number(config.update_rate, 'updateRate')
        if math.isnan(update_rate):
            raise FlatsimError('updateRate must be a number, not %r' % config.update_rate)
        if 0.0 < update_rate < MIN_UPDATE_RATE:
            raise FlatsimError('updateRate %g Hz would never update the drive; give at least %g Hz'
                               % (update_rate, MIN_UPDATE_RATE))
        # gazebo_ros: a rate that is not positive means "update on every step".
        self._period_ns = round(NANOSECONDS / update_rate) if update_rate > 0.0 else 0
        self.left_joints = list(config.left_joints)
        self.right_joints = list(config.right_joints)
        self.wheels = list(config.wheels) or ideal_wheels(config, self.wheels_per_side)
        names = [wheel.joint for wheel in self.wheels]
        # Which side's speed each wheel joint is given (0 left, 1 right), as the plugin pairs them.
        self._sides = [0 if name in self.left_joints else 1 for name in names]
        self._twist_of_rates = twist_matrix(self.wheels)
        self.reset()

    def reset(self):
        """Like the plugin's Reset() on a world reset: the command and odometry start over."""
        self.linear_command = 0.0
        self.angular_command = 0.0
        self.sideways_command = 0.0
        self._now_ns = 0
        self._last_update_ns = 0
        self._last_ramp_ns = 0
        self.wheel_targets = (0.0, 0.0)  # left, right wheel rim speed the plugin sets (m/s)
        self._wheel_speeds = (0.0, 0.0)  # left, right rim speed as the plugin reads it (m/s)
        self._rates = [0.0] * len(self.wheels)
        self._joint_angles = [0.0] * len(self.wheels)
        self.publish_due = False

    def set_command(self, linear_x, angular_z, linear_y=0.0):
        """Take a cmd_vel; it persists until the next one (the plugins have no timeout)."""
        try:
            linear, angular, sideways = float(linear_x), float(angular_z), float(linear_y)
        except (TypeError, ValueError):
            linear = angular = sideways = math.nan
        if not (math.isfinite(linear) and math.isfinite(angular) and math.isfinite(sideways)):
            raise InvalidCommand('ignoring velocity command (%r, %r): not finite' % (linear_x, angular_z))
        self.linear_command = _clamp(linear, COMMAND_LIMIT)
        self.angular_command = _clamp(angular, COMMAND_LIMIT)
        self.sideways_command = _clamp(sideways, COMMAND_LIMIT)

    @property
    def max_force(self):
        """Largest total push the wheels give the body (N): each wheel at its torque limit."""
        return sum(self.wheel_torque / wheel.radius for wheel in self.wheels if wheel.radius > 0.0)

    @property
    def max_torque(self):
        """Largest yaw torque the wheels give the body (N*m): each wheel pushing at its lever arm."""
        total = 0.0
        for wheel in self.wheels:
            gain = math.hypot(wheel.roll_x, wheel.roll_y)
            if wheel.radius > 0.0 and gain > 0.0:
                arm = abs(wheel.x * wheel.roll_y - wheel.y * wheel.roll_x) / gain
                total += self.wheel_torque / wheel.radius * arm
        return total

    def commanded_wheel_speeds(self):
        half_track_rate = self.angular_command * self.wheel_separation / 2.0
        return self.linear_command - half_track_rate, self.linear_command + half_track_rate

    def body_twist(self, side_speeds):
        """The body twist when each wheel joint turns at its side's rim speed over the plugin's radius."""
        rates = np.array([side_speeds[side] / self.wheel_radius for side in self._sides])
        linear_x, linear_y, angular = self._twist_of_rates @ rates
        return float(linear_x), float(linear_y), float(angular)

    def update(self, dt, actual_x, actual_y, actual_angular):
        """Advance the plugin by one physics step of dt seconds; return the target body twist."""
        self._now_ns += round(dt * NANOSECONDS)
        self._rates = joint_rates(self.wheels, actual_x, actual_y, actual_angular)
        for index, rate in enumerate(self._rates):
            self._joint_angles[index] += rate * dt
        # The plugin reads each side's first joint and takes its own wheelDiameter for the radius.
        self._wheel_speeds = tuple(self._rates[self._sides.index(side)] * self.wheel_radius
                                   if side in self._sides else 0.0 for side in (0, 1))
        self._before_update(dt)
        self.publish_due = self._now_ns - self._last_update_ns > self._period_ns
        if self.publish_due:
            self.wheel_targets = self._next_wheel_targets()
            self._last_ramp_ns = self._now_ns
            self._last_update_ns += self._period_ns
            if self._period_ns == 0:
                self._last_update_ns = self._now_ns
        return self.body_twist(self.wheel_targets)

    def _before_update(self, dt):
        """Per-step bookkeeping the plugin does before its rate check."""

    def _next_wheel_targets(self):
        return self.commanded_wheel_speeds()

    def odometry(self, world_pose, world_twist):
        """What the odometry message holds, from the ground truth Pose and world (vx, vy, wz).

        Returns (pose in the odometry frame, (vx, vy, wz) in the robot base frame).
        """
        vx, vy, wz = world_twist
        cos_yaw, sin_yaw = math.cos(world_pose.yaw), math.sin(world_pose.yaw)
        return world_pose, (cos_yaw * vx + sin_yaw * vy, cos_yaw * vy - sin_yaw * vx, wz)

    def wheel_states(self):
        """(names, positions in rad, velocities in rad/s) of every wheel joint, left side first."""
        by_name = {wheel.joint: index for index, wheel in enumerate(self.wheels)}
        names, positions, velocities = [], [], []
        for name in self.left_joints + self.right_joints:
            index = by_name.get(name)
            names.append(name)
            positions.append(self._joint_angles[index] if index is not None else 0.0)
            velocities.append(self._rates[index] if index is not None else 0.0)
        return names, positions, velocities


class DiffDrive(Drive):
    """libgazebo_ros_diff_drive: optional wheel acceleration ramp, world or encoder odometry.

    wheelAcceleration limits how fast the wheel rim speed targets change (m/s^2:
    the plugin compares it with rim speeds, joint rate times wheel radius).
    Two deliberate departures from the plugin's arithmetic, both to keep the
    ramp at the configured rate: the ramp advances by the time since the
    previous update (the plugin uses the time since the nominal update instant,
    which overshoots by one physics step), and it ramps from the last target
    rather than adding to it the gap to the measured speed (which keeps growing
    while a wall holds the robot).
    """

    def __init__(self, config):
        self.wheel_acceleration = _non_negative(config.wheel_acceleration, 'wheelAcceleration')
        if config.odometry_source not in ('world', 'encoder'):
            raise FlatsimError("odometrySource must be 'world' or 'encoder', not %r" % config.odometry_source)
        self.odometry_source = config.odometry_source
        super().__init__(config)

    def reset(self):
        super().reset()
        self._encoder_pose = (0.0, 0.0, 0.0)
        self._encoder_twist = (0.0, 0.0)

    def _before_update(self, dt):
        if self.odometry_source == 'encoder':
            self._integrate_encoders(dt)

    def _integrate_encoders(self, dt):
        """Dead reckoning from wheel travel, the arc formula the plugin uses (Siegwart 2011)."""
        left_travel = self._wheel_speeds[0] * dt
        right_travel = self._wheel_speeds[1] * dt
        travel_sum = left_travel + right_travel
        travel_diff = right_travel - left_travel
        x, y, theta = self._encoder_pose
        mid_heading = theta + travel_diff / (2.0 * self.wheel_separation)
        dx = travel_sum / 2.0 * math.cos(mid_heading)
        dy = travel_sum / 2.0 * math.sin(mid_heading)
        dtheta = travel_diff / self.wheel_separation
        self._encoder_pose = (x + dx, y + dy, theta + dtheta)
        if dt > 0.0:
            speed = math.hypot(dx, dy) / dt
            self._encoder_twist = (-speed if travel_sum < 0.0 else speed, dtheta / dt)

    def _next_wheel_targets(self):
        targets = self.commanded_wheel_speeds()
        if self.wheel_acceleration == 0.0 or any(
                abs(target - speed) < RAMP_DONE_TOLERANCE
                for target, speed in zip(targets, self._wheel_speeds)):
            return targets
        max_change = self.wheel_acceleration * (self._now_ns - self._last_ramp_ns) / NANOSECONDS
        return tuple(previous + _clamp(target - previous, max_change)
                     for previous, target in zip(self.wheel_targets, targets))

    def odometry(self, world_pose, world_twist):
        if self.odometry_source == 'world':
            return super().odometry(world_pose, world_twist)
        x, y, yaw = self._encoder_pose
        linear, angular = self._encoder_twist
        return Pose(x, y, 0.0, 0.0, 0.0, yaw), (linear, 0.0, angular)


class SkidSteerDrive(Drive):
    """libgazebo_ros_skid_steer_drive: four wheels, no ramp, ground-truth odometry."""

    wheels_per_side = 2


class PlanarMove:
    """libgazebo_ros_planar_move: the body's velocity is set to the command, no wheels.

    Every physics step the plugin sets the model's linear velocity to
    (linear.x, linear.y) turned by its yaw and its yaw rate to angular.z. It
    publishes odometry at odometryRate (Hz; 0 or less: never), with the twist
    from the pose's change since the last message.
    """

    wheel_torque = 0.0
    left_joints = right_joints = ()

    def __init__(self, config):
        self.config = config
        rate = _number(config.update_rate, 'odometryRate')
        if math.isnan(rate):
            raise FlatsimError('odometryRate must be a number, not %r' % config.update_rate)
        self._period_ns = round(NANOSECONDS / rate) if rate >= MIN_UPDATE_RATE else None
        self.reset()

    # Set outright by the plugin: physics holds it with a force of its own, not a wheel's.
    max_force = None
    max_torque = None

    def reset(self):
        self.linear_command = self.sideways_command = self.angular_command = 0.0
        self._now_ns = 0
        self._last_publish_ns = 0
        self._interval = 0.0
        self._last_pose = None
        self.publish_due = False

    def set_command(self, linear_x, angular_z, linear_y=0.0):
        values = []
        for value in (linear_x, linear_y, angular_z):
            try:
                values.append(float(value))
            except (TypeError, ValueError):
                values.append(math.nan)
        if not all(math.isfinite(value) for value in values):
            raise InvalidCommand('ignoring velocity command (%r, %r, %r): not finite'
                                 % (linear_x, linear_y, angular_z))
        self.linear_command, self.sideways_command, self.angular_command = (
            _clamp(value, COMMAND_LIMIT) for value in values)

    def update(self, dt, actual_x, actual_y, actual_angular):
        self._now_ns += round(dt * NANOSECONDS)
        since = self._now_ns - self._last_publish_ns
        self.publish_due = self._period_ns is not None and since > self._period_ns
        if self.publish_due:
            self._interval = since / NANOSECONDS
            self._last_publish_ns = self._now_ns
        return self.linear_command, self.sideways_command, self.angular_command

    def odometry(self, world_pose, world_twist):
        """Pose from the world; twist from the pose's change over the time since the last message."""
        last, self._last_pose = self._last_pose, world_pose
        if last is None or self._interval <= 0.0:
            # No earlier message to difference against: the body's own velocity.
            return Drive.odometry(self, world_pose, world_twist)
        step = self._interval
        vx = (world_pose.x - last.x) / step
        vy = (world_pose.y - last.y) / step
        if self.angular_command > math.pi / step:
            angular = self.angular_command      # the plugin's way round a turn it cannot see
        else:
            angular = math.remainder(world_pose.yaw - last.yaw, 2.0 * math.pi) / step
        cos_yaw, sin_yaw = math.cos(world_pose.yaw), math.sin(world_pose.yaw)
        return world_pose, (cos_yaw * vx + sin_yaw * vy, cos_yaw * vy - sin_yaw * vx, angular)

    def wheel_states(self):
        return [], [], []


def _turned(wheel, steering, angle):
    """The actuated wheel with its steering joint at `angle`."""
    turn = steering.sense * angle
    cos_turn, sin_turn = math.cos(turn), math.sin(turn)
    dx, dy = wheel.x - steering.x, wheel.y - steering.y
    return Wheel(wheel.joint, steering.x + cos_turn * dx - sin_turn * dy,
                 steering.y + sin_turn * dx + cos_turn * dy,
                 cos_turn * wheel.roll_x - sin_turn * wheel.roll_y,
                 sin_turn * wheel.roll_x + cos_turn * wheel.roll_y, wheel.radius, wheel.z)


class TricycleDrive:
    """libgazebo_ros_tricycle_drive: one steered, driven wheel; two passive encoder wheels.

    cmd_vel's linear.x is the driven wheel's rim speed (m/s at
    actuatedWheelDiameter) and angular.z its steering angle (rad), not a yaw
    rate. At each update the plugin sets the wheel joint's speed (ramped by
    wheelAcceleration / wheelDeceleration in rad/s^2 when they are positive)
    and either sets the steering joint to the angle (steeringSpeed 0) or turns
    it at steeringSpeed towards the angle clamped to +-pi/2. The two
    comparisons of its ramp and steering are kept as the plugin writes them
    (the speed gap compared with the target speed, the angle gap with the
    target wheel speed).
    """

    def __init__(self, config):
        self.config = config
        if config.steering is None or not config.wheels or len(config.encoder_wheels) != 2:
            raise FlatsimError('the tricycle drive needs a steering joint, a driven wheel and two '
                               'encoder wheels')
        self.wheel_radius = _positive(config.wheel_diameter, 'actuatedWheelDiameter') / 2.0
        self.wheel_torque = _non_negative(config.wheel_torque, 'wheelTorque')
        self.acceleration = _non_negative(config.wheel_acceleration, 'wheelAcceleration')
        self.deceleration = _non_negative(config.wheel_deceleration, 'wheelDeceleration')
        self.speed_tolerance = _non_negative(config.wheel_speed_tolerance, 'wheelSpeedTolerance')
        self.steering_speed = _non_negative(config.steering_speed, 'steeringSpeed')
        self.angle_tolerance = _non_negative(config.steering_angle_tolerance, 'steeringAngleTolerance')
        update_rate = _number(config.update_rate, 'updateRate')
        if math.isnan(update_rate) or 0.0 < update_rate < MIN_UPDATE_RATE:
            raise FlatsimError('updateRate must be a number of at least %g Hz, not %r'
                               % (MIN_UPDATE_RATE, config.update_rate))
        self._period_ns = round(NANOSECONDS / update_rate) if update_rate > 0.0 else 0
        self.actuated = config.wheels[0]
        self.steering = config.steering
        self.encoders = list(config.encoder_wheels)
        self.left_joints = [config.steering.joint, self.actuated.joint, self.encoders[0].joint]
        self.right_joints = [self.encoders[1].joint]
        self.reset()

    def reset(self):
        self.linear_command = self.angular_command = self.sideways_command = 0.0
        self._now_ns = 0
        self._last_update_ns = 0
        self.steering_angle = 0.0
        self.steering_rate = 0.0
        self.wheel_rate_target = 0.0
        self._wheel_rate = 0.0
        self._wheel_angle = 0.0
        self._encoder_rates = [0.0, 0.0]
        self._encoder_angles = [0.0, 0.0]
        self.publish_due = False
        self._turn(0.0)

    def _turn(self, angle):
        self.steering_angle = angle
        self._wheel = _turned(self.actuated, self.steering, angle)
        self._twist_of_rate = twist_matrix([self._wheel], held=self.encoders)[:, 0]

    set_command = Drive.set_command

    @property
    def max_force(self):
        return self.wheel_torque / self.actuated.radius if self.actuated.radius > 0.0 else 0.0

    @property
    def max_torque(self):
        """The yaw torque the driven wheel's push gives at the longest lever the wheels have.

        A tricycle turns by the grip of its wheels across their rolling direction, which
        is friction, not wheel torque; the wheel's push at that lever stands in for it.
        """
        levers = [math.hypot(self.steering.x, self.steering.y)]
        levers += [math.hypot(wheel.x, wheel.y) for wheel in self.encoders]
        return self.max_force * max(levers)

    def update(self, dt, actual_x, actual_y, actual_angular):
        self._now_ns += round(dt * NANOSECONDS)
        self._wheel_rate = joint_rates([self._wheel], actual_x, actual_y, actual_angular)[0]
        self._wheel_angle += self._wheel_rate * dt
        self._encoder_rates = joint_rates(self.encoders, actual_x, actual_y, actual_angular)
        for index, rate in enumerate(self._encoder_rates):
            self._encoder_angles[index] += rate * dt
        if self.steering_rate:
            self._turn(self.steering_angle + self.steering_rate * dt)
        since_ns = self._now_ns - self._last_update_ns
        self.publish_due = since_ns > self._period_ns
        if self.publish_due:
            self._control(since_ns / NANOSECONDS)
            self._last_update_ns += self._period_ns
            if self._period_ns == 0:
                self._last_update_ns = self._now_ns
        linear_x, linear_y, angular = self._twist_of_rate * self.wheel_rate_target
        return float(linear_x), float(linear_y), float(angular)

    def _control(self, seconds):
        target_speed = self.linear_command / self.wheel_radius
        applied = target_speed
        if self.acceleration > 0.0:
            current = self._wheel_rate
            gap = current - target_speed
            if abs(gap) < self.speed_tolerance:
                applied = target_speed
            elif gap < target_speed:
                applied = current + self.acceleration * seconds
            else:
                applied = current - self.deceleration * seconds
        self.wheel_rate_target = applied
        target_angle = self.angular_command
        if self.steering_speed > 0.0:
            clamped = max(-math.pi / 2.0, min(math.pi / 2.0, target_angle))
            gap = self.steering_angle - clamped
            if abs(gap) < self.angle_tolerance:
                self.steering_rate = 0.0
            elif gap < target_speed:
                self.steering_rate = self.steering_speed
            else:
                self.steering_rate = -self.steering_speed
        else:
            self._turn(target_angle)

    odometry = Drive.odometry

    def wheel_states(self):
        """Steering, actuated wheel, left and right encoder wheel, as the plugin lists them."""
        names = [self.steering.joint, self.actuated.joint] + [w.joint for w in self.encoders]
        positions = [self.steering_angle, self._wheel_angle] + self._encoder_angles
        velocities = [self.steering_rate, self._wheel_rate] + self._encoder_rates
        return names, positions, velocities


class RosControlWheels:
    """Wheels that ros_control turns (diff_drive_controller) rolling the robot on the floor.

    Each step the velocity commands on the wheel joints, through their velocity
    limits, give the body twist the wheels roll it at (twist_matrix); the
    wheel joints' positions and rates then follow the body's actual motion, as
    wheels that roll without slip do, so the controller's odometry reads them.
    Without a running controller the commands stay zero and the wheels hold
    the robot, as Gazebo's velocity joints do.
    """

    left_joints = right_joints = ()
    publish_due = False

    def __init__(self, control, wheels):
        self.control = control
        self.wheels = [wheel for wheel in wheels if wheel.joint in control.hw.joints]
        self._twist_of_rates = twist_matrix(self.wheels)
        hw = control.hw
        self._joints = [hw.joints[wheel.joint] for wheel in self.wheels]
        self._limits = [joint.model.limits for joint in self._joints]
        self.reset()

    @property
    def max_force(self):
        """Each wheel's push at its effort limit; without one the joints are held at their speed."""
        if any(limits.effort is None for limits in self._limits):
            return None
        return sum(limits.effort / wheel.radius for limits, wheel in zip(self._limits, self.wheels))

    @property
    def max_torque(self):
        if self.max_force is None:
            return None
        total = 0.0
        for limits, wheel in zip(self._limits, self.wheels):
            gain = math.hypot(wheel.roll_x, wheel.roll_y)
            total += limits.effort / wheel.radius * abs(wheel.x * wheel.roll_y - wheel.y * wheel.roll_x) / gain
        return total

    def reset(self):
        self._angles = [0.0] * len(self.wheels)

    def update(self, dt, actual_x, actual_y, actual_angular):
        # The articulation moved the wheel joints on a base that stays put; on the floor they
        # roll with the body instead.
        articulation = self.control.articulation
        rolling = joint_rates(self.wheels, actual_x, actual_y, actual_angular)
        for index, (joint, rate) in enumerate(zip(self._joints, rolling)):
            self._angles[index] += rate * dt
            articulation.velocity[joint.index] = rate
            articulation.position[joint.index] = self._angles[index]
        rates = []
        for joint, limits in zip(self._joints, self._limits):
            command = joint.command if joint.interface == 'velocity' and math.isfinite(joint.command) else 0.0
            if limits.velocity is not None:
                command = _clamp(command, limits.velocity)
            rates.append(command)
        linear_x, linear_y, angular = self._twist_of_rates @ np.array(rates)
        return float(linear_x), float(linear_y), float(angular)


def make_drive(config):
    """The drive class the config's plugin names."""
    kinds = {'diff_drive': DiffDrive, 'skid_steer': SkidSteerDrive, 'planar_move': PlanarMove,
             'tricycle': TricycleDrive}
    try:
        kind = kinds[config.plugin]
    except KeyError:
        raise FlatsimError('unknown drive plugin %r (expected one of %s)'
                           % (config.plugin, ', '.join(sorted(kinds)))) from None
    return kind(config)
