"""What an articulated robot's URDF gives gazebo_ros_control: joints, inertials, transmissions.

Read as Gazebo and ros_control read them (noetic):
- <joint><limit lower upper effort velocity/>, <dynamics damping friction/> and
  <safety_controller k_position k_velocity soft_lower_limit soft_upper_limit/>
  (joint_limits_interface's getJointLimits / getSoftJointLimits: a continuous
  joint has no position limits; a safety controller gives soft limits);
- each link's <inertial> (mass, origin, inertia tensor);
- <transmission> blocks (transmission_interface's parser): one joint each, with
  its <hardwareInterface> inside <joint> (or, deprecated, inside <actuator>);
- the <plugin filename="libgazebo_ros_control.so"> tag: <robotNamespace>
  (default: the model name), <robotParam> (robot_description), <controlPeriod>
  (default: the physics step) and <robotSimType> (DefaultRobotHWSim only).
Problems that gazebo_ros_control only warns about are kept as warnings; the
robot loads without the offending joint, as it does in Gazebo.
"""
import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional

import numpy as np

from flatsim.pose import Pose

ROS_CONTROL_PLUGIN = 'libgazebo_ros_control.so'
DEFAULT_SIM_TYPE = 'gazebo_ros_control/DefaultRobotHWSim'
INTERFACES = {'EffortJointInterface': 'effort', 'PositionJointInterface': 'position',
              'VelocityJointInterface': 'velocity'}
MOVABLE_JOINT_TYPES = ('revolute', 'continuous', 'prismatic')


@dataclass
class JointLimits:
    """joint_limits_interface::JointLimits as read from URDF (None: that limit is absent)."""
    lower: Optional[float] = None              # rad or m; None for continuous joints
    upper: Optional[float] = None
    velocity: Optional[float] = None           # rad/s or m/s
    effort: Optional[float] = None             # N*m or N


@dataclass
class SoftLimits:
    """From <safety_controller>: the soft-limit handles ros_control puts over the command."""
    k_position: float = 0.0
    k_velocity: float = 0.0
    lower: float = 0.0
    upper: float = 0.0


@dataclass
class JointModel:
    name: str
    kind: str                                  # revolute | continuous | prismatic
    limits: JointLimits = field(default_factory=JointLimits)
    soft_limits: Optional[SoftLimits] = None
    damping: float = 0.0                       # N*m*s/rad or N*s/m
    friction: float = 0.0                      # N*m or N


@dataclass
class Inertial:
    mass: float = 0.0
    origin: Pose = field(default_factory=Pose)
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))  # about the origin, in its axes


@dataclass
class Transmission:
    name: str
    joint: str
    interface: str                             # effort | position | velocity
    reduction: float = 1.0


@dataclass
class RosControlConfig:
    robot_namespace: str = ''
    robot_param: str = 'robot_description'
    control_period: float = 0.0                # s; 0 means every physics step
    transmissions: List[Transmission] = field(default_factory=list)
    warnings: List[str] = field(default_factory=list)
    # Velocity-interface joints that may be wheels (flatsim.loading.config.Wheel), left to the
    # simulation to keep those that reach the floor.
    wheels: list = field(default_factory=list)


@dataclass
class Articulation:
    """The movable joints and every link's inertial, for flatsim.world.articulation."""
    joints: Dict[str, JointModel] = field(default_factory=dict)
    inertials: Dict[str, Inertial] = field(default_factory=dict)


def read_articulation(reader, spec):
    """Joint limits and dynamics and the link inertials of a URDF (reader: the URDF reader)."""
    articulation = Articulation()
    for element in reader.root.findall('link'):
        inertial = element.find('inertial')
        if inertial is not None:
            articulation.inertials[element.get('name')] = _read_inertial(
                reader, inertial, 'link %s inertial' % element.get('name'))
    for element in reader.root.findall('joint'):
        joint = spec.joints.get(element.get('name'))
        if joint is None or joint.kind not in MOVABLE_JOINT_TYPES:
            continue
        articulation.joints[joint.name] = _read_joint(reader, element, joint)
    return articulation


def _read_inertial(reader, element, what):
    mass_element = element.find('mass')
    mass = 0.0 if mass_element is None else reader.number(mass_element.get('value'),
                                                           '%s mass' % what, mass_element)
    if mass < 0:
        raise reader.error('%s mass %g is negative' % (what, mass), mass_element)
    inertia = np.zeros((3, 3))
    tensor = element.find('inertia')
    if tensor is not None:
        values = {key: reader.number(tensor.get(key, '0'), '%s inertia %s' % (what, key), tensor)
                  for key in ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')}
        inertia = np.array([[values['ixx'], values['ixy'], values['ixz']],
                            [values['ixy'], values['iyy'], values['iyz']],
                            [values['ixz'], values['iyz'], values['izz']]])
        if np.linalg.eigvalsh(inertia).min() < -1e-12:
            raise reader.error('%s inertia is not positive semi-definite' % what, tensor)
    return Inertial(mass, reader.origin(element, what), inertia)


def _read_joint(reader, element, joint):
    what = 'joint %s' % joint.name
    model = JointModel(joint.name, joint.kind)
    limit = element.find('limit')
    if limit is None and joint.kind in ('revolute', 'prismatic'):
        raise reader.error('%s is %s and needs a <limit>, as URDF requires' % (what, joint.kind),
                           element)
    if limit is not None:
        def value(key):
            text = limit.get(key)
            return None if text is None else reader.number(text, '%s limit %s' % (what, key), limit)
        model.limits.effort = value('effort')
        model.limits.velocity = value('velocity')
        if joint.kind != 'continuous':
            model.limits.lower = value('lower') or 0.0
            model.limits.upper = value('upper') or 0.0
            if model.limits.upper < model.limits.lower:
                raise reader.error('%s limit upper %g is below lower %g'
                                   % (what, model.limits.upper, model.limits.lower), limit)
        for key in ('effort', 'velocity'):
            if getattr(model.limits, key) is not None and getattr(model.limits, key) < 0:
                raise reader.error('%s limit %s is negative' % (what, key), limit)
    dynamics = element.find('dynamics')
    if dynamics is not None:
        model.damping = reader.number(dynamics.get('damping', '0'), '%s damping' % what, dynamics)
        model.friction = reader.number(dynamics.get('friction', '0'), '%s friction' % what, dynamics)
        if model.damping < 0 or model.friction < 0:
            raise reader.error('%s dynamics damping and friction must not be negative' % what,
                               dynamics)
    safety = element.find('safety_controller')
    if safety is not None:
        def safety_value(key):
            return reader.number(safety.get(key, '0'), '%s safety_controller %s' % (what, key), safety)
        model.soft_limits = SoftLimits(safety_value('k_position'), safety_value('k_velocity'),
                                       safety_value('soft_lower_limit'),
                                       safety_value('soft_upper_limit'))
    return model


def read_ros_control_plugin(reader, spec, plugin):
    """The gazebo_ros_control plugin tag and the robot's transmissions."""
    config = RosControlConfig()
    namespace = plugin.find('robotNamespace')
    config.robot_namespace = ((namespace.text or '').strip() if namespace is not None else '') \
        or reader.robot_namespace or spec.name
    config.robot_param = reader.child_text(plugin, 'robotParam', 'robot_description') \
        or 'robot_description'
    config.control_period = reader.child_number(plugin, 'controlPeriod', 0.0,
                                                'gazebo_ros_control <controlPeriod>')
    if not (config.control_period >= 0 and math.isfinite(config.control_period)):
        raise reader.error('gazebo_ros_control <controlPeriod> %r is not a time in seconds'
                           % config.control_period, plugin)
    sim_type = reader.child_text(plugin, 'robotSimType', DEFAULT_SIM_TYPE)
    if sim_type != DEFAULT_SIM_TYPE:
        config.warnings.append('<robotSimType> %s is not provided; flatsim simulates %s'
                               % (sim_type, DEFAULT_SIM_TYPE))
    for element in reader.root.findall('transmission'):
        transmission = _read_transmission(element, spec, config.warnings)
        if transmission is not None:
            config.transmissions.append(transmission)
    return config


def _read_transmission(element, spec, warnings):
    name = element.get('name', '')
    joints = element.findall('joint')
    if not joints:
        warnings.append('Transmission %s has no associated joints.' % name)
        return None
    if len(joints) > 1:
        warnings.append('Transmission %s has more than one joint. Currently the default robot '
                        'hardware simulation interface only supports one.' % name)
        return None
    joint_name = joints[0].get('name', '')
    interfaces = [(e.text or '').strip() for e in joints[0].findall('hardwareInterface')]
    actuator = element.find('actuator')
    if not interfaces and actuator is not None:
        interfaces = [(e.text or '').strip() for e in actuator.findall('hardwareInterface')]
        if interfaces:
            warnings.append('The <hardware_interface> element of tranmission %s should be nested '
                            'inside the <joint> element, not <actuator>.' % name)
    if not interfaces:
        warnings.append('Joint %s of transmission %s does not specify any hardware interface. '
                        'Not adding it to the robot hardware simulation.' % (joint_name, name))
        return None
    if len(interfaces) > 1:
        warnings.append('Joint %s of transmission %s specifies multiple hardware interfaces. '
                        'Using the first entry' % (joint_name, name))
    interface = interfaces[0]
    short = interface[len('hardware_interface/'):] if interface.startswith('hardware_interface/') \
        else interface
    if short not in INTERFACES:
        warnings.append("No matching hardware interface found for '%s' while loading interfaces "
                        "for %s; the joint is left out" % (interface, joint_name))
        return None
    joint = spec.joints.get(joint_name)
    if joint is None or joint.kind not in MOVABLE_JOINT_TYPES:
        warnings.append('This robot has a joint named "%s" which is not in the gazebo model.'
                        % joint_name if joint is None else
                        'Transmission %s names %s joint %s, which cannot move; left out'
                        % (name, joint.kind, joint_name))
        return None
    reduction = 1.0
    if actuator is not None and actuator.find('mechanicalReduction') is not None:
        try:
            reduction = float(actuator.find('mechanicalReduction').text)
        except (TypeError, ValueError):
            warnings.append('Transmission %s <mechanicalReduction> is not a number; 1 is used' % name)
    return Transmission(name, joint_name, INTERFACES[short], reduction)
