"""How much of the camera stream process_image keeps up with, and how late its answers come.

  python bench/bench_chase_latency.py [--seconds 20] [--port 11491]

Runs my_robot world.launch (chase_house, real-time factor 1, camera at 30 Hz)
and ball_chaser.launch on a master of its own, with process_image's
~publish_handled on: it then publishes the header of every image it has
handled on /process_image/handled. The robot chases a ball that this script
moves to a new place ahead of it every two sim seconds, so the command keeps
changing and process_image keeps calling drive_bot.

Prints:
- frames published (counted on /camera/rgb/camera_info, which flatsim sends
  with every image) and the fraction process_image handled;
- latency from an image's header stamp to the /cmd_vel that answers it, in
  wall time. The stamp is sim time; /clock receipts map it to wall time. A
  /cmd_vel answers the first handled image reported after it.
- latency from stamp to the handled report, for every handled image.
No asserts: the figures depend on the machine and its load.
"""
import argparse
import bisect
import math
import os
import random
import sys
import time

import numpy as np

from chase_tools.procs import Launches

ROBOT, BALL = 'my_robot', 'white_ball'
MOVE_EVERY_S = 2.0
MATCH_WINDOW_S = 0.5


def parse_args(argv):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=20.0, help='sim seconds to measure')
    parser.add_argument('--port', type=int, default=11491, help="port of the bench's own ROS master")
    parser.add_argument('--seed', type=int, default=1, help='seed for the ball placements')
    return parser.parse_args(argv)


class Recorder:
    """Receipt wall times (time.monotonic) of the topics the figures come from."""

    def __init__(self, rospy):
        from geometry_msgs.msg import Twist
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import CameraInfo
        from std_msgs.msg import Header
        self.clock = []      # (sim, wall)
        self.frames = []     # sim stamps of published frames
        self.handled = []    # (sim stamp, wall receipt)
        self.cmd_vel = []    # wall receipt
        self.subs = [
            rospy.Subscriber('/clock', Clock, self.on_clock, queue_size=100),
            rospy.Subscriber('/camera/rgb/camera_info', CameraInfo, self.on_frame, queue_size=100),
            rospy.Subscriber('/process_image/handled', Header, self.on_handled, queue_size=100),
            rospy.Subscriber('/cmd_vel', Twist, self.on_cmd_vel, queue_size=100),
        ]

    def on_clock(self, msg):
        self.clock.append((msg.clock.to_sec(), time.monotonic()))

    def on_frame(self, msg):
        self.frames.append(msg.header.stamp.to_sec())

    def on_handled(self, msg):
        self.handled.append((msg.stamp.to_sec(), time.monotonic()))

    def on_cmd_vel(self, _msg):
        self.cmd_vel.append(time.monotonic())

    def freeze(self):
        """Stop recording: copies the lists, which the subscriber threads append to."""
        for sub in self.subs:
            sub.unregister()
        self.clock, self.frames = list(self.clock), list(self.frames)
        self.handled, self.cmd_vel = list(self.handled), list(self.cmd_vel)
        self._clock_sims = np.array([s for s, _ in self.clock])
        self._clock_walls = np.array([w for _, w in self.clock])

    def wall_of(self, sim):
        """Wall time at which /clock said sim (linear between receipts)."""
        return float(np.interp(sim, self._clock_sims, self._clock_walls))


def describe(name, values_s):
    if not values_s:
        print('%s: none' % name)
        return
    ms = np.array(values_s) * 1000.0
    print('%s: n=%d  median %.1f ms  p90 %.1f ms  max %.1f ms'
          % (name, len(ms), np.median(ms), np.percentile(ms, 90), ms.max()))


def run_scenario(rospy, args, recorder):
    from flatsim.pose import Pose
    from flatsim.ros.messages import pose_msg
    from gazebo_msgs.msg import ModelState
    from gazebo_msgs.srv import GetModelState, SetModelState
    from geometry_msgs.msg import Twist
    from std_srvs.srv import Empty
    state_proxy = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState, persistent=True)
    set_proxy = rospy.ServiceProxy('/gazebo/set_model_state', SetModelState, persistent=True)

    def get_state(name):
        return state_proxy(model_name=name)

    def set_state(name, pose, twist):
        return set_proxy(ModelState(model_name=name, pose=pose, twist=twist))
    rng = random.Random(args.seed)
    set_state(ROBOT, pose_msg(Pose(0.0, 0.0, 0.0)), Twist())
    set_state(BALL, pose_msg(Pose(2.5, 0.0, 0.1)), Twist())
    rospy.ServiceProxy('/gazebo/unpause_physics', Empty)()
    start = rospy.get_time()
    next_move = start + MOVE_EVERY_S
    while rospy.get_time() - start < args.seconds:
        now = rospy.get_time()
        if now >= next_move:
            robot = get_state(ROBOT).pose
            yaw = 2.0 * math.atan2(robot.orientation.z, robot.orientation.w)
            bearing = yaw + math.radians(rng.uniform(-25.0, 25.0))
            distance = rng.uniform(1.2, 2.2)
            # Back to the middle of the main room when the next spot would leave it.
            x = robot.position.x + distance * math.cos(bearing)
            y = robot.position.y + distance * math.sin(bearing)
            if not (-2.5 < x < 3.5 and -1.0 < y < 3.5):
                set_state(ROBOT, pose_msg(Pose(-1.5, 1.0, 0.0, yaw=rng.uniform(-0.5, 0.5))), Twist())
                robot = get_state(ROBOT).pose
                yaw = 2.0 * math.atan2(robot.orientation.z, robot.orientation.w)
                x, y = -1.5 + distance * math.cos(yaw), 1.0 + distance * math.sin(yaw)
            set_state(BALL, pose_msg(Pose(x, y, 0.1)), Twist())
            next_move = now + MOVE_EVERY_S
        time.sleep(0.01)
    return start, rospy.get_time()


def report(recorder, start, end):
    frames = [s for s in recorder.frames if start <= s <= end]
    handled = [(s, w) for s, w in recorder.handled if start <= s <= end]
    print('camera frames published: %d in %.1f sim s (%.1f Hz)' % (len(frames), end - start,
                                                                  len(frames) / max(end - start, 1e-9)))
    print('frames handled by process_image: %d (%.1f%%)'
          % (len(handled), 100.0 * len(handled) / max(len(frames), 1)))
    describe('stamp -> handled report (all handled frames)',
             [w - recorder.wall_of(s) for s, w in handled])
    handled_walls = [w for _, w in recorder.handled]
    answers = []
    for cmd_wall in recorder.cmd_vel:
        index = bisect.bisect_left(handled_walls, cmd_wall)
        if index < len(handled_walls) and handled_walls[index] - cmd_wall <= MATCH_WINDOW_S:
            stamp = recorder.handled[index][0]
            if start <= stamp <= end:
                answers.append(cmd_wall - recorder.wall_of(stamp))
    print('/cmd_vel messages: %d (%.1f%% of handled frames changed the command)'
          % (len(answers), 100.0 * len(answers) / max(len(handled), 1)))
    describe('stamp -> /cmd_vel (answered frames)', answers)
    clock = [(s, w) for s, w in recorder.clock if start <= s <= end]
    if len(clock) > 1:
        print('real-time factor over the run: %.2f'
              % ((clock[-1][0] - clock[0][0]) / (clock[-1][1] - clock[0][1])))


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    os.environ['ROS_MASTER_URI'] = 'http://localhost:%d' % args.port
    os.environ.setdefault('ROS_HOSTNAME', 'localhost')
    launches = Launches(args.port, dict(os.environ))
    # Only now: rospy and the graph helpers read ROS_MASTER_URI when imported.
    import rospy
    from chase_tools.chase_graph import wait_for_service

    def wait_for(service):
        if not wait_for_service(service, launches):
            raise SystemExit('bench: %s did not come up; see /tmp/bench_chase_latency.log' % service)
    with open('/tmp/bench_chase_latency.log', 'w') as log:
        launches.launch('my_robot', 'world.launch', 'gui:=false', 'paused:=true', 'real_time_factor:=1', log=log)
        try:
            wait_for('/gazebo/get_model_state')
            rospy.init_node('bench_chase_latency', disable_signals=True)
            rospy.set_param('/process_image/publish_handled', True)
            launches.launch('ball_chaser', 'ball_chaser.launch', 'output:=log', log=log)
            wait_for('/ball_chaser/command_robot')
            recorder = Recorder(rospy)
            deadline = time.monotonic() + 60.0
            while not recorder.subs[2].get_num_connections() and time.monotonic() < deadline:
                time.sleep(0.1)
            start, end = run_scenario(rospy, args, recorder)
            time.sleep(MATCH_WINDOW_S)
            recorder.freeze()
            report(recorder, start, end)
        finally:
            launches.stop()
    return 0


if __name__ == '__main__':
    sys.exit(main())
