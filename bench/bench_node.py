"""The simulator node through ROS against its core, in one run: what the wire costs.

    python bench/bench_node.py [--sim-seconds 20] [--split | --alone] [--profile]

First the core alone (bench_sim's loop: chase_house, my_robot driving a
circle, camera and lidar rendered whenever due) for --sim-seconds, then
`my_robot world.launch real_time_factor:=0` on a master of its own, with a
subscriber on the camera image and the scan (rospy.AnyMsg: it counts the
messages without decoding them, as rosbag and topic_tools do) and the robot
driving the same circle. Everything runs on one CPU, the first this process
may use; with --split the subscriber runs on another CPU instead, so only the
node and its launch share the first; with --alone the simulator node has the
first CPU to itself, and everything else (subscriber, master,
robot_state_publisher) shares the other.

Prints both real-time factors and their ratio, twice: per wall second, and
per CPU second (for the ROS side, the CPU time of every process of the
system: node, subscriber, robot_state_publisher, master, roslaunch, found by
parentage). On a
shared machine the wall figures show the load; the CPU figures show the cost.
Also the frames and scans the subscriber received against those the sim
time called for, and the floor any ROS path has to pay: the camera's
frames for the same sim time sent through loopback TCP from this process
to a reader on the subscriber's CPU, with no ROS at all, set against the
CPU per sim second that 60 % of the core leaves. With --profile,
py-spy samples the node while it is measured and the functions holding the
most samples (their own time, then with callees) are printed. Figures only.
"""
import argparse
import collections
import json
import os
import socket
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, '..', 'tests'))
from bench_sim import Runner, build, pin_to_one_cpu  # noqa: E402
from rosproc import RosSystem, free_port, wait_until  # noqa: E402

CAMERA_TOPIC = '/camera/rgb/image_raw'
SCAN_TOPIC = '/scan'
WARMUP_SIM_S = 2.0
TARGET_SHARE = 0.6  # of the core's real-time factor
# Reads whatever comes until the sender closes, then prints its CPU seconds spent reading.
FLOOR_READER = """
import socket, sys, time
with socket.create_connection(('127.0.0.1', int(sys.argv[1]))) as sock:
    view = memoryview(bytearray(1 << 22))
    start = time.process_time()
    while sock.recv_into(view):
        pass
print(time.process_time() - start)
"""


def core_rtf(sim_seconds):
    """(sim seconds per wall second, per CPU second, camera frame bytes, {'camera' | 'laser': updates per
    sim second}) of the core alone."""
    runner = Runner(build())
    runner.run(1.0)  # the first frames pay for memory the later ones reuse
    runner.wall_s = runner.sim_s = runner.cpu_s = 0.0
    runner.run(sim_seconds)
    slots = {slot.kind: slot for robot in runner.sim.robots() for slot in robot.sensors}
    rates = {kind: 1.0 / slot.period for kind, slot in slots.items()}
    frame_bytes = runner.sim.sense(slots['camera']).nbytes
    return runner.sim_s / runner.wall_s, runner.sim_s / runner.cpu_s, frame_bytes, rates


def wire_floor(frame_bytes, count, reader_cpu):
    """(CPU seconds to send, to receive) count frames of frame_bytes through loopback TCP, no ROS.

    This thread sends; the reader is a process of its own on reader_cpu.
    """
    with socket.socket() as server:
        server.bind(('127.0.0.1', 0))
        server.listen(1)
        reader = subprocess.Popen(['taskset', '-c', str(reader_cpu), sys.executable, '-c', FLOOR_READER,
                                   str(server.getsockname()[1])], stdout=subprocess.PIPE, text=True)
        connection, _ = server.accept()
        frame = bytes(frame_bytes)
        with connection:
            start = time.thread_time()
            for _ in range(count):
                connection.sendall(frame)
            send_s = time.thread_time() - start
        receive_s = float(reader.communicate()[0])
    return send_s, receive_s


def cpu_seconds(roots):
    """{command: user and system CPU seconds} of the given processes and all below them.

    By parentage, not process group: roslaunch starts each node in a session of its own.
    """
    total = collections.Counter()
    tick = os.sysconf('SC_CLK_TCK')
    parent, cpu, names = {}, {}, {}
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            with open('/proc/%s/stat' % entry) as stat:
                head, _, tail = stat.read().rpartition(')')
            with open('/proc/%s/cmdline' % entry, 'rb') as cmdline:
                argv = cmdline.read().split(b'\0')
        except OSError:
            continue
        fields = tail.split()
        pid = int(entry)
        # After the command: state ppid pgrp ... utime (12th) stime (13th).
        parent[pid] = int(fields[1])
        cpu[pid] = (int(fields[11]) + int(fields[12])) / tick
        # Name Python processes by their script (or module).
        script = argv[1] if len(argv) > 1 and b'python' in argv[0] else argv[0]
        if script == b'-m' and len(argv) > 2:
            script = argv[2]
        names[pid] = os.path.basename(script.decode())
    for pid in cpu:
        ancestor = pid
        while ancestor not in roots and ancestor > 1:
            ancestor = parent.get(ancestor, 0)
        if ancestor in roots:
            total[names[pid]] += cpu[pid]
    return total


def subscriber_main(master_uri, sim_seconds, out_path, roots):
    """Runs in its own process: counts the stream and times sim time against wall time."""
    os.environ['ROS_MASTER_URI'] = master_uri
    import rospy
    from geometry_msgs.msg import Twist
    from rosgraph_msgs.msg import Clock
    from std_srvs.srv import Empty
    rospy.init_node('bench_node_subscriber', disable_signals=True)
    counts = collections.Counter()
    clock = []

    def count(topic):
        return lambda _msg: counts.update([topic])
    subs = [rospy.Subscriber(topic, rospy.AnyMsg, count(topic), queue_size=1, buff_size=2 ** 24)
            for topic in (CAMERA_TOPIC, SCAN_TOPIC)]
    cpu_at = {}

    def on_clock(msg):
        sim = msg.clock.to_sec()
        if sim >= WARMUP_SIM_S and 'start' not in cpu_at:
            cpu_at['start'] = cpu_seconds(roots)
        clock.append((sim, time.monotonic(), counts[CAMERA_TOPIC], counts[SCAN_TOPIC]))
    subs.append(rospy.Subscriber('/clock', Clock, on_clock, queue_size=1000))
    drive = rospy.Publisher('/cmd_vel', Twist, queue_size=1, latch=True)
    wait_until(lambda: all(s.get_num_connections() for s in subs) and drive.get_num_connections(), 60.0)
    twist = Twist()
    twist.linear.x, twist.angular.z = 0.3, 0.3
    drive.publish(twist)
    rospy.ServiceProxy('/gazebo/unpause_physics', Empty)()
    wait_until(lambda: clock and clock[-1][0] >= WARMUP_SIM_S + sim_seconds, 600.0, interval=0.05)
    rospy.ServiceProxy('/gazebo/pause_physics', Empty)()
    cpu = cpu_seconds(roots)
    cpu.subtract(cpu_at['start'])
    start = next(sample for sample in clock if sample[0] >= WARMUP_SIM_S)
    end = clock[-1]
    with open(out_path, 'w') as out:
        json.dump([end[0] - start[0], end[1] - start[1], cpu, end[2] - start[2], end[3] - start[3]], out)


def top_functions(raw_path, count=12):
    """From py-spy's raw (collapsed) output: [(share of samples, own or total, function)]."""
    own, total = collections.Counter(), collections.Counter()
    samples = 0
    with open(raw_path) as raw:
        for line in raw:
            stack, _, n = line.rstrip().rpartition(' ')
            n = int(n)
            frames = [frame.split(' (')[0] + ' (' + frame.split(' (')[1].split(':')[0].rsplit('/', 1)[-1]
                      if ' (' in frame else frame for frame in stack.split(';')]
            samples += n
            own[frames[-1]] += n
            for frame in set(frames):
                total[frame] += n
    return samples, own.most_common(count), total.most_common(count)


def pin_process(pid, cpu):
    """Every thread of the process onto one CPU."""
    for thread in os.listdir('/proc/%d/task' % pid):
        try:
            os.sched_setaffinity(int(thread), {cpu})
        except ProcessLookupError:
            pass  # a thread that has ended since the listing


def node_rtf(args, cpu, other_cpu):
    with tempfile.TemporaryDirectory() as tmp:
        with RosSystem(tmp, port=args.port or free_port()) as ros:
            pin = ['taskset', '-c', str(other_cpu if args.alone else cpu)]
            ros.run('world', pin + ['roslaunch', '-p', str(ros.port), '--wait', 'my_robot', 'world.launch',
                                    'gui:=false', 'paused:=true', 'real_time_factor:=0'])
            ros.graph.wait_for_service('/gazebo/unpause_physics')
            pid = ros.graph.wait_for_node('/flatsim')
            if args.alone:
                pin_process(pid, cpu)
            sub_cpu = other_cpu if args.split or args.alone else cpu
            out_path = os.path.join(tmp, 'figures')
            roots = [proc.pid for proc in ros.procs.values()] + [os.getpid()]
            subscriber = subprocess.Popen(
                ['taskset', '-c', str(sub_cpu), sys.executable, __file__, '--subscriber', ros.master_uri,
                 str(args.sim_seconds), out_path, ','.join(map(str, roots))], env=ros.env)
            spy = None
            if args.profile:
                time.sleep(2.0)
                spy = subprocess.Popen(['py-spy', 'record', '--pid', str(pid), '--format', 'raw',
                                        '--rate', '200', '--output', os.path.join(tmp, 'profile.txt'),
                                        '--gil'], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            subscriber.wait()
            if spy is not None:
                spy.send_signal(2)
                spy.wait()
            with open(out_path) as figures:
                sim_s, wall_s, cpu_by_process, frames, scans = json.load(figures)
            profile = top_functions(os.path.join(tmp, 'profile.txt')) if spy is not None else None
    return sim_s, wall_s, cpu_by_process, frames, scans, profile


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--sim-seconds', type=float, default=20.0, help='sim seconds measured in each part')
    placement = parser.add_mutually_exclusive_group()
    placement.add_argument('--split', action='store_true', help='the subscriber on another CPU')
    placement.add_argument('--alone', action='store_true',
                           help='the simulator node alone on its CPU, everything else on another')
    parser.add_argument('--profile', action='store_true', help='sample the node with py-spy while measured')
    parser.add_argument('--port', type=int, default=0, help='master port (default: a free one)')
    parser.add_argument('--subscriber', nargs=4, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.subscriber:
        master_uri, sim_seconds, out_path, roots = args.subscriber
        return subscriber_main(master_uri, float(sim_seconds), out_path, {int(p) for p in roots.split(',')})
    cpus = sorted(os.sched_getaffinity(0))
    cpu = pin_to_one_cpu()
    other = next((c for c in cpus if c != cpu), cpu)
    core, core_cpu, frame_bytes, rates = core_rtf(args.sim_seconds)
    send_s, receive_s = wire_floor(frame_bytes, round(rates['camera'] * args.sim_seconds),
                                   other if args.split or args.alone else cpu)
    sim_s, wall_s, cpu_by_process, frames, scans, profile = node_rtf(args, cpu, other)
    cpu_s = sum(cpu_by_process.values())
    node, node_cpu = sim_s / wall_s, sim_s / cpu_s
    where = ('the node alone on CPU %d' % cpu if args.alone else
             'subscriber on CPU %d' % other if args.split else 'subscriber on the same CPU')
    print('sim seconds per                          wall second   CPU second')
    print('core (bench_sim loop), CPU %d             %8.2f     %8.2f' % (cpu, core, core_cpu))
    print('node, camera and scan subscribed         %8.2f     %8.2f   (%s)' % (node, node_cpu, where))
    print('node / core                              %7.0f%%     %7.0f%%'
          % (100.0 * node / core, 100.0 * node_cpu / core_cpu))
    print('CPU per sim second: %s' % ', '.join(
        '%s %.0f ms' % (name, 1000.0 * seconds / sim_s)
        for name, seconds in sorted(cpu_by_process.items(), key=lambda item: -item[1]) if seconds > 0))
    print('received over %.1f sim s: %d of %d frames, %d of %d scans'
          % (sim_s, frames, round(sim_s * rates['camera']), scans, round(sim_s * rates['laser'])))
    budget_ms = 1000.0 / (TARGET_SHARE * core_cpu)
    print('floor, no ROS: %g frames of %d bytes per sim second through loopback TCP cost %.0f ms of CPU '
          'to send and %.0f ms to receive'
          % (rates['camera'], frame_bytes, 1000.0 * send_s / args.sim_seconds, 1000.0 * receive_s / args.sim_seconds))
    print('budget: at %.0f %% of the core, %.0f ms of CPU per sim second, of which the core\'s own work '
          'takes %.0f ms' % (100 * TARGET_SHARE, budget_ms, 1000.0 / core_cpu))
    if profile:
        samples, own, total = profile
        print('\nprofile of the node (%d samples; own time):' % samples)
        for function, n in own:
            print('  %5.1f%%  %s' % (100.0 * n / samples, function))
        print('with callees:')
        for function, n in total:
            print('  %5.1f%%  %s' % (100.0 * n / samples, function))


if __name__ == '__main__':
    main()
