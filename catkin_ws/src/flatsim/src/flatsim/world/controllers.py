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


CONTROLLER_TYPES = {
    'effort_controllers/JointPositionController': JointPositionController,
    'effort_controllers/JointVelocityController': EffortJointVelocityController,
    'effort_controllers/JointEffortController': EffortForward,
    'position_controllers/JointPositionController': PositionForward,
    'velocity_controllers/JointVelocityController': VelocityForward,
    'joint_state_controller/JointStateController': JointStateController,
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
