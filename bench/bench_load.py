"""Load on a running world and drive_bot: /cmd_vel at 1 kHz and drive_bot's service at
500 calls/s, both for --seconds of wall time.

    python bench/bench_load.py [--seconds 60] [--cmd-rate 1000] [--call-rate 500] [--attach]

Without --attach it starts my_robot world.launch (no rviz, real-time factor 1) and
drive_bot on a master of its own and stops them afterwards; with --attach it loads
the system that ROS_MASTER_URI points at. Prints the rates achieved, service-call
latency percentiles, and the resident memory (VmRSS) of the flatsim and drive_bot
processes before and after. Figures only; nothing is asserted.
"""
import argparse
import math
import os
import pathlib
import sys
import tempfile
import threading
import time

import numpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / 'tests'))
from rosproc import RosGraph, RosSystem, vm_rss_kib  # noqa: E402

COMMAND_SERVICE = '/ball_chaser/command_robot'
LOADED_NODES = ('/flatsim', '/drive_bot')
MODELS = ('my_robot', 'white_ball')


class Paced:
    """Runs action() rate times per second of wall time until stop is set; counts and times it.

    It keeps the schedule rather than sleeping a fixed period, so a late call is
    followed by a prompt one; it never bursts more than one period behind.
    """

    def __init__(self, rate, action, stop):
        self.period = 1.0 / rate
        self.action = action
        self.stop = stop
        self.count = 0
        self.errors = 0
        self.latencies = []
        self.elapsed = 0.0
        self.thread = threading.Thread(target=self._run, daemon=True)

    def _run(self):
        start = next_due = time.perf_counter()
        while not self.stop.is_set():
            before = time.perf_counter()
            try:
                self.action()
            except Exception:  # noqa: BLE001 - a failed call is counted, not fatal: the figures report it
                self.errors += 1
            after = time.perf_counter()
            self.latencies.append(after - before)
            self.count += 1
            next_due = max(next_due + self.period, after - self.period)
            if next_due > after:
                time.sleep(next_due - after)
        self.elapsed = time.perf_counter() - start

    @property
    def rate(self):
        return self.count / self.elapsed if self.elapsed else 0.0


def node_rss(graph):
    """{node: (pid, VmRSS KiB)} for the loaded nodes."""
    found = {}
    for node in LOADED_NODES:
        pid = graph.node_pid(node)
        found[node] = (pid, vm_rss_kib(pid) if pid else None)
    return found


def finite_state(get_state, model):
    """True when the model is known and every number in its pose and twist is finite."""
    response = get_state(model_name=model)
    if not response.success:
        return False
    pose, twist = response.pose, response.twist
    values = [pose.position.x, pose.position.y, pose.position.z, pose.orientation.x,
              pose.orientation.y, pose.orientation.z, pose.orientation.w,
              twist.linear.x, twist.linear.y, twist.linear.z,
              twist.angular.x, twist.angular.y, twist.angular.z]
    return all(math.isfinite(v) for v in values)


def run_load(master_uri, seconds, cmd_rate=1000.0, call_rate=500.0):
    """Load the system for seconds of wall time; returns a dict of figures.

    Uses rospy, so call it in a process that has no rospy node yet (the test
    runs it through rosproc.run_forked).
    """
    os.environ['ROS_MASTER_URI'] = master_uri
    if not os.environ.get('ROS_IP'):
        os.environ.setdefault('ROS_HOSTNAME', 'localhost')
    import rospy
    from geometry_msgs.msg import Twist

    from ball_chaser.srv import DriveToTarget
    from gazebo_msgs.srv import GetModelState

    graph = RosGraph(master_uri)
    rospy.init_node('bench_load', anonymous=True, disable_signals=True)
    rospy.wait_for_service(COMMAND_SERVICE, timeout=60.0)
    rospy.wait_for_service('/gazebo/get_model_state', timeout=60.0)
    get_state = rospy.ServiceProxy('/gazebo/get_model_state', GetModelState)
    publisher = rospy.Publisher('/cmd_vel', Twist, queue_size=10)
    drive = rospy.ServiceProxy(COMMAND_SERVICE, DriveToTarget, persistent=True)
    # Wait until flatsim is connected, so the first second's messages are not lost.
    deadline = time.monotonic() + 10.0
    while publisher.get_num_connections() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)

    twist = Twist()
    phase = [0]

    def publish():
        # Turn in place, alternating direction each second, so the robot stays in its room.
        phase[0] += 1
        twist.angular.z = 0.5 if (phase[0] // int(cmd_rate)) % 2 else -0.5
        publisher.publish(twist)

    def call():
        drive(0.0, 0.3)

    before = node_rss(graph)
    stop = threading.Event()
    loads = {'cmd_vel': Paced(cmd_rate, publish, stop), 'service': Paced(call_rate, call, stop)}
    for load in loads.values():
        load.thread.start()
    time.sleep(seconds)
    stop.set()
    for load in loads.values():
        load.thread.join(timeout=30.0)
    after = node_rss(graph)
    figures = {
        'seconds': seconds,
        'cmd_vel_rate': loads['cmd_vel'].rate,
        'cmd_vel_errors': loads['cmd_vel'].errors,
        'call_rate': loads['service'].rate,
        'call_errors': loads['service'].errors,
        'latency_s': dict(zip(('p50', 'p90', 'p99', 'max'),
                              numpy.percentile(loads['service'].latencies, [50, 90, 99, 100]).tolist()))
        if loads['service'].latencies else {},
        'rss_before': before,
        'rss_after': after,
        'answers_after': {
            'drive_bot': _answers(lambda: drive(0.0, 0.0)),
            'flatsim': _answers(lambda: all(finite_state(get_state, model) for model in MODELS)),
        },
        'finite_states': {model: finite_state(get_state, model) for model in MODELS},
    }
    drive.close()
    rospy.signal_shutdown('load done')
    return figures


def _answers(call):
    try:
        return call() is not False
    except Exception:  # noqa: BLE001 - any failure to answer is the figure being reported
        return False


def print_figures(figures, cmd_rate, call_rate):
    print('load for %g s of wall time' % figures['seconds'])
    print('  /cmd_vel      %8.1f msg/s  (asked %g)   errors %d'
          % (figures['cmd_vel_rate'], cmd_rate, figures['cmd_vel_errors']))
    print('  command_robot %8.1f call/s (asked %g)   errors %d'
          % (figures['call_rate'], call_rate, figures['call_errors']))
    latency = figures['latency_s']
    if latency:
        print('  call latency  p50 %.2f ms  p90 %.2f ms  p99 %.2f ms  max %.2f ms'
              % tuple(1000.0 * latency[k] for k in ('p50', 'p90', 'p99', 'max')))
    for node in LOADED_NODES:
        pid, start = figures['rss_before'][node]
        end_pid, end = figures['rss_after'][node]
        if start is None or end is None:
            print('  %-10s RSS unavailable (pid %s -> %s)' % (node, pid, end_pid))
            continue
        restarted = '' if end_pid == pid else '  (restarted: pid %s -> %s)' % (pid, end_pid)
        print('  %-10s RSS %8.1f MiB -> %8.1f MiB  (%+.1f%%)%s'
              % (node, start / 1024.0, end / 1024.0, 100.0 * (end - start) / start, restarted))
    print('  answering afterwards: %s; finite model states: %s'
          % (figures['answers_after'], figures['finite_states']))


def start_system(ros):
    """World (real-time factor 1, no rviz) and drive_bot alone: nothing else calls the service."""
    ros.launch('world', 'my_robot', 'world.launch', 'gui:=false')
    ros.graph.wait_for_service('/gazebo/get_model_state')
    ros.run('drive_bot', ['rosrun', 'ball_chaser', 'drive_bot'])
    ros.graph.wait_for_service(COMMAND_SERVICE)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=60.0, help='wall seconds of load')
    parser.add_argument('--cmd-rate', type=float, default=1000.0, help='/cmd_vel messages per second')
    parser.add_argument('--call-rate', type=float, default=500.0, help='drive_bot service calls per second')
    parser.add_argument('--attach', action='store_true',
                        help='load the running system at ROS_MASTER_URI instead of starting one')
    args = parser.parse_args(argv)
    if args.attach:
        figures = run_load(os.environ.get('ROS_MASTER_URI', 'http://localhost:11311'),
                           args.seconds, args.cmd_rate, args.call_rate)
    else:
        with tempfile.TemporaryDirectory(prefix='bench_load_') as log_dir, RosSystem(log_dir) as ros:
            print('starting world and drive_bot on %s' % ros.master_uri, flush=True)
            start_system(ros)
            figures = run_load(ros.master_uri, args.seconds, args.cmd_rate, args.call_rate)
    print_figures(figures, args.cmd_rate, args.call_rate)


if __name__ == '__main__':
    main()
