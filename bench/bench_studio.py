"""What the studio (Gazebo's window as a web page) costs and how it performs.

    python bench/bench_studio.py [--seconds 10] [--rounds 2]

(a) The simulator's real-time factor running as fast as possible
    (`my_robot world.launch real_time_factor:=0`, the robot driving in circles),
    in turn with no page, with one page open in headless chromium, and with one
    WebSocket client and no browser (the server's own share), in one run; the
    cost is the drop, in %, medians over the rounds. Target: at most 10 %.
    The headless browser draws on this machine's CPUs, the simulator's, so the
    CPU it used is printed too, and so is the simulator's CPU per simulated
    second, which another process's load disturbs less. Last, the server alone
    in this process over a bare Simulation: its CPU per physics step.
(b) The frames per second at which that page shows model motion: rendered
    frames that showed a new pose (the page's window.studio.view.poseFrames).
    Target: at least 30.
(c) The wall time from typing `gazebo WORLD` to the page being ready (scene and
    poses shown), with no master running (gazebo starts roscore) and with one.
    The browser is started beforehand. Target: at most 2 s.
Figures only; nothing is asserted.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'tests'))
from rosproc import RosSystem, free_port  # noqa: E402
from studio_browser import launch_browser, start_studio_world, wait_ready  # noqa: E402

PACKAGES = os.path.join(HERE, '..', 'catkin_ws', 'src')
WORLD = os.path.join(PACKAGES, 'my_robot', 'worlds', 'chase_house.world')
ADDRESS = re.compile(r"Gazebo's window \(flatsim studio\) is at (\S+)")


def sim_time(proxy):
    return proxy().sim_time


def cpu_seconds(pids):
    """CPU time (user + system) used so far by these processes and their threads."""
    total = 0
    for pid in pids:
        try:
            with open('/proc/%d/stat' % pid) as stat:
                fields = stat.read().rsplit(')', 1)[1].split()
        except FileNotFoundError:
            continue
        total += int(fields[11]) + int(fields[12])
    return total / os.sysconf('SC_CLK_TCK')


def browser_pids(profile):
    """The browser started on profile (its user data dir) and every process under it."""
    parents, roots = {}, []
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            with open('/proc/%s/stat' % entry) as stat:
                parents[int(entry)] = int(stat.read().rsplit(')', 1)[1].split()[1])
            with open('/proc/%s/cmdline' % entry, 'rb') as cmdline:
                if ('--user-data-dir=%s' % profile).encode() in cmdline.read():
                    roots.append(int(entry))
        except (OSError, ValueError):
            continue
    found = set(roots)
    while True:
        more = {pid for pid, parent in parents.items() if parent in found} - found
        if not more:
            return sorted(found)
        found |= more


def measure(proxy, seconds, simulator, pids=()):
    """Over a window of wall time: the real-time factor, the simulator's CPU seconds per
    simulated second, and the CPU seconds per second that pids used."""
    wall0, sim0 = time.monotonic(), sim_time(proxy)
    own0, cpu0 = cpu_seconds([simulator]), cpu_seconds(pids)
    time.sleep(seconds)
    wall1, sim1 = time.monotonic(), sim_time(proxy)
    own1, cpu1 = cpu_seconds([simulator]), cpu_seconds(pids)
    return ((sim1 - sim0) / (wall1 - wall0), (own1 - own0) / max(sim1 - sim0, 1e-9),
            (cpu1 - cpu0) / (wall1 - wall0))


def median(values):
    ordered = sorted(values)
    middle = len(ordered) // 2
    return ordered[middle] if len(ordered) % 2 else (ordered[middle - 1] + ordered[middle]) / 2


def cost_and_fps(context, profile, seconds, rounds):
    """Windows of no page, one page, and (for the server's own share) one WebSocket client
    without a browser, taken in turn so that a machine's changing load touches them alike."""
    found = {'none': [], 'page': [], 'socket': [], 'fps': [], 'browser_cpu': []}
    cpu = {'none': [], 'page': [], 'socket': []}
    client = os.path.join(HERE, 'studio_stream_client.py')
    with tempfile.TemporaryDirectory() as tmp:
        with start_studio_world(tmp, ('my_robot', 'world.launch', 'gui:=false',
                                      'real_time_factor:=0')) as world:
            os.environ['ROS_MASTER_URI'] = world.ros.master_uri
            import rospy
            from gazebo_msgs.srv import GetWorldProperties
            from geometry_msgs.msg import Twist, Vector3
            rospy.init_node('bench_studio', anonymous=True, disable_signals=True)
            drive = rospy.Publisher('/cmd_vel', Twist, queue_size=1, latch=True)
            # The robot drives in circles: its pose changes at every frame.
            drive.publish(Twist(linear=Vector3(0.4, 0.0, 0.0), angular=Vector3(0.0, 0.0, 0.6)))
            proxy = rospy.ServiceProxy('/gazebo/get_world_properties', GetWorldProperties)
            time.sleep(2.0)
            simulator = world.simulator_pid()

            def window(key, pids=()):
                rtf, own, other = measure(proxy, seconds, simulator, pids)
                found[key].append(rtf)
                cpu[key].append(own)
                return other

            for _ in range(rounds):
                window('none')
                page = context.new_page()
                page.goto(world.url)
                wait_ready(page)
                time.sleep(1.0)
                frames0, wall0 = page.evaluate('window.studio.view.poseFrames'), time.monotonic()
                found['browser_cpu'].append(window('page', browser_pids(profile)))
                frames1, wall1 = page.evaluate('window.studio.view.poseFrames'), time.monotonic()
                found['fps'].append((frames1 - frames0) / (wall1 - wall0))
                page.close()
                time.sleep(1.0)
                window('none')
                stream = subprocess.Popen([sys.executable, client, world.url])
                time.sleep(1.0)
                window('socket')
                stream.terminate()
                stream.wait(10)
                time.sleep(1.0)
            rospy.signal_shutdown('done')
    return found, cpu


def server_cost(seconds, rounds):
    """The server's own cost, apart from the browser's and from a busy machine's: the
    process's CPU time per physics step of the project's world with the robot driving,
    stepped as the node steps it (reads handed to the loop), with no client and with one
    WebSocket client taking the stream. CPU time per step hardly depends on how much CPU
    other processes leave."""
    import threading
    from flatsim.loading.sdf_world import load_world
    from flatsim.loading.urdf_robot import load_robot
    from flatsim.pose import Pose
    from flatsim.studio.hub import Hub
    from flatsim.studio.server import StudioServer
    from flatsim.studio.sim_world import SimWorld
    from flatsim.world.sim import Simulation
    urdf = subprocess.run(['xacro', os.path.join(PACKAGES, 'my_robot', 'urdf', 'my_robot.xacro')],
                          capture_output=True, text=True, check=True).stdout
    sim = Simulation(load_world(WORLD))
    sim.spawn_robot('my_robot', load_robot(urdf), Pose())
    sim.models['my_robot'].drive.set_command(0.4, 0.6)
    world = SimWorld(sim, stepped=True)
    web = os.path.join(PACKAGES, 'flatsim', 'studio_web')
    server = StudioServer(Hub(world), os.path.join(web, 'client'),
                          os.path.join(web, 'node_modules', 'three'))
    url = server.start()
    steps = [0]
    running = [True]

    def step():
        while running[0]:
            with world.lock:
                sim.step()
                world.run_readers()
            steps[0] += 1

    stepper = threading.Thread(target=step)
    stepper.start()

    def per_step():
        cpu0, steps0 = time.process_time(), steps[0]
        time.sleep(seconds)
        return (time.process_time() - cpu0) / max(steps[0] - steps0, 1)

    found = {'none': [], 'socket': []}
    try:
        for _ in range(rounds):
            found['none'].append(per_step())
            stream = subprocess.Popen([sys.executable, os.path.join(HERE, 'studio_stream_client.py'), url])
            time.sleep(1.0)
            found['socket'].append(per_step())
            stream.terminate()
            stream.wait(10)
            time.sleep(0.5)
    finally:
        running[0] = False
        stepper.join()
        server.stop()
    return found


def time_to_ready(context, with_master):
    with tempfile.TemporaryDirectory() as tmp:
        env = dict(os.environ, ROS_HOME=os.path.join(tmp, 'home'), ROS_LOG_DIR=os.path.join(tmp, 'log'))
        env.pop('DISPLAY', None)
        ros = RosSystem(tmp, port=free_port(), env=env) if with_master else None
        if ros is not None:
            ros.start_master()
            env = ros.env
        else:
            env['ROS_MASTER_URI'] = 'http://localhost:%d' % free_port()
        started = time.monotonic()
        gazebo = subprocess.Popen(['gazebo', WORLD], env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, start_new_session=True)
        try:
            for line in gazebo.stdout:
                found = ADDRESS.search(line)
                if found:
                    break
            else:
                raise RuntimeError('gazebo printed no address')
            printed = time.monotonic()
            page = context.new_page()
            page.goto(found.group(1))
            wait_ready(page)
            ready = time.monotonic()
            page.close()
        finally:
            gazebo.terminate()
            gazebo.wait(30)
            if ros is not None:
                ros.stop()
    return printed - started, ready - started


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=5.0, help='length of each measuring window')
    parser.add_argument('--rounds', type=int, default=3, help='rounds of windows (none, page, none, socket)')
    args = parser.parse_args()
    from playwright.sync_api import sync_playwright
    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as profile:
        context = launch_browser(playwright, profile)
        for with_master in (False, True):
            printed, ready = time_to_ready(context, with_master)
            print('(c) gazebo WORLD %s: address printed after %.2f s, page ready after %.2f s '
                  '(target at most 2 s)' % ('with a master running' if with_master
                                            else 'without a master (starts roscore)', printed, ready))
        found, cpu = cost_and_fps(context, profile, args.seconds, args.rounds)
        context.close()
    base, base_cpu = median(found['none']), median(cpu['none'])
    print('(a) real-time factor as fast as possible, median of %d windows of %g s each: '
          '%.2f with no page, the simulator using %.3f CPU-seconds per simulated second'
          % (len(found['none']), args.seconds, base, base_cpu))
    for key, label in (('page', 'one page open in headless chromium'),
                       ('socket', 'one WebSocket client, no browser (the server alone)')):
        value, spent = median(found[key]), median(cpu[key])
        print('    %s: real-time factor %.2f (cost %.1f %%); the simulator\'s CPU per simulated '
              'second %.3f, so %.1f %% of its real-time factor when it has a CPU to itself'
              % (label, value, 100.0 * (1.0 - value / base), spent, 100.0 * (1.0 - base_cpu / spent)))
    print('    (real-time factors without: %s; with the page: %s; the headless browser used '
          '%.2f CPU-seconds per second)' % (' '.join('%.1f' % v for v in found['none']),
                                           ' '.join('%.1f' % v for v in found['page']),
                                           median(found['browser_cpu'])))
    server = server_cost(args.seconds, args.rounds)
    alone, streamed = median(server['none']), median(server['socket'])
    print('    the server alone, in process (the world stepped bare, as fast as it goes): %.1f us '
          'of CPU per step with no client, %.1f us with one: cost %.1f %%'
          % (1e6 * alone, 1e6 * streamed, 100.0 * (1.0 - alone / streamed)))
    print('    target: at most 10 %')
    print('(b) frames per second showing model motion: %s (target at least 30)'
          % ' '.join('%.1f' % v for v in found['fps']))


if __name__ == '__main__':
    main()
