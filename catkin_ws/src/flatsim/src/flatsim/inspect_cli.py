"""flatsim inspect: print what flatsim will simulate from a world and a robot, and what it skipped.

  rosrun flatsim inspect --world my_robot/worlds/my.world --robot my_robot/urdf/my_robot.xacro
  rosrun flatsim inspect --robot robot.urdf        (a .urdf, or a .xacro expanded with xacro)

Exits 1 with a clear message when a file cannot be read at all.
"""
import argparse
import sys

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.world.sim import Simulation


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='inspect', description=__doc__.split('\n')[0])
    parser.add_argument('--world', help='SDF .world file')
    parser.add_argument('--robot', help='URDF or xacro file of the robot to spawn at the origin')
    parser.add_argument('--xacro-arg', action='append', default=[], metavar='NAME:=VALUE',
                        help='argument for xacro, e.g. drive:=skid')
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


def describe(sim, robot=None):
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
    if robot is not None:
        spec = robot.spec
        lines.append('robot %s: root link %s, %d links, mass %.2f kg, footprint %d points'
                     % (robot.name, spec.root_link, len(spec.links), spec.mass, len(spec.footprint)))
        drive = spec.drive
        if drive is None:
            lines.append('  drive: none (the robot stays where it is)')
        else:
            lines.append('  drive: %s on %s -> %s, tf %s -> %s%s, separation %.3f m, diameter %.3f m, %s'
                         % (drive.plugin, drive.command_topic, drive.odometry_topic,
                            drive.odometry_frame, drive.robot_base_frame,
                            '' if drive.publish_tf else ' (not published)',
                            drive.wheel_separation, drive.wheel_diameter, _fmt_rate(drive.update_rate)))
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
    except FlatsimError as error:
        print('inspect: %s' % error, file=sys.stderr)
        return 1
    print(describe(sim, robot))
    return 0
