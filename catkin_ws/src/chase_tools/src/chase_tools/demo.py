"""chase_demo: the main job. A headless ball chase in flatsim, start to finish.

  rosrun chase_tools chase_demo [--robot diff|skid] [--timeout 60] [--port PORT] [--output out]

It starts a ROS master of its own, on a free port or on --port (an error if
that port is taken: it never joins a master that is already running), then
`my_robot world.launch` (no rviz) and `ball_chaser ball_chaser.launch` on it,
and stops them all at the end, master last, so nothing of the run is left.
It prints sim time and the distance to the ball as the robot drives, and stops
when the robot is within --reach of the ball or when --timeout seconds of sim
time have passed. Exit status 0 means it reached the ball.

The world runs in lockstep by default (flatsim waits after each camera frame
for the controller's command) and as fast as that allows: the chase, and the
sim time at which the robot reaches the ball, are the same on any machine and
under any load. --real-time runs it at a real-time factor of 1 without
lockstep, as the course does in Gazebo. SIGTERM and SIGHUP stop it as Ctrl-C
does, with every process it started.

While it runs, rosbag records the run into OUTPUT/chase.bag (the camera
throttled to --camera-rate Hz of sim time on /camera/rgb/image_throttled); at
the end chase_tools.report writes trajectory.png, first_sight.png and summary.md
next to it, whatever the outcome.
"""
import argparse
import os
import sys
import time

import rosgraph
import rospy
from gazebo_msgs.srv import GetModelState
from std_srvs.srv import Empty

from chase_tools import arguments, report
from chase_tools.chase_graph import (CAMERA_TOPIC, MODEL_STATES_TOPIC, ChaseWatch, chaser_ready, default_world_file,
                                     lockstep_ready, planar_gap, sim_service, wait_for_service)
from chase_tools.procs import (Launches, MasterError, PortTaken, ProcessGroup, cleanup_on_signals, free_port,
                               port_taken, wait_until)
from flatsim.errors import FlatsimError

REACH_M = report.REACH_M
THROTTLED_CAMERA_TOPIC = '/camera/rgb/image_throttled'
TAKEN_ADVICE = '; give another --port, or leave it out for a free one'
RECORDED_TOPICS = ('/odom', '/cmd_vel', '/scan', MODEL_STATES_TOPIC, '/clock',
                   THROTTLED_CAMERA_TOPIC)


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='chase_demo', description=__doc__.split('\n')[0])
    parser.add_argument('--robot', choices=['diff', 'skid'], default='diff', help='drive layout')
    parser.add_argument('--world', default='', help='SDF world (default: my_robot chase_house.world)')
    parser.add_argument('--timeout', type=arguments.positive, default=60.0,
                        help='sim seconds before giving up')
    parser.add_argument('--reach', type=arguments.positive, default=REACH_M,
                        help='distance from the robot base to the ball centre that counts as reached (m)')
    parser.add_argument('--ball', default='white_ball', help='name of the ball model')
    parser.add_argument('--port', type=arguments.port, default=None,
                        help='port of the demo\'s own ROS master (default: a free one); the demo '
                             'stops with an error if it is taken')
    # Lockstep by default: flatsim waits for process_image's answer to each frame,
    # so the chase is the same at any speed and on any load.
    parser.add_argument('--real-time', action='store_true',
                        help='run at real time without lockstep, as the course does in Gazebo')
    parser.add_argument('--real-time-factor', type=arguments.not_negative, default=None,
                        help='sim seconds per wall second (default: 0, as fast as lockstep allows; '
                             '1 with --real-time)')
    parser.add_argument('--output', type=arguments.output_folder, default='out',
                        help='folder for the bag and the report (created if missing)')
    parser.add_argument('--camera-rate', type=arguments.positive, default=2.0,
                        help='camera frames per second of sim time kept in the bag')
    args = parser.parse_args(argv)
    if args.port is not None and port_taken(args.port):
        parser.error('argument --port: %s%s' % (PortTaken(args.port), TAKEN_ADVICE))
    if args.real_time_factor is None:
        args.real_time_factor = 1.0 if args.real_time else 0.0
    return args


class Recorder:
    """rosbag record of the run, with the camera thinned out by topic_tools throttle."""

    def __init__(self, env, bag_path, camera_rate):
        self.group = ProcessGroup(env, stop_timeout=20)
        self.bag_path = bag_path
        self.camera_rate = camera_rate

    def start(self, log):
        commands = [
            ['rosrun', 'topic_tools', 'throttle', 'messages', CAMERA_TOPIC, '%g' % self.camera_rate,
             THROTTLED_CAMERA_TOPIC, '__name:=camera_throttle'],
            # lz4 shrinks the flat-shaded frames about tenfold at little cost.
            ['rosbag', 'record', '--lz4', '-O', self.bag_path, '__name:=chase_recorder']
            + list(RECORDED_TOPICS),
        ]
        for cmd in commands:
            self.group.start(cmd, log)

    def ready(self, master):
        """True once the recorder listens to every topic and the throttle to the camera."""
        _, subscribers, _ = master.getSystemState()
        nodes = {name: set(subscribed) for name, subscribed in subscribers}
        return (all('/chase_recorder' in nodes.get(topic, ()) for topic in RECORDED_TOPICS)
                and '/camera_throttle' in nodes.get(CAMERA_TOPIC, ()))

    def alive(self):
        return self.group.alive()

    def stop(self):
        """SIGINT lets rosbag write the bag's index and rename it from .active."""
        self.group.stop()


def run(args):
    port = args.port or free_port()
    # rospy reads the master address from the environment when it first contacts it.
    os.environ['ROS_MASTER_URI'] = 'http://localhost:%d' % port
    os.environ.setdefault('ROS_HOSTNAME', 'localhost')
    launches = Launches(port, dict(os.environ))
    out_dir = args.output
    world = os.path.abspath(args.world) if args.world else default_world_file()
    bag_path = os.path.join(out_dir, 'chase.bag')
    recorder = Recorder(launches.env, bag_path, args.camera_rate)
    facts = report.RunFacts()
    log_path = os.path.join(out_dir, 'chase_demo_launch.log')
    with open(log_path, 'w') as log:
        try:
            try:
                launches.start_master(log)
            except MasterError as error:
                advice = TAKEN_ADVICE if isinstance(error, PortTaken) and args.port else ''
                print('chase_demo: %s%s' % (error, advice), file=sys.stderr)
                return 2
            print('chase_demo: a ROS master of its own on port %d' % port, flush=True)
            for stale in (bag_path, bag_path + '.active'):
                if os.path.exists(stale):
                    os.remove(stale)
            # Paused until ball_chaser is listening, so no sim time passes while nodes start.
            world_args = ['my_robot', 'world.launch', 'gui:=false', 'paused:=true', 'robot:=%s' % args.robot,
                          'lockstep:=%s' % str(not args.real_time).lower(),
                          'real_time_factor:=%g' % args.real_time_factor, 'world_file:=%s' % world]
            print('chase_demo: starting the world (%s robot), log in %s' % (args.robot, log_path),
                  flush=True)
            launches.launch(*world_args, log=log)
            status = chase(args, launches, recorder, log, facts)
        except KeyboardInterrupt:
            facts.detail = 'interrupted'
            status = 130
        finally:
            recorder.stop()
            launches.stop()
    facts.reached = status == 0
    return write_report(args, bag_path, world, facts, status)


def write_report(args, bag_path, world, facts, status):
    """The report of whatever the bag holds; a report that cannot be written fails the run."""
    if not os.path.exists(bag_path) and os.path.exists(bag_path + '.active'):
        bag_path += '.active'
    print('chase_demo: writing the report from %s' % bag_path, flush=True)
    try:
        written, _ = report.build(bag_path, os.path.dirname(bag_path), world, 'my_robot', args.ball,
                                  args.reach, facts)
    except FlatsimError as err:
        print('chase_demo: no report: %s' % err, file=sys.stderr)
        return status or 1
    print('chase_demo: wrote %s' % ', '.join(written.files), flush=True)
    return status


def chase(args, launches, recorder, log, facts):
    if not wait_for_service(sim_service('get_model_state'), launches):
        print('chase_demo: the simulator did not start; see the launch log', file=sys.stderr)
        facts.detail = 'the simulator did not start'
        return 1
    rospy.init_node('chase_demo', disable_signals=True)
    proxy = rospy.ServiceProxy(sim_service('get_model_state'), GetModelState)

    def get_state(name):
        return proxy(model_name=name)
    spawned = wait_until(lambda: get_state('my_robot').success, [launches])
    robot = get_state('my_robot') if spawned else None
    ball = get_state(args.ball)
    if robot is None or not ball.success:
        facts.detail = 'the robot was not spawned' if robot is None else ball.status_message
        print('chase_demo: %s' % facts.detail, file=sys.stderr)
        return 1
    start = robot.pose.position
    print('chase_demo: robot at (%.2f, %.2f), ball at (%.2f, %.2f), %.2f m apart; starting ball_chaser'
          % (start.x, start.y, ball.pose.position.x, ball.pose.position.y,
             planar_gap(robot.pose, ball.pose)), flush=True)
    recorder.start(log)
    launches.launch('ball_chaser', 'ball_chaser.launch', log=log)
    master = rosgraph.Master('/chase_demo')

    def ready():
        return (chaser_ready(master, CAMERA_TOPIC, {'/camera_throttle'}) and recorder.ready(master)
                and (args.real_time or lockstep_ready(master, CAMERA_TOPIC)))
    if not wait_until(ready, [launches, recorder]):
        facts.detail = 'ball_chaser or the recorder did not come up'
        print('chase_demo: %s; see the launch log' % facts.detail, file=sys.stderr)
        return 1
    # The time to the ball is the stamp of the first odometry within reach: the
    # same under lockstep however fast the machine runs.
    watch = ChaseWatch()
    watch.begin((ball.pose.position.x, ball.pose.position.y), args.reach, args.timeout)
    rospy.ServiceProxy(sim_service('unpause_physics'), Empty)()
    wall_start = time.monotonic()
    t_start = rospy.get_time()
    next_report = 0.0
    try:
        while True:
            decided = watch.wait(0.2, launches.alive, poll_s=0.2)
            progress = watch.progress()
            if progress is not None and (progress[0] >= next_report or decided):
                print('  sim %5.1f s   distance to ball %.2f m' % progress, flush=True)
                next_report = progress[0] + 2.0
            if decided or not launches.alive():
                break
    finally:
        facts.wall_seconds = time.monotonic() - wall_start
        facts.sim_seconds = rospy.get_time() - t_start
        pause(facts)
    if not decided:
        facts.detail = 'a launched process died'
        print('chase_demo: a launched process died; see the launch log', file=sys.stderr)
        return 1
    if watch.reached_at is not None:
        facts.detail = 'the demo saw %.2f m at %.1f s of sim time' % (watch.last[1], watch.reached_at)
        print('chase_demo: reached the ball in %.1f s of sim time (%.2f m)' % (watch.reached_at, watch.last[1]))
        return 0
    facts.detail = 'still %.2f m from the ball after %.0f s of sim time' % (watch.last[1], args.timeout)
    print('chase_demo: FAILED, %s' % facts.detail, file=sys.stderr)
    return 1


def pause(facts):
    """Stop sim time, so that the bag ends where the chase did."""
    try:
        rospy.ServiceProxy(sim_service('pause_physics'), Empty)()
    except (rospy.ServiceException, rospy.ROSException):
        facts.detail += '; the simulator was gone before it could be paused'


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        with cleanup_on_signals():
            return run(args)
    except KeyboardInterrupt:
        return 130
