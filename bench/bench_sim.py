"""The whole simulation with the course's sensors, headless, as fast as it goes, in one process.

my_robot (diff drive) in chase_house.world, driving a circle; its camera
(800x800 R8G8B8, 30 Hz) and lidar (720 beams, 40 Hz) are rendered every
time they fall due, as if both topics had subscribers. Memory settings are
the simulator node's (flatsim.sensors.camera.keep_freed_memory).

It runs on one CPU, as the targets are stated: the process pins itself to
the first CPU it may use before anything starts threads (OpenCV sizes its
thread pool by the CPUs it may run on).

Prints the real-time factor (sim seconds per wall second), the median
camera render and lidar scan times, and resident memory before and after.
Wall-clock figures suffer when other processes share the cores, so the CPU
time of this process is printed alongside.
With --minutes N it runs for N minutes of wall time and prints the resident
memory every minute, to show whether it grows. Figures only, no asserts.

    python bench/bench_sim.py [--sim-seconds 20] [--minutes N]
"""
import argparse
import os
import resource
import statistics
import sys
import time

TOP = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')
SRC = os.path.join(TOP, 'catkin_ws', 'src')
sys.path.insert(0, os.path.join(SRC, 'flatsim', 'src'))
os.environ['ROS_PACKAGE_PATH'] = SRC + os.pathsep + os.environ.get('ROS_PACKAGE_PATH', '')

from flatsim.loading.sdf_world import load_world  # noqa: E402
from flatsim.loading.urdf_robot import expand_xacro, load_robot  # noqa: E402
from flatsim.pose import Pose  # noqa: E402
from flatsim.sensors.camera import keep_freed_memory  # noqa: E402
from flatsim.world.sim import Simulation  # noqa: E402

WORLD = os.path.join(SRC, 'my_robot', 'worlds', 'chase_house.world')
XACRO = os.path.join(SRC, 'my_robot', 'urdf', 'my_robot.xacro')
# A 1 m radius circle from the spawn pose keeps clear of the furniture.
COMMAND = (0.3, 0.3)


def rss_mb():
    """Current resident set size (VmRSS) in MiB."""
    with open('/proc/self/status') as status:
        for line in status:
            if line.startswith('VmRSS:'):
                return int(line.split()[1]) / 1024.0
    return float('nan')


def max_rss_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def pin_to_one_cpu():
    """Restrict this process to one CPU; returns its number, or None where unsupported."""
    if not hasattr(os, 'sched_setaffinity'):
        return None
    cpu = min(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cpu})
    return cpu


def build():
    sim = Simulation(load_world(WORLD))
    spec = load_robot(expand_xacro(XACRO), name='my_robot')
    robot = sim.spawn_robot('my_robot', spec, Pose())
    robot.drive.set_command(*COMMAND)
    return sim


class Runner:
    def __init__(self, sim):
        self.sim = sim
        self.times_ms = {'camera': [], 'laser': []}
        self.cpu_ms = {'camera': [], 'laser': []}
        self.wall_s = 0.0
        self.cpu_s = 0.0
        self.sim_s = 0.0

    def run(self, sim_seconds):
        sim = self.sim
        steps = int(round(sim_seconds / sim.step_size))
        sim_start, wall_start, cpu_start = sim.time, time.perf_counter(), time.process_time()
        for _ in range(steps):
            sim.step()
            for slot in sim.due_sensors():
                start, cpu = time.perf_counter(), time.process_time()
                sim.sense(slot)
                self.times_ms[slot.kind].append((time.perf_counter() - start) * 1000.0)
                self.cpu_ms[slot.kind].append((time.process_time() - cpu) * 1000.0)
        self.wall_s += time.perf_counter() - wall_start
        self.cpu_s += time.process_time() - cpu_start
        self.sim_s += sim.time - sim_start


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--sim-seconds', type=float, default=20.0,
                        help='sim time to run for the figures (default 20)')
    parser.add_argument('--minutes', type=float, default=0.0,
                        help='then keep running this many wall minutes, printing RSS each minute')
    args = parser.parse_args()

    cpu = pin_to_one_cpu()
    print('running on CPU %s only' % cpu if cpu is not None
          else 'running on every CPU (no affinity here)')
    keep_freed_memory()
    print('resident memory at start:      %7.1f MiB' % rss_mb())
    sim = build()
    print('resident memory after loading: %7.1f MiB' % rss_mb())
    runner = Runner(sim)
    runner.run(args.sim_seconds)
    print('sim seconds:            %8.1f' % runner.sim_s)
    print('wall seconds:           %8.2f' % runner.wall_s)
    print('CPU seconds:            %8.2f' % runner.cpu_s)
    print('real-time factor:       %8.2f  (per CPU second: %.2f)'
          % (runner.sim_s / runner.wall_s, runner.sim_s / runner.cpu_s))
    for kind, label in [('camera', 'camera render (800x800)'), ('laser', 'lidar scan (720 beams)')]:
        times = runner.times_ms[kind]
        print('%-24s median %6.2f ms  p90 %6.2f ms  CPU median %6.2f ms  (%d updates)'
              % (label, statistics.median(times), sorted(times)[int(0.9 * len(times))],
                 statistics.median(runner.cpu_ms[kind]), len(times)))
    pose = sim.model_pose('my_robot')
    print('robot at (%.2f, %.2f)' % (pose.x, pose.y))
    print('resident memory after run:     %7.1f MiB (peak %.1f MiB)' % (rss_mb(), max_rss_mb()))

    if args.minutes > 0:
        end = time.monotonic() + args.minutes * 60.0
        next_report = time.monotonic() + 60.0
        while time.monotonic() < end:
            runner.run(1.0)
            # The timing lists would grow by themselves; memory must show the simulator's.
            for samples in list(runner.times_ms.values()) + list(runner.cpu_ms.values()):
                samples.clear()
            if time.monotonic() >= next_report:
                next_report += 60.0
                print('minute %3d: sim %8.1f s  resident %7.1f MiB  peak %7.1f MiB'
                      % (round((args.minutes * 60.0 - (end - time.monotonic())) / 60.0),
                         sim.time, rss_mb(), max_rss_mb()), flush=True)


if __name__ == '__main__':
    main()
