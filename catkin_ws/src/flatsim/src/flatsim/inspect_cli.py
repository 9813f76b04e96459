"""flatsim inspect: print what flatsim will simulate from a world and a robot, and what it skipped.

  rosrun flatsim inspect --world my_robot/worlds/my.world --robot my_robot/urdf/my_robot.xacro
  rosrun flatsim inspect --robot robot.urdf        (a .urdf, or a .xacro expanded with xacro)
  rosrun flatsim inspect --robot simple_arm/urdf/simple_arm.urdf.xacro \
                         --controllers simple_arm/config/controllers.yaml

For a robot that drives, it warns when its centre of mass (from the URDF's
inertials) lies outside the support polygon of its wheels and casters, or
within 2 cm of its edge: such a robot would tip over in Gazebo, while flatsim
keeps every robot upright.

For a robot with the gazebo_ros_control plugin it also lists the movable
joints (type, axis, limits), the plugin's namespace and the transmissions;
with --controllers (a YAML file loaded at the root namespace, as
`<rosparam file=... command="load"/>` does) it loads every controller found
under that namespace as the controller manager would, and shows its joint,
gains and topics, or the error the spawner would get.

Exits 1 with a clear message when a file cannot be read at all.
"""
import argparse
import math
import sys

import yaml

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.stability import assess
from flatsim.world.controllers import INTERFACE_NAMES, STATE_INTERFACE
from flatsim.world.sim import Simulation

JOINT_UNITS = {'prismatic': ('m', 'N', 'm/s')}
ANGULAR_UNITS = ('rad', 'N*m', 'rad/s')


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='inspect', description=__doc__.split('\n')[0])
    parser.add_argument('--world', help='SDF .world file')
    parser.add_argument('--robot', help='URDF or xacro file of the robot to spawn at the origin')
    parser.add_argument('--xacro-arg', action='append', default=[], metavar='NAME:=VALUE',
                        help='argument for xacro, e.g. drive:=skid')
    parser.add_argument('--controllers', action='append', default=[], metavar='YAML',
                        help='controller parameters to load for a ros_control robot (repeatable)')
    args = parser.parse_args(argv)
    if not args.world and not args.robot:
        parser.error('give --world, --robot or both')
    return args


def load_robot_file(path, xacro_args=()):
    mappings = dict(arg.split(':=', 1) for arg in xacro_args)
    if path.endswith('.urdf'):
        try:
            with open(path, encoding='utf-8') as handle:
                xml = handle.read()
        except OSError as error:
            raise FlatsimError('cannot read %s: %s' % (path, error.strerror)) from None
    else:
        xml = expand_xacro(path, mappings)
    return load_robot(xml, source=path)


def _fmt_rate(rate):
    return 'every step' if rate <= 0 else '%g Hz' % rate


def load_controller_files(paths):
    """[(path, parameters)] from controller YAML files; FlatsimError for one that cannot be read."""
    loaded = []
    for path in paths:
        try:
            with open(path, encoding='utf-8') as handle:
                params = yaml.safe_load(handle)
        except OSError as error:
            raise FlatsimError('cannot read %s: %s' % (path, error.strerror)) from None
        except yaml.YAMLError as error:
            raise FlatsimError('%s is not YAML: %s' % (path, error)) from None
        loaded.append((path, params))
    return loaded


def _fmt_number(value):
    return '%g' % value


def _fmt_limits(joint, model):
    length, force, speed = JOINT_UNITS.get(joint.kind, ANGULAR_UNITS)
    limits = model.limits
    parts = ['position %s..%s %s' % (_fmt_number(limits.lower), _fmt_number(limits.upper), length)
             if limits.lower is not None else 'no position limits']
    parts.append('effort %s %s' % (_fmt_number(limits.effort), force) if limits.effort is not None
                 else 'effort unlimited')
    parts.append('velocity %s %s' % (_fmt_number(limits.velocity), speed) if limits.velocity is not None
                 else 'velocity unlimited')
    if model.soft_limits is not None:
        soft = model.soft_limits
        parts.append('soft limits %s..%s %s (k_position %s, k_velocity %s)'
                     % (_fmt_number(soft.lower), _fmt_number(soft.upper), length,
                        _fmt_number(soft.k_position), _fmt_number(soft.k_velocity)))
    if model.damping or model.friction:
        parts.append('damping %s, friction %s' % (_fmt_number(model.damping), _fmt_number(model.friction)))
    return ', '.join(parts)


def describe_joints(spec):
    lines = ['  joints:']
    movable = spec.articulation.joints if spec.articulation is not None else {}
    for joint in spec.joints.values():
        if joint.name in movable:
            lines.append('    %s: %s, axis (%s), %s -> %s; %s'
                         % (joint.name, joint.kind, ', '.join(_fmt_number(a) for a in joint.axis),
                            joint.parent, joint.child,
                            _fmt_limits(joint, movable[joint.name])))
        else:
            lines.append('    %s: %s, %s -> %s' % (joint.name, joint.kind, joint.parent, joint.child))
    return lines


def describe_ros_control(robot, controller_files=()):
    """The gazebo_ros_control plugin, its transmissions, and the controllers the files define."""
    config = robot.spec.ros_control
    namespace = '/' + config.robot_namespace.strip('/')
    period = 'every physics step' if config.control_period <= 0 else '%g s' % config.control_period
    lines = ['  ros_control: libgazebo_ros_control.so, namespace %s, %s, control period %s; '
             'services %s/controller_manager/*' % (namespace, config.robot_param, period,
                                                   namespace.rstrip('/'))]
    lines.append('  transmissions:' if config.transmissions else
                 '  transmissions: none (no joint can take a controller)')
    for transmission in config.transmissions:
        lines.append('    %s: %s on %s, mechanical reduction %s'
                     % (transmission.name, transmission.joint,
                        INTERFACE_NAMES[transmission.interface].split('::')[1],
                        _fmt_number(transmission.reduction)))
    if not controller_files:
        lines.append('  controllers: loaded at run time from the parameters under %s '
                     '(give --controllers config/controllers.yaml to check them)' % namespace)
    for path, params in controller_files:
        lines.extend(_describe_controller_file(robot.control.manager, namespace, path, params))
    return lines


def _describe_controller_file(manager, namespace, path, params):
    found = params
    for segment in [s for s in namespace.split('/') if s]:
        found = found.get(segment) if isinstance(found, dict) else None
    if not isinstance(found, dict):
        top = ', '.join(sorted(params)) if isinstance(params, dict) else 'none'
        return ['  controllers in %s: nothing under %s (top-level keys: %s); loaded at the root '
                'namespace, it gives the spawner in %s no controllers' % (path, namespace, top, namespace)]
    lines = ['  controllers in %s, under %s:' % (path, namespace)]
    for name, controller_params in found.items():
        if not (isinstance(controller_params, dict) and 'type' in controller_params):
            continue
        if manager.load(name, controller_params):
            lines.append('    %s: %s' % (name, _describe_controller(
                manager.controllers[name], manager.types[name], namespace)))
            manager.unload(name)
        else:
            lines.append('    %s: cannot be loaded: %s'
                         % (name, ' '.join(error.replace('\n', ' ') for error in manager.errors)))
    if len(lines) == 1:
        lines.append('    none: no entry under %s has a type' % namespace)
    return lines


def _describe_controller(controller, controller_type, namespace):
    topic = '%s/%s' % (namespace.rstrip('/'), controller.name)
    if getattr(controller, 'command_type', None) == 'twist':
        return ('%s on %s / %s (VelocityJointInterface); %s/cmd_vel (geometry_msgs/Twist) -> '
                '%s/odom%s; separation %s m, radius %s m, cmd_vel_timeout %s s'
                % (controller_type, ', '.join(controller.left), ', '.join(controller.right), topic,
                   topic, ' and /tf %s -> %s' % (controller.odom_frame_id, controller.base_frame_id)
                   if controller.enable_odom_tf else '', _fmt_number(controller.separation),
                   _fmt_number(controller.radius), _fmt_number(controller.cmd_vel_timeout)))
    if controller.interface == 'state':
        return '%s, publish_rate %s Hz -> %s/joint_states (%s)' % (
            controller_type, _fmt_number(controller.publish_rate), namespace.rstrip('/'),
            STATE_INTERFACE.split('::')[1])
    text = '%s on %s (%s); %s/command (std_msgs/Float64)' % (
        controller_type, controller.joint.name, INTERFACE_NAMES[controller.interface].split('::')[1],
        topic)
    pid = getattr(controller, 'pid', None)
    if pid is not None:
        text += ' -> %s/state (control_msgs/JointControllerState); pid p %s, i %s, d %s' % (
            topic, _fmt_number(pid.p), _fmt_number(pid.i), _fmt_number(pid.d))
        if pid.i != 0.0 and pid.i_max == 0.0 and pid.i_min == 0.0 and not pid.antiwindup:
            text += ' (i has no effect without i_clamp)'
        elif pid.i_max or pid.i_min:
            text += ', i_clamp %s..%s' % (_fmt_number(pid.i_min), _fmt_number(pid.i_max))
    return text


def describe_robot(robot, controller_files=()):
    lines = []
    spec = robot.spec
    lines.append('robot %s%s: root link %s%s, %d links, mass %.2f kg, footprint %d points'
                 % (robot.name, ' (saved in the world file)' if robot.saved else '', spec.root_link,
                    ' (fixed to the world)' if spec.root_link == 'world' else '',
                    len(spec.links), spec.mass, len(spec.footprint)))
    if spec.drive is None and robot.drive is not None:
        lines.append('  drive: the ros_control velocity joints %s roll the robot on the floor; '
                     'nothing moves it until a controller commands them'
                     % ', '.join(wheel.joint for wheel in robot.drive.wheels))
        lines.extend(_describe_wheels(robot.drive.wheels))
    else:
        lines.extend(describe_drive(spec.drive))
    for slot in robot.sensors:
        cfg = slot.config
        if slot.kind == 'camera':
            lines.append('  camera %s on %s: %dx%d %s hfov %.3f, %s -> %s (+ %s), frame %s'
                         % (cfg.sensor_name, cfg.link, cfg.width, cfg.height, cfg.image_format,
                            cfg.hfov, _fmt_rate(cfg.update_rate), cfg.image_topic, cfg.info_topic,
                            cfg.frame_name))
        else:
            lines.append('  laser %s on %s: %d beams %.3f..%.3f rad, %.2f..%.1f m, noise %.3f, %s -> %s, frame %s'
                         % (cfg.sensor_name, cfg.link, cfg.samples, cfg.min_angle, cfg.max_angle,
                            cfg.range_min, cfg.range_max, cfg.noise_stddev, _fmt_rate(cfg.update_rate),
                            cfg.topic, cfg.frame_name))
    lines.extend(describe_stability(spec))
    if spec.articulation is not None and spec.articulation.joints:
        lines.extend(describe_joints(spec))
    if spec.ros_control is not None:
        lines.extend(describe_ros_control(robot, controller_files))
    return lines


def describe_drive(drive):
    """The drive plugin's topics and settings, and where its wheels really are."""
    if drive is None:
        return ['  drive: none (the robot stays where it is)']
    topics = '%s on %s -> %s, tf %s -> %s%s' % (
        drive.plugin, drive.command_topic, drive.odometry_topic, drive.odometry_frame,
        drive.robot_base_frame, '' if drive.publish_tf else ' (not published)')
    if drive.plugin == 'planar_move':
        return ['  drive: %s, odometry %s; sets the body velocity to linear.x, linear.y, angular.z'
                % (topics, _fmt_rate(drive.update_rate))]
    if drive.plugin == 'tricycle':
        lines = ['  drive: %s, actuated wheel diameter %.3f m, %s; linear.x is the wheel speed, '
                 'angular.z the steering angle'
                 % (topics, drive.wheel_diameter, _fmt_rate(drive.update_rate))]
        lines.append('    steering %s at (%.3f, %.3f)' % (drive.steering.joint, drive.steering.x,
                                                          drive.steering.y))
    else:
        lines = ['  drive: %s, separation %.3f m, diameter %.3f m, %s'
                 % (topics, drive.wheel_separation, drive.wheel_diameter, _fmt_rate(drive.update_rate))]
    return lines + _describe_wheels(list(drive.wheels) + list(drive.encoder_wheels))


def _describe_wheels(wheels):
    lines = []
    for wheel in wheels:
        # Which way a positive joint rate rolls the robot, in its own frame.
        heading = math.degrees(math.atan2(wheel.roll_y, wheel.roll_x)) + 0.0   # no "-0"
        lines.append('    wheel %s at (%.3f, %.3f), radius %.3f m, rolls towards %.0f deg'
                     % (wheel.joint, wheel.x, wheel.y, wheel.radius, heading))
    return lines


def describe_stability(spec):
    """Whether the robot would stand in Gazebo, which flatsim, keeping it upright, cannot show."""
    stability, why = assess(spec)
    if stability is None:
        return [] if spec.root_link == 'world' else ['  stability: not judged: %s' % why]
    return ['  %sstability: %s' % ('' if stability.stable else 'warning: ', stability.describe())]


def describe(sim, robot=None, controller_files=()):
    lines = []
    statics = [m for m in sim.models.values() if m.kind == 'static']
    balls = [m for m in sim.models.values() if m.kind == 'ball']
    lines.append('physics: step %.4f s, %d static colliders from %d static models'
                 % (sim.step_size, sim.physics.static_count(), len(statics)))
    lines.append('scene: %d shapes for the camera and lidar' % len(sim.scene))
    for ball in balls:
        pose = sim.model_pose(ball.name)
        prim = sim.scene.prim(ball.prim_ids[0])
        white = ' white (exactly 255,255,255 in the camera)' if prim.unlit_white else ''
        lines.append('ball %s: r=%.3f m at (%.2f, %.2f)%s' % (ball.name, prim.radius, pose.x, pose.y, white))
    for body in (m for m in sim.models.values() if m.kind == 'body'):
        pose = sim.model_pose(body.name)
        friction = getattr(body.source, 'friction', 1.0)
        lines.append('model %s: a body robots push, %.3g kg, friction mu %.3g (slides against %.3g N) '
                     'at (%.2f, %.2f)' % (body.name, body.handle.body.mass, friction,
                                          body.handle.constraints[0].max_force, pose.x, pose.y))
    for model in sim.models.values():
        for prim in model.ground:
            lines.append('ground: %s, its top %.3f m up: robots drive on it'
                         % (prim.name, prim.z_max))
    for each in sim.robots():
        lines.extend(describe_robot(each, controller_files if each is robot else ()))
    skipped = list(sim.skipped) + (list(robot.spec.skipped) if robot is not None else [])
    lines.append('skipped: %d' % len(skipped))
    lines.extend('  - %s' % item for item in skipped)
    return '\n'.join(lines)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        world = load_world(args.world) if args.world else None
        sim = Simulation(world)
        robot = None
        if args.robot:
            spec = load_robot_file(args.robot, args.xacro_arg)
            robot = sim.spawn_robot(spec.name, spec, Pose())
        controller_files = load_controller_files(args.controllers)
    except FlatsimError as error:
        print('inspect: %s' % error, file=sys.stderr)
        return 1
    if controller_files and (robot is None or robot.spec.ros_control is None):
        print('inspect: --controllers needs a --robot with the gazebo_ros_control plugin',
              file=sys.stderr)
        return 1
    print(describe(sim, robot, controller_files))
    return 0
