"""ros_control as gazebo_ros_control runs it, without ROS: hardware, controllers, their manager.

Semantics copied from ros_control / ros_controllers / gazebo_ros_control (noetic):
- RobotHW: one joint per transmission, on the effort, position or velocity
  interface its transmission names; joint names in sorted order (ros_control
  keeps them in a std::map). Effort commands pass the soft-limit handle when
  the URDF joint has a <safety_controller>, else the saturation handle;
  position and velocity commands pass their saturation handles.
- control_toolbox::Pid: p required; i, d, i_clamp (or i_clamp_min/max) and
  antiwindup optional; without antiwindup the integral term is clamped to
  +/- i_clamp (so with no i_clamp it is zero); a NaN or infinite error gives 0.
- Controllers: effort_controllers/Joint{Position,Velocity,Effort}Controller,
  position_controllers/JointPositionController,
  velocity_controllers/JointVelocityController and
  joint_state_controller/JointStateController, each with the same parameters,
  topics (relative to the controller's namespace) and start behaviour.
- ControllerManager: load (type from the parameters, init, claim), unload
  (not while running), switch (STRICT / BEST_EFFORT, resource conflicts), list.
Failures return the same messages ros_control logs, for the ROS layer to log.
"""
import math
from dataclasses import dataclass, field
from typing import Dict, List

import numpy as np

from flatsim.names import logged_name

BEST_EFFORT, STRICT = 1, 2
INTERFACE_NAMES = {'effort': 'hardware_interface::EffortJointInterface',
                   'position': 'hardware_interface::PositionJointInterface',
                   'velocity': 'hardware_interface::VelocityJointInterface'}
STATE_INTERFACE = 'hardware_interface::JointStateInterface'
# Controllers publish their state every this many updates (ros_controllers' loop_count_ % 10).
STATE_DECIMATION = 10


class ControllerError(Exception):
    """A controller that cannot be loaded; the message is what ros_control would log."""


def clamp(value, low, high):
    return min(max(value, low), high)


def shortest_angular_distance(start, end):
    """angles::shortest_angular_distance."""
    return math.remainder(end - start, 2.0 * math.pi)


class Pid:
    """control_toolbox::Pid with gains from a parameter dict (the controller's pid namespace)."""

    def __init__(self, params, namespace):
        if not isinstance(params, dict) or 'p' not in params:
            raise ControllerError('No p gain specified for pid.  Namespace: %s' % namespace)
        self.p = _number(params['p'], namespace + '/p')
        self.i = _number(params.get('i', 0.0), namespace + '/i')
        self.d = _number(params.get('d', 0.0), namespace + '/d')
        i_clamp = abs(_number(params.get('i_clamp', 0.0), namespace + '/i_clamp'))
        self.i_max, self.i_min = i_clamp, -i_clamp
        if 'i_clamp_min' in params:
            self.i_min = -abs(_number(params['i_clamp_min'], namespace + '/i_clamp_min'))
        if 'i_clamp_max' in params:
            self.i_max = abs(_number(params['i_clamp_max'], namespace + '/i_clamp_max'))
        self.antiwindup = bool(params.get('antiwindup', False))
        self.reset()

    def reset(self):
        self.p_error_last = self.p_error = self.i_error = self.d_error = self.command = 0.0

    def compute(self, error, dt):
        """computeCommand(error, dt): the error's derivative is taken from its change."""
        if dt == 0.0 or not math.isfinite(error):
            return 0.0
        error_dot = (error - self.p_error_last) / dt
        self.p_error_last = error
        return self.compute_with_derivative(error, error_dot, dt)

    def compute_with_derivative(self, error, error_dot, dt):
        self.p_error, self.d_error = error, error_dot
        if dt == 0.0 or not math.isfinite(error) or not math.isfinite(error_dot):
            return 0.0
        p_term = self.p * error
        self.i_error += dt * error
        if self.antiwindup and self.i != 0.0:
            self.i_error = clamp(self.i_error, self.i_min / abs(self.i), self.i_max / abs(self.i))
        i_term = self.i * self.i_error
        if not self.antiwindup:
            i_term = clamp(i_term, self.i_min, self.i_max)
        self.command = p_term + i_term + self.d * self.d_error
        return self.command

    def state(self):
        return dict(p=self.p, i=self.i, d=self.d, i_clamp=self.i_max, antiwindup=self.antiwindup)


def _number(value, name):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ControllerError('Parameter %s is %r, not a finite number' % (name, value))
    return float(value)


@dataclass
class HardwareJoint:
    name: str
    index: int                     # in the articulation's arrays
    interface: str                 # effort | position | velocity
    model: object                  # flatsim.loading.ros_control.JointModel
    command: float = 0.0
    previous_command: float = float('nan')


class RobotHW:
    """DefaultRobotHWSim: the joints that transmissions name, over an Articulation."""

    def __init__(self, articulation, transmissions):
        self.articulation = articulation
        self.joints: Dict[str, HardwareJoint] = {}
        for transmission in transmissions:
            if transmission.joint in articulation.joints and transmission.joint not in self.joints:
                index = articulation.index(transmission.joint)
                self.joints[transmission.joint] = HardwareJoint(
                    transmission.joint, index, transmission.interface, articulation.models[index])
        self.names = sorted(self.joints)

    def handle(self, joint, interface):
        """The joint's command handle on an interface, or ros_control's error for a missing one."""
        hardware_joint = self.joints.get(joint)
        if hardware_joint is None or hardware_joint.interface != interface:
            raise ControllerError("Could not find resource '%s' in '%s'."
                                  % (joint, INTERFACE_NAMES[interface]))
        return hardware_joint

    def position(self, joint):
        return float(self.articulation.position[self.joints[joint].index])

    def velocity(self, joint):
        return float(self.articulation.velocity[self.joints[joint].index])

    def effort(self, joint):
        return float(self.articulation.effort[self.joints[joint].index])

    def write(self, dt):
        """Commands through the limit handles into efforts and targets; returns the efforts."""
        articulation = self.articulation
        effort = np.zeros(len(articulation.joints))
        for joint in self.joints.values():
            limits, soft = joint.model.limits, joint.model.soft_limits
            position = articulation.position[joint.index]
            velocity = articulation.velocity[joint.index]
            if joint.interface == 'effort':
                effort[joint.index] = _effort_limited(joint.command, limits, soft, position, velocity)
            elif joint.interface == 'position':
                articulation.position_target[joint.index] = self._position_limited(joint, dt)
            else:
                command = joint.command
                if limits.velocity is not None and math.isfinite(command):
                    command = clamp(command, -limits.velocity, limits.velocity)
                articulation.velocity_target[joint.index] = command if math.isfinite(command) else 0.0
        return effort

    def _position_limited(self, joint, dt):
        """PositionJointSaturationHandle: within the position limits, and at most velocity * dt a step."""
        limits = joint.model.limits
        if not math.isfinite(joint.previous_command):
            joint.previous_command = self.articulation.position[joint.index]
        command = joint.command if math.isfinite(joint.command) else joint.previous_command
        low = limits.lower if limits.lower is not None else -math.inf
        high = limits.upper if limits.upper is not None else math.inf
        if limits.velocity is not None:
            low = max(joint.previous_command - limits.velocity * dt, low)
            high = min(joint.previous_command + limits.velocity * dt, high)
        command = clamp(command, low, high)
        joint.previous_command = command
        return command


def _effort_limited(command, limits, soft, position, velocity):
    """EffortJointSoftLimitsHandle when there are soft limits, else EffortJointSaturationHandle."""
    if not math.isfinite(command):
        return command
    max_effort = limits.effort if limits.effort is not None else math.inf
    if soft is not None and limits.velocity is not None and limits.effort is not None:
        max_velocity = limits.velocity
        if limits.lower is not None:
            soft_min_vel = clamp(-soft.k_position * (position - soft.lower), -max_velocity, max_velocity)
            soft_max_vel = clamp(-soft.k_position * (position - soft.upper), -max_velocity, max_velocity)
        else:
            soft_min_vel, soft_max_vel = -max_velocity, max_velocity
        soft_min_eff = clamp(-soft.k_velocity * (velocity - soft_min_vel), -max_effort, max_effort)
        soft_max_eff = clamp(-soft.k_velocity * (velocity - soft_max_vel), -max_effort, max_effort)
        return clamp(command, soft_min_eff, soft_max_eff)
    return clamp(command, -max_effort, max_effort)


class Controller:
    """controller_interface::Controller: init from parameters, then starting/update/stopping."""

    interface = None               # the hardware interface it claims joints on

    def __init__(self, name, params, hw, namespace):
        self.name = name
        self.namespace = namespace  # the controller's parameter and topic namespace
        self.hw = hw
        self.state = 'initialized'
        self.outbox = []           # (topic relative to self.namespace or root, fields) to publish
        self.claimed = []

    def commands(self):
        """(topic relative to the controller namespace, callback taking a float) it subscribes to."""
        return []

    def starting(self, time):
        pass

    def update(self, time, period):
        pass

    def stopping(self, time):
        pass


class _SingleJoint(Controller):
    def __init__(self, name, params, hw, namespace):
        super().__init__(name, params, hw, namespace)
        joint = params.get('joint')
        if not isinstance(joint, str):
            raise ControllerError('No joint given (namespace: %s)' % namespace)
        self.joint = hw.handle(joint, self.interface)
        self.claimed = [joint]
        self.loop_count = 0
        self.command = 0.0

    def commands(self):
        return [('command', self.set_command)]

    def set_command(self, value):
        self.command = float(value)

    @staticmethod
    def untrackable(value):
        """Why this command gives no effort, or None when it is used."""
        return None if math.isfinite(value) else 'is not a finite number'


# The largest position target (rad or m) a position controller tracks. Beyond it a double
# cannot tell one turn from the next, so the error would no longer depend on where the joint
# is and a continuous joint would spin without end; such a target is taken as a NaN one is.
MAX_TRACKED_TARGET = 1e6


class JointPositionController(_SingleJoint):
    """effort_controllers/JointPositionController: PID from position error to effort."""

    interface = 'effort'

    @staticmethod
    def untrackable(value):
        """Why this command gives no effort, or None when it is tracked."""
        if not math.isfinite(value):
            return 'is not a finite number'
        if abs(value) > MAX_TRACKED_TARGET:
            return 'is too large to track (the limit is %g either way)' % MAX_TRACKED_TARGET
        return None

    def __init__(self, name, params, hw, namespace):
        super().__init__(name, params, hw, namespace)
        self.pid = Pid(params.get('pid'), namespace + '/pid')
        self.urdf = self.joint.model

    def _within_limits(self, position):
        limits = self.urdf.limits
        if self.urdf.kind in ('revolute', 'prismatic') and limits.lower is not None:
            return clamp(position, limits.lower, limits.upper)
        return position

    def starting(self, time):
        self.command = self._within_limits(self.hw.position(self.joint.name))
        self.pid.reset()

    def update(self, time, period):
        target = self._within_limits(self.command) if math.isfinite(self.command) else self.command
        if self.untrackable(target):
            target = float('nan')
        current = self.hw.position(self.joint.name)
        if self.urdf.kind == 'continuous':
            error = shortest_angular_distance(current, target) if math.isfinite(target) else target
        elif self.urdf.kind == 'revolute':
            error = _revolute_error(current, target, self.urdf.limits)
        else:
            error = target - current
        effort = self.pid.compute(error, period)
        self.joint.command = effort
        self._publish_state(time, period, target, current, self.hw.velocity(self.joint.name),
                            error, effort)

    def _publish_state(self, time, period, set_point, value, value_dot, error, command):
        if self.loop_count % STATE_DECIMATION == 0:
            self.outbox.append(('state', dict(stamp=time, set_point=set_point, process_value=value,
                                              process_value_dot=value_dot, error=error,
                                              time_step=period, command=command,
                                              **self.pid.state())))
        self.loop_count += 1


def _revolute_error(current, target, limits):
    """angles::shortest_angular_distance_with_large_limits, for targets within the limits."""
    if not math.isfinite(target):
        return target
    delta = shortest_angular_distance(current, target)
    if limits.lower is None or limits.upper - limits.lower >= 2.0 * math.pi:
        return delta
    # The short way must not cross a limit; otherwise go the long way round.
    end = current + delta
    if end < limits.lower or end > limits.upper:
        return delta - math.copysign(2.0 * math.pi, delta)
    return delta


class EffortJointVelocityController(JointPositionController):
    """effort_controllers/JointVelocityController: PID from velocity error to effort."""

    untrackable = staticmethod(_SingleJoint.untrackable)

    def starting(self, time):
        self.command = 0.0
        self.pid.reset()

    def update(self, time, period):
        velocity = self.hw.velocity(self.joint.name)
        error = self.command - velocity
        effort = self.pid.compute(error, period)
        self.joint.command = effort
        self._publish_state(time, period, self.command, velocity, 0.0, error, effort)


class ForwardController(_SingleJoint):
    """forward_command_controller: the command goes to the joint as it is."""

    def starting(self, time):
        # position_controllers start at the current position; the others at zero.
        self.command = self.hw.position(self.joint.name) if self.interface == 'position' else 0.0

    def update(self, time, period):
        self.joint.command = self.command


class EffortForward(ForwardController):
    interface = 'effort'


class PositionForward(ForwardController):
    interface = 'position'


class VelocityForward(ForwardController):
    interface = 'velocity'


class JointStateController(Controller):
    """joint_state_controller/JointStateController: joint_states at publish_rate."""

    interface = 'state'

    def __init__(self, name, params, hw, namespace):
        super().__init__(name, params, hw, namespace)
        if 'publish_rate' not in params:
            raise ControllerError("Parameter 'publish_rate' not set")
        self.publish_rate = _number(params['publish_rate'], namespace + '/publish_rate')
        self.last_publish = 0.0

    def starting(self, time):
        self.last_publish = time

    def update(self, time, period):
        if self.publish_rate > 0.0 and self.last_publish + 1.0 / self.publish_rate < time:
            self.last_publish += 1.0 / self.publish_rate
            names = self.hw.names
            self.outbox.append(('/joint_states', dict(
                stamp=time, name=list(names), position=[self.hw.position(j) for j in names],
                velocity=[self.hw.velocity(j) for j in names],
                effort=[self.hw.effort(j) for j in names])))


class SpeedLimiter:
    """diff_drive_controller's SpeedLimiter: jerk, then acceleration, then velocity limits."""

    def __init__(self, params, prefix, namespace):
        def flag(key):
            return bool(params.get('%s/has_%s_limits' % (prefix, key), False))

        def value(key, default):
            return _number(params.get('%s/%s' % (prefix, key), default),
                           '%s/%s/%s' % (namespace, prefix, key))
        params = _flatten(params)
        self.has_velocity, self.has_acceleration, self.has_jerk = (
            flag('velocity'), flag('acceleration'), flag('jerk'))
        self.max_velocity = value('max_velocity', 0.0)
        self.min_velocity = value('min_velocity', -self.max_velocity)
        self.max_acceleration = value('max_acceleration', 0.0)
        self.min_acceleration = value('min_acceleration', -self.max_acceleration)
        self.max_jerk = value('max_jerk', 0.0)
        self.min_jerk = value('min_jerk', -self.max_jerk)

    def limit(self, v, v0, v1, dt):
        if self.has_jerk and dt > 0.0:
            dv, dv0, dt2 = v - v0, v0 - v1, 2.0 * dt * dt
            v = v0 + dv0 + clamp(dv - dv0, self.min_jerk * dt2, self.max_jerk * dt2)
        if self.has_acceleration:
            v = v0 + clamp(v - v0, self.min_acceleration * dt, self.max_acceleration * dt)
        if self.has_velocity:
            v = clamp(v, self.min_velocity, self.max_velocity)
        return v


def _flatten(params, prefix=''):
    """{'linear': {'x': {'max_velocity': 1}}} -> {'linear/x/max_velocity': 1}, as getParam sees it."""
    flat = {}
    for key, value in params.items():
        name = '%s%s' % (prefix, key)
        if isinstance(value, dict):
            flat.update(_flatten(value, name + '/'))
        else:
            flat[name] = value
    return flat


class WheelOdometry:
    """diff_drive_controller's Odometry: dead reckoning from the wheel positions."""

    def __init__(self, window):
        self.window = max(1, int(window))
        self.reset(0.0)

    def reset(self, time):
        self.timestamp = time
        self.x = self.y = self.heading = 0.0
        self.linear = self.angular = 0.0
        self.left_old = self.right_old = None
        self.linear_samples, self.angular_samples = [], []

    def integrate(self, linear, angular):
        if abs(angular) < 1e-6:
            direction = self.heading + angular * 0.5      # second-order Runge-Kutta
            self.x += linear * math.cos(direction)
            self.y += linear * math.sin(direction)
            self.heading += angular
        else:
            heading_old = self.heading
            radius = linear / angular
            self.heading += angular
            self.x += radius * (math.sin(self.heading) - math.sin(heading_old))
            self.y += -radius * (math.cos(self.heading) - math.cos(heading_old))

    def update(self, left_pos, right_pos, time, separation, left_radius, right_radius):
        left, right = left_pos * left_radius, right_pos * right_radius
        if self.left_old is None:
            self.left_old, self.right_old = left, right
        left_delta, right_delta = left - self.left_old, right - self.right_old
        self.left_old, self.right_old = left, right
        linear = (right_delta + left_delta) * 0.5
        angular = (right_delta - left_delta) / separation
        self.integrate(linear, angular)
        dt = time - self.timestamp
        if dt < 0.0001:
            return
        self.timestamp = time
        self._average(linear / dt, angular / dt)

    def update_open_loop(self, linear, angular, time):
        dt = time - self.timestamp
        self.timestamp = time
        self.integrate(linear * dt, angular * dt)
        self.linear, self.angular = linear, angular

    def _average(self, linear, angular):
        self.linear_samples = (self.linear_samples + [linear])[-self.window:]
        self.angular_samples = (self.angular_samples + [angular])[-self.window:]
        self.linear = sum(self.linear_samples) / len(self.linear_samples)
        self.angular = sum(self.angular_samples) / len(self.angular_samples)


class DiffDriveController(Controller):
    """diff_drive_controller/DiffDriveController (ros_controllers, noetic).

    Subscribes to <controller>/cmd_vel (geometry_msgs/Twist) and sets the
    wheel joints' velocities to (linear -+ angular * separation / 2) / radius,
    with separation and radius from its parameters or, as the controller does,
    from the URDF (the distance between the first left and right wheel joints'
    origins; the left wheel link's cylinder or sphere collision). Publishes
    <controller>/odom and, with enable_odom_tf, odom -> base on /tf, dead
    reckoned from the wheel joints' positions.
    """

    interface = 'velocity'
    command_type = 'twist'

    def __init__(self, name, params, hw, namespace):
        super().__init__(name, params, hw, namespace)
        self.left = self._wheel_names(params, 'left_wheel')
        self.right = self._wheel_names(params, 'right_wheel')
        if len(self.left) != len(self.right):
            raise ControllerError('#left wheels (%d) != #right wheels (%d).'
                                  % (len(self.left), len(self.right)))
        self.publish_rate = _number(params.get('publish_rate', 50.0), namespace + '/publish_rate')
        self.open_loop = bool(params.get('open_loop', False))
        self.separation_multiplier = _number(params.get('wheel_separation_multiplier', 1.0),
                                             namespace + '/wheel_separation_multiplier')
        radius_multiplier = _number(params.get('wheel_radius_multiplier', 1.0),
                                    namespace + '/wheel_radius_multiplier')
        self.left_radius_multiplier = _number(params.get('left_wheel_radius_multiplier', radius_multiplier),
                                              namespace + '/left_wheel_radius_multiplier')
        self.right_radius_multiplier = _number(params.get('right_wheel_radius_multiplier', radius_multiplier),
                                               namespace + '/right_wheel_radius_multiplier')
        self.odometry = WheelOdometry(params.get('velocity_rolling_window_size', 10))
        self.cmd_vel_timeout = _number(params.get('cmd_vel_timeout', 0.5), namespace + '/cmd_vel_timeout')
        self.base_frame_id = str(params.get('base_frame_id', 'base_link'))
        self.odom_frame_id = str(params.get('odom_frame_id', 'odom'))
        self.enable_odom_tf = bool(params.get('enable_odom_tf', True))
        self.pose_covariance = self._diagonal(params, 'pose_covariance_diagonal')
        self.twist_covariance = self._diagonal(params, 'twist_covariance_diagonal')
        self.linear_limiter = SpeedLimiter(params, 'linear/x', namespace)
        self.angular_limiter = SpeedLimiter(params, 'angular/z', namespace)
        self.separation = params.get('wheel_separation')
        self.radius = params.get('wheel_radius')
        if self.separation is None or self.radius is None:
            self._from_urdf()
        self.separation = _number(self.separation, namespace + '/wheel_separation')
        self.radius = _number(self.radius, namespace + '/wheel_radius')
        self.joints = [hw.handle(joint, 'velocity') for joint in self.left + self.right]
        self.claimed = self.left + self.right
        self.command = (0.0, 0.0, -math.inf)      # linear, angular, stamp (sim time)
        self.last0 = self.last1 = (0.0, 0.0)
        self.last_publish = 0.0

    @staticmethod
    def _wheel_names(params, key):
        names = params.get(key)
        if isinstance(names, str):
            return [names]
        if isinstance(names, list) and names and all(isinstance(n, str) for n in names):
            return list(names)
        if isinstance(names, list) and not names:
            raise ControllerError("Wheel param '%s' is an empty list" % key)
        raise ControllerError("Couldn't retrieve wheel param '%s'." % key)

    @staticmethod
    def _diagonal(params, key):
        values = params.get(key)
        if isinstance(values, list) and len(values) == 6:
            try:
                return [float(v) for v in values]
            except (TypeError, ValueError):
                pass
        return [0.0] * 6

    def _from_urdf(self):
        spec = getattr(self.hw, 'spec', None)
        if spec is None:
            raise ControllerError('Could not read the robot description to look up the wheels')
        left, right = spec.joints.get(self.left[0]), spec.joints.get(self.right[0])
        for name, joint in ((self.left[0], left), (self.right[0], right)):
            if joint is None:
                raise ControllerError('%s couldn\'t be retrieved from model description' % name)
        if self.separation is None:
            self.separation = math.dist((left.origin.x, left.origin.y, left.origin.z),
                                        (right.origin.x, right.origin.y, right.origin.z))
        if self.radius is None:
            link = spec.links[left.child]
            round_shapes = [size[0] for kind, _, size in link.collisions[:1]
                            if kind in ('cylinder', 'sphere')]
            if not round_shapes:
                raise ControllerError('Wheel link %s is NOT modeled as a cylinder or sphere!' % link.name)
            self.radius = round_shapes[0]

    def commands(self):
        return [('cmd_vel', self.set_twist)]

    def set_twist(self, linear, angular, stamp):
        if not (math.isfinite(linear) and math.isfinite(angular)):
            return
        self.command = (float(linear), float(angular), float(stamp))

    @staticmethod
    def untrackable(value):
        return None

    def starting(self, time):
        for joint in self.joints:
            joint.command = 0.0
        self.last_publish = time
        self.odometry.reset(time)

    def stopping(self, time):
        for joint in self.joints:
            joint.command = 0.0

    def update(self, time, period):
        separation = self.separation_multiplier * self.separation
        left_radius = self.left_radius_multiplier * self.radius
        right_radius = self.right_radius_multiplier * self.radius
        if self.open_loop:
            self.odometry.update_open_loop(self.last0[0], self.last0[1], time)
        else:
            count = len(self.left)
            left = sum(self.hw.position(j) for j in self.left) / count
            right = sum(self.hw.position(j) for j in self.right) / count
            if math.isnan(left) or math.isnan(right):
                return
            self.odometry.update(left, right, time, separation, left_radius, right_radius)
        if self.last_publish + 1.0 / self.publish_rate < time:
            self.last_publish += 1.0 / self.publish_rate
            odometry = self.odometry
            self.outbox.append(('odom', dict(
                stamp=time, frame_id=self.odom_frame_id, child_frame_id=self.base_frame_id,
                x=odometry.x, y=odometry.y, yaw=odometry.heading, linear=odometry.linear,
                angular=odometry.angular, pose_covariance=self.pose_covariance,
                twist_covariance=self.twist_covariance)))
            if self.enable_odom_tf:
                self.outbox.append(('/tf', dict(stamp=time, frame_id=self.odom_frame_id,
                                                child_frame_id=self.base_frame_id, x=odometry.x,
                                                y=odometry.y, yaw=odometry.heading)))
        linear, angular, stamp = self.command
        if time - stamp > self.cmd_vel_timeout:
            linear = angular = 0.0
        linear = self.linear_limiter.limit(linear, self.last0[0], self.last1[0], period)
        angular = self.angular_limiter.limit(angular, self.last0[1], self.last1[1], period)
        self.last1, self.last0 = self.last0, (linear, angular)
        left_speed = (linear - angular * separation / 2.0) / left_radius
        right_speed = (linear + angular * separation / 2.0) / right_radius
        for joint in self.joints:
            joint.command = left_speed if joint.name in self.left else right_speed


CONTROLLER_TYPES = {
    'effort_controllers/JointPositionController': JointPositionController,
    'effort_controllers/JointVelocityController': EffortJointVelocityController,
    'effort_controllers/JointEffortController': EffortForward,
    'position_controllers/JointPositionController': PositionForward,
    'velocity_controllers/JointVelocityController': VelocityForward,
    'joint_state_controller/JointStateController': JointStateController,
    'diff_drive_controller/DiffDriveController': DiffDriveController,
}


@dataclass
class ControllerManager:
    """controller_manager::ControllerManager over one RobotHW (all calls under one lock)."""
    hw: RobotHW
    namespace: str                             # the robot namespace (root_nh)
    controllers: Dict[str, Controller] = field(default_factory=dict)
    types: Dict[str, str] = field(default_factory=dict)
    errors: List[str] = field(default_factory=list)

    def load(self, name, params):
        """Load a controller from its parameters (None if there are none); False and errors on failure."""
        self.errors = []
        if name in self.controllers:
            return self._fail("A controller named '%s' was already loaded inside the controller "
                              "manager" % logged_name(name))
        namespace = '%s/%s' % (self.namespace.rstrip('/'), name)
        if not isinstance(params, dict) or not isinstance(params.get('type'), str):
            return self._fail("Could not load controller '%s' because the type was not specified. "
                              "Did you load the controller configuration on the parameter server "
                              "(namespace: '%s')?" % (logged_name(name), logged_name(namespace)))
        controller_type = params['type']
        cls = CONTROLLER_TYPES.get(controller_type)
        if cls is None:
            return self._fail("Could not load controller '%s' because controller type '%s' does "
                              "not exist." % (logged_name(name), controller_type),
                              "Use 'rosservice call controller_manager/list_controller_types' to "
                              "get the available types")
        try:
            controller = cls(name, params, self.hw, namespace)
        except ControllerError as error:
            return self._fail("Exception thrown while initializing controller '%s'.\n%s"
                              % (logged_name(name), error),
                              "Initializing controller '%s' failed" % logged_name(name))
        self.controllers[name] = controller
        self.types[name] = controller_type
        return True

    def unload(self, name):
        self.errors = []
        controller = self.controllers.get(name)
        if controller is None:
            return self._fail("Could not unload controller with name '%s' because no controller "
                              "with this name exists" % logged_name(name))
        if controller.state == 'running':
            return self._fail("Could not unload controller with name '%s' because it is still "
                              "running" % logged_name(name))
        del self.controllers[name]
        del self.types[name]
        return True

    def switch(self, start, stop, strictness, time):
        self.errors = []
        if strictness == 0:
            self.errors.append('Controller Manager: To switch controllers you need to specify a '
                               'strictness level of controller_manager_msgs::SwitchController::'
                               'STRICT (2) or ::BEST_EFFORT (1). Defaulting to ::BEST_EFFORT.')
            strictness = BEST_EFFORT
        for names, verb in ((stop, 'stop'), (start, 'start')):
            for name in names:
                if name not in self.controllers and strictness == STRICT:
                    return self._fail("Could not %s controller with name '%s' because no "
                                      "controller with this name exists" % (verb, logged_name(name)))
        stopping = [n for n in stop if n in self.controllers]
        starting = [n for n in start if n in self.controllers]
        for name in stopping:
            if self.controllers[name].state != 'running' and strictness == STRICT:
                return self._fail("Could not stop controller '%s' since it is not running" % name)
        for name in starting:
            if self.controllers[name].state == 'running' and name not in stopping \
                    and strictness == STRICT:
                return self._fail("Controller '%s' is already running" % name)
        stopping = [n for n in stopping if self.controllers[n].state == 'running']
        starting = [n for n in starting if n in stopping or self.controllers[n].state != 'running']
        running = [n for n, c in self.controllers.items()
                   if (c.state == 'running' and n not in stopping) or n in starting]
        claims = {}
        for name in running:
            controller = self.controllers[name]
            for joint in controller.claimed:
                if joint in claims:
                    return self._fail('Resource conflict on [%s].  Controllers = [%s, %s]'
                                      % (joint, claims[joint], name),
                                      'Could not switch controllers, due to resource conflict')
                claims[joint] = name
        for name in stopping:
            self.controllers[name].stopping(time)
            self.controllers[name].state = 'stopped'
        for name in starting:
            self.controllers[name].starting(time)
            self.controllers[name].state = 'running'
        return True

    def update(self, time, period):
        for controller in self.controllers.values():
            if controller.state == 'running':
                controller.update(time, period)

    def listing(self):
        """(name, state, type, [(interface, resources)]) for each loaded controller."""
        rows = []
        for name, controller in self.controllers.items():
            interface = STATE_INTERFACE if controller.interface == 'state' \
                else INTERFACE_NAMES[controller.interface]
            rows.append((name, controller.state, self.types[name],
                         [(interface, list(controller.claimed))]))
        return rows

    def _fail(self, *messages):
        self.errors.extend(messages)
        return False
