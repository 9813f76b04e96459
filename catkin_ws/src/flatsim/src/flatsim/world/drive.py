"""Wheel kinematics of gazebo_ros's diff drive and skid steer plugins.

A drive turns the last velocity command into wheel speed targets the way
libgazebo_ros_diff_drive / libgazebo_ros_skid_steer_drive (noetic) do, and
reports the body twist those wheel speeds give. Physics realises that twist
with the force the wheel torque limit allows (flatsim.world.physics). Wheel joints
roll without slip, so their speeds follow the body's actual twist.
"""
import math

from flatsim.errors import FlatsimError
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


class Drive:
    """What the two plugins share: command, update clock, wheel joints and odometry.

    Per physics step the owner calls update(dt, v, w) with the body's actual
    forward speed and yaw rate; it returns the (v, w) the wheels are set to.
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
        self.reset()

    def reset(self):
        """Like the plugin's Reset() on a world reset: the command and odometry start over."""
        self.linear_command = 0.0
        self.angular_command = 0.0
        self._now_ns = 0
        self._last_update_ns = 0
        self._last_ramp_ns = 0
        self.wheel_targets = (0.0, 0.0)  # left, right wheel rim speed set on the joints (m/s)
        self._wheel_speeds = (0.0, 0.0)  # actual left, right rim speeds (m/s)
        self._joint_angles = [0.0, 0.0]  # left, right (rad)
        self.publish_due = False

    def set_command(self, linear_x, angular_z):
        """Take a cmd_vel; it persists until the next one (the plugins have no timeout)."""
        try:
            linear, angular = float(linear_x), float(angular_z)
        except (TypeError, ValueError):
            linear = angular = math.nan
        if not (math.isfinite(linear) and math.isfinite(angular)):
            raise InvalidCommand('ignoring velocity command (%r, %r): not finite' % (linear_x, angular_z))
        self.linear_command = _clamp(linear, COMMAND_LIMIT)
        self.angular_command = _clamp(angular, COMMAND_LIMIT)

    @property
    def max_wheel_force(self):
        """Ground force one wheel exerts at the torque limit (N)."""
        return self.wheel_torque / self.wheel_radius

    @property
    def max_force(self):
        """Largest total push the wheels give the body (N)."""
        return 2 * self.wheels_per_side * self.max_wheel_force

    @property
    def max_torque(self):
        """Largest yaw torque the wheels give the body (N*m): every wheel pushing at half the track."""
        return 2 * self.wheels_per_side * self.max_wheel_force * self.wheel_separation / 2.0

    def commanded_wheel_speeds(self):
        half_track_rate = self.angular_command * self.wheel_separation / 2.0
        return self.linear_command - half_track_rate, self.linear_command + half_track_rate

    def update(self, dt, actual_linear, actual_angular):
        """Advance the plugin by one physics step of dt seconds; return the target body (v, w)."""
        self._now_ns += round(dt * NANOSECONDS)
        half_track_rate = actual_angular * self.wheel_separation / 2.0
        self._wheel_speeds = (actual_linear - half_track_rate, actual_linear + half_track_rate)
        for side, speed in enumerate(self._wheel_speeds):
            self._joint_angles[side] += speed / self.wheel_radius * dt
        self._before_update(dt)
        self.publish_due = self._now_ns - self._last_update_ns > self._period_ns
        if self.publish_due:
            self.wheel_targets = self._next_wheel_targets()
            self._last_ramp_ns = self._now_ns
            self._last_update_ns += self._period_ns
            if self._period_ns == 0:
                self._last_update_ns = self._now_ns
        left, right = self.wheel_targets
        return (left + right) / 2.0, (right - left) / self.wheel_separation

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
        """(names, positions in rad, velocities in rad/s) of every wheel joint, left side first.

        Wheels roll without slipping, so all wheels on one side turn together.
        """
        names, positions, velocities = [], [], []
        for side, joints in enumerate((self.left_joints, self.right_joints)):
            for name in joints:
                names.append(name)
                positions.append(self._joint_angles[side])
                velocities.append(self._wheel_speeds[side] / self.wheel_radius)
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


def make_drive(config):
    """The drive class the config's plugin names."""
    kinds = {'diff_drive': DiffDrive, 'skid_steer': SkidSteerDrive}
    try:
        kind = kinds[config.plugin]
    except KeyError:
        raise FlatsimError('unknown drive plugin %r (expected one of %s)'
                           % (config.plugin, ', '.join(sorted(kinds)))) from None
    return kind(config)
