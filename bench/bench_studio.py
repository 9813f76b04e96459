"""What the studio (Gazebo's window as a web page) costs and how it performs.

    python bench/bench_studio.py [--seconds 5] [--rounds 5] [--ready-runs 3] [--profile]
                                 [--real-time-factor 0]

(a) The simulator's real-time factor running as fast as possible
    (`my_robot world.launch real_time_factor:=0`, the robot driving in circles)
    with no page and with one page open in headless chromium, in windows that
    alternate in one run (no page, page, no page, page, ...), so that the
    machine's changing load touches both alike. The cost is the drop of the
    real-time factor from each no-page window to the page window right after
    it, median over the rounds. Target: at most 10 %.
    With --real-time-factor 1 the simulator holds real time, as the course runs
    it: the drop is then what a user sees in the page's Real Time Factor.
    In two placements, each round taking both: "shared", every process free
    to run on both CPUs (a browser on the simulator's own machine, as the
    tests run it), and "apart", chromium confined to one CPU and the
    simulator's stack (roscore, roslaunch and its nodes) to the other (the
    user's browser on a laptop has cores of its own; as bench_node.py --alone
    does for its case).
    Also, apart from the browser's CPU: the simulator process's own CPU per
    simulated second with and without the page (the studio's cost to the
    simulator itself), the browser's CPU, and, in the shared placement, the
    same drop with one WebSocket client and no browser (the server alone).
(b) The frames per second at which that page shows model motion: rendered
    frames that showed a new pose (the page's window.studio.view.poseFrames),
    median over the page windows of each placement. Target: at least 30.
    And the pose messages per second the WebSocket client received.
(c) The wall time from typing `gazebo WORLD` to the page being ready (scene and
    poses shown), with no master running (gazebo starts roscore) and with one,
    median of --ready-runs each; the browser is started beforehand. Target:
    at most 2 s.
With --profile, py-spy samples the simulator in one window without and one
with the page, and the functions it spent its time in are printed.
Figures only; nothing is asserted. The load average is printed with them.
"""
import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, '..', 'tests'))
from rosproc import RosSystem, free_port  # noqa: E402
from studio_browser import CHROMIUM, launch_browser, start_studio_world, wait_ready  # noqa: E402

PACKAGES = os.path.join(HERE, '..', 'catkin_ws', 'src')
WORLD = os.path.join(PACKAGES, 'my_robot', 'worlds', 'chase_house.world')
ADDRESS = re.compile(r"Gazebo's window \(flatsim studio\) is at (\S+)")
STREAM_CLIENT = os.path.join(HERE, 'studio_stream_client.py')
# The "apart" placement: the simulator's stack on one CPU, the browser on the other.
SIMULATOR_CPU, BROWSER_CPU = 0, 1
ALL_CPUS = {0, 1}
PLACEMENTS = ('shared', 'apart')
# After a page opens or closes, before a window starts: the page's first frames and the
# simulator's first full poses are not what a page costs while it stays open.
SETTLE_SECONDS = 1.0


def median(values):
    ordered = sorted(values)
    if not ordered:
        return float('nan')
    middle = len(ordered) // 2
    return ordered[middle] if len(ordered) % 2 else (ordered[middle - 1] + ordered[middle]) / 2


def spread(values, form='%.1f'):
    return ' '.join(form % value for value in values)


def load_average():
    with open('/proc/loadavg') as loadavg:
        return float(loadavg.read().split()[0])


# -- processes -----------------------------------------------------------------------

def _stat_fields(pid):
    with open('/proc/%d/stat' % pid) as stat:
        return stat.read().rsplit(')', 1)[1].split()


def cpu_seconds(pids):
    """CPU time (user + system) used so far by these processes and their threads."""
    total = 0
    for pid in pids:
        try:
            fields = _stat_fields(pid)
        except (FileNotFoundError, ProcessLookupError):
            continue
        total += int(fields[11]) + int(fields[12])
    return total / os.sysconf('SC_CLK_TCK')


def process_tree(roots):
    """The processes roots and every process under them, as they are now."""
    parents = {}
    for entry in os.listdir('/proc'):
        if entry.isdigit():
            try:
                parents[int(entry)] = int(_stat_fields(int(entry))[1])
            except (OSError, ValueError, IndexError):
                continue
    found = set(roots) & set(parents)
    while True:
        more = {pid for pid, parent in parents.items() if parent in found} - found
        if not more:
            return sorted(found)
        found |= more


def browser_pids(profile):
    """The browser started on profile (its user data dir) and every process under it."""
    roots = []
    for entry in os.listdir('/proc'):
        if not entry.isdigit():
            continue
        try:
            with open('/proc/%s/cmdline' % entry, 'rb') as cmdline:
                if ('--user-data-dir=%s' % profile).encode() in cmdline.read():
                    roots.append(int(entry))
        except OSError:
            continue
    return process_tree(roots)


def pin(pids, cpus):
    """Every thread of these processes onto cpus; the threads and children they start
    later inherit it (chromium forks its tabs' renderers from a zygote it started first)."""
    for pid in pids:
        try:
            threads = os.listdir('/proc/%d/task' % pid)
        except FileNotFoundError:
            continue
        for thread in threads:
            try:
                os.sched_setaffinity(int(thread), cpus)
            except (ProcessLookupError, PermissionError):
                pass  # a thread that has ended since the listing


# -- (a) and (b): cost and frames ------------------------------------------------------

class CostRun:
    """One world, one browser, and the windows measured on them."""

    def __init__(self, world, context, profile, seconds):
        import rospy
        from gazebo_msgs.srv import GetWorldProperties
        self.world = world
        self.context = context
        self.profile = profile
        self.seconds = seconds
        self.proxy = rospy.ServiceProxy('/gazebo/get_world_properties', GetWorldProperties)
        self.simulator = world.simulator_pid()
        self.stack = [proc.pid for proc in world.ros.procs.values()]
        # (placement, what) -> [...], what: 'page', 'socket', or 'without page' and
        # 'without socket' for the windows paired with them.
        self.rtf = collections.defaultdict(list)        # -> [real-time factor]
        self.own_cpu = collections.defaultdict(list)    # -> [CPU s per simulated s]
        self.browser_cpu = collections.defaultdict(list)  # placement -> [CPU s per s]
        self.fps = collections.defaultdict(list)        # placement -> [frames per s]
        self.drops = collections.defaultdict(list)      # (placement, what) -> [drop in %]
        self.stream_rates = []        # pose messages per second that the WebSocket client got
        self.loads = []

    def place(self, placement):
        apart = placement == 'apart'
        pin(process_tree(self.stack), {SIMULATOR_CPU} if apart else ALL_CPUS)
        pin(browser_pids(self.profile), {BROWSER_CPU} if apart else ALL_CPUS)

    def window(self, placement, what, others=()):
        """Measure one window: the real-time factor, the simulator's CPU per simulated
        second, and the CPU seconds per second that others used."""
        wall0, sim0 = time.monotonic(), self.proxy().sim_time
        own0, other0 = cpu_seconds([self.simulator]), cpu_seconds(others)
        time.sleep(self.seconds)
        wall1, sim1 = time.monotonic(), self.proxy().sim_time
        own1, other1 = cpu_seconds([self.simulator]), cpu_seconds(others)
        self.loads.append(load_average())
        self.rtf[placement, what].append((sim1 - sim0) / (wall1 - wall0))
        self.own_cpu[placement, what].append((own1 - own0) / max(sim1 - sim0, 1e-9))
        return (other1 - other0) / (wall1 - wall0)

    def with_page(self, placement):
        page = self.context.new_page()
        page.goto(self.world.url)
        wait_ready(page)
        self.place(placement)          # the new tab's renderer too
        time.sleep(SETTLE_SECONDS)
        frames0, wall0 = page.evaluate('window.studio.view.poseFrames'), time.monotonic()
        self.browser_cpu[placement].append(
            self.window(placement, 'page', browser_pids(self.profile)))
        frames1, wall1 = page.evaluate('window.studio.view.poseFrames'), time.monotonic()
        self.fps[placement].append((frames1 - frames0) / (wall1 - wall0))
        page.close()
        time.sleep(SETTLE_SECONDS)

    def with_socket(self, placement):
        stream = subprocess.Popen([sys.executable, STREAM_CLIENT, self.world.url],
                                  stdout=subprocess.PIPE, text=True)
        time.sleep(SETTLE_SECONDS)
        self.window(placement, 'socket')
        stream.terminate()
        said = stream.communicate(timeout=10)[0]
        found = re.search(r'poses per second: ([\d.]+)', said)
        if found:
            self.stream_rates.append(float(found.group(1)))
        time.sleep(SETTLE_SECONDS)

    def pair(self, placement, what, measure):
        """A window without, then one with: the drop between the two, in %."""
        self.place(placement)
        self.window(placement, 'without ' + what)
        measure(placement)
        before, after = self.rtf[placement, 'without ' + what][-1], self.rtf[placement, what][-1]
        self.drops[placement, what].append(100.0 * (1.0 - after / before))

    def profiled(self, seconds):
        """py-spy's top functions in the simulator without a page and with one (shared)."""
        # Imported here: bench_node puts another spelling of the workspace on
        # ROS_PACKAGE_PATH, where rosrun (gazebo's command) then finds every script twice.
        from bench_node import top_functions
        found = {}
        self.place('shared')
        for what in ('none', 'page'):
            page = None
            if what == 'page':
                page = self.context.new_page()
                page.goto(self.world.url)
                wait_ready(page)
                time.sleep(SETTLE_SECONDS)
            with tempfile.NamedTemporaryFile(suffix='.txt') as out:
                spy = subprocess.run(['py-spy', 'record', '--pid', str(self.simulator), '--format',
                                      'raw', '--rate', '200', '--duration', str(int(seconds)),
                                      '--output', out.name, '--gil'], capture_output=True, text=True)
                found[what] = top_functions(out.name) if spy.returncode == 0 else spy.stderr
            if page is not None:
                page.close()
                time.sleep(SETTLE_SECONDS)
        return found


def cost_and_fps(context, profile, seconds, rounds, profiling, real_time_factor):
    with tempfile.TemporaryDirectory() as tmp:
        with start_studio_world(tmp, ('my_robot', 'world.launch', 'gui:=false',
                                      'real_time_factor:=%g' % real_time_factor)) as world:
            os.environ['ROS_MASTER_URI'] = world.ros.master_uri
            import rospy
            from geometry_msgs.msg import Twist, Vector3
            rospy.init_node('bench_studio', anonymous=True, disable_signals=True)
            drive = rospy.Publisher('/cmd_vel', Twist, queue_size=1, latch=True)
            # The robot drives in circles: its pose changes at every frame.
            drive.publish(Twist(linear=Vector3(0.4, 0.0, 0.0), angular=Vector3(0.0, 0.0, 0.6)))
            time.sleep(2.0)
            run = CostRun(world, context, profile, seconds)
            for _ in range(rounds):
                for placement in PLACEMENTS:
                    run.pair(placement, 'page', run.with_page)
                run.pair('shared', 'socket', run.with_socket)
            profiles = run.profiled(2 * seconds) if profiling else None
            run.place('shared')
            rospy.signal_shutdown('done')
    return run, profiles


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
            stream = subprocess.Popen([sys.executable, STREAM_CLIENT, url], stdout=subprocess.DEVNULL)
            time.sleep(SETTLE_SECONDS)
            found['socket'].append(per_step())
            stream.terminate()
            stream.wait(10)
            time.sleep(0.5)
    finally:
        running[0] = False
        stepper.join()
        server.stop()
    return found


# -- (c): gazebo WORLD to the page ready -----------------------------------------------

def time_to_ready(context, with_master):
    """(address printed, page loaded, page ready) in seconds after `gazebo WORLD` started."""
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
            loaded = time.monotonic()
            wait_ready(page)
            ready = time.monotonic()
            page.close()
        finally:
            gazebo.terminate()
            gazebo.wait(30)
            if ros is not None:
                ros.stop()
    return printed - started, loaded - started, ready - started


# -- the report -------------------------------------------------------------------------

def verdict(met):
    return 'met' if met else 'NOT met'


def report_cost(run, seconds, rounds, real_time_factor):
    pace = ('as fast as possible' if real_time_factor == 0
            else 'the simulator set to %g times real time' % real_time_factor)
    print('(a) the studio\'s cost to the simulator: real-time factor %s, '
          '%d rounds of %g-s windows, load average %.1f to %.1f while measured'
          % (pace, rounds, seconds, min(run.loads), max(run.loads)))
    for placement, where in (('shared', 'every process on both CPUs'),
                             ('apart', 'chromium on CPU %d, the simulator\'s stack on CPU %d'
                              % (BROWSER_CPU, SIMULATOR_CPU))):
        drop = median(run.drops[placement, 'page'])
        none_cpu = median(run.own_cpu[placement, 'without page'])
        page_cpu = median(run.own_cpu[placement, 'page'])
        print('    %s (%s): one page costs %.1f %% of the real-time factor (target at most '
              '10 %%: %s)' % (placement, where, drop, verdict(drop <= 10.0)))
        print('        real-time factor without the page %s, with it %s; drops %s %%'
              % (spread(run.rtf[placement, 'without page']), spread(run.rtf[placement, 'page']),
                 spread(run.drops[placement, 'page'])))
        per_frame = [cpu / fps for cpu, fps in zip(run.browser_cpu[placement], run.fps[placement])
                     if fps > 0]
        print('        the simulator\'s own CPU per simulated second: %.1f ms without the page, '
              '%.1f ms with it (%+.1f %%); chromium used %.2f CPU-seconds per second, %.1f ms '
              'per frame shown' % (1e3 * none_cpu, 1e3 * page_cpu, 100.0 * (page_cpu / none_cpu - 1.0),
                                   median(run.browser_cpu[placement]), 1e3 * median(per_frame)))
    drop = median(run.drops['shared', 'socket'])
    none_cpu = median(run.own_cpu['shared', 'without socket'])
    socket_cpu = median(run.own_cpu['shared', 'socket'])
    print('    the server alone (one WebSocket client, no browser, shared): %.1f %% of the '
          'real-time factor (drops %s %%); the simulator\'s CPU per simulated second %+.1f %%'
          % (drop, spread(run.drops['shared', 'socket']), 100.0 * (socket_cpu / none_cpu - 1.0)))


def report_server(server):
    alone, streamed = median(server['none']), median(server['socket'])
    print('    the server alone in this process (the world stepped bare, as fast as it goes): '
          '%.1f us of CPU per step with no client, %.1f us with one (%+.1f %%)'
          % (1e6 * alone, 1e6 * streamed, 100.0 * (streamed / alone - 1.0)))


def report_fps(run):
    print('(b) the stream: %s pose messages per second to the WebSocket client, the robot '
          'driving (the stream rate is 40 Hz)' % spread(run.stream_rates))
    for placement in PLACEMENTS:
        fps = median(run.fps[placement])
        print('(b) %s: frames per second showing model motion %.1f (windows: %s; target at '
              'least 30: %s)' % (placement, fps, spread(run.fps[placement]), verdict(fps >= 30.0)))


def report_ready(readies):
    for with_master, label in ((False, 'without a master (gazebo starts roscore)'),
                               (True, 'with a master running')):
        times = readies[with_master]
        ready = median([t[2] for t in times])
        print('(c) gazebo WORLD %s: page ready after %.2f s (runs: %s; target at most 2 s: %s)'
              % (label, ready, spread([t[2] for t in times], '%.2f'), verdict(ready <= 2.0)))
        print('        address printed after %s s, page loaded after %s s'
              % (spread([t[0] for t in times], '%.2f'), spread([t[1] for t in times], '%.2f')))


def report_profiles(profiles):
    for what, label in (('none', 'without a page'), ('page', 'with one page')):
        found = profiles[what]
        if isinstance(found, str):
            print('py-spy could not sample the simulator: %s' % found.strip())
            return
        samples, own, total = found
        print('\nthe simulator %s (py-spy, %d samples): own time' % (label, samples))
        for function, count in own:
            print('    %5.1f %%  %s' % (100.0 * count / samples, function))
        print('  total time')
        for function, count in total:
            print('    %5.1f %%  %s' % (100.0 * count / samples, function))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seconds', type=float, default=5.0, help='length of each measuring window')
    parser.add_argument('--rounds', type=int, default=5,
                        help='rounds of paired windows (without, with) in each placement')
    parser.add_argument('--ready-runs', type=int, default=3,
                        help='times gazebo WORLD is started, with and without a master')
    parser.add_argument('--real-time-factor', type=float, default=0.0,
                        help='the pace the simulator is set to in (a) and (b): 0 (default) as fast '
                             'as possible, where any CPU the page takes shows; 1 as the course runs')
    parser.add_argument('--profile', action='store_true',
                        help='sample the simulator with py-spy without and with a page')
    args = parser.parse_args()
    if not 0.0 <= args.real_time_factor < float('inf'):
        parser.error('--real-time-factor must be 0 (as fast as possible) or a positive number')
    if not os.path.exists(CHROMIUM):
        raise SystemExit('bench_studio needs %s (./setup.sh installs it)' % CHROMIUM)
    from playwright.sync_api import sync_playwright
    print('load average at the start: %.1f' % load_average(), flush=True)
    with sync_playwright() as playwright, tempfile.TemporaryDirectory() as profile:
        context = launch_browser(playwright, profile)
        readies = {False: [], True: []}
        for _ in range(args.ready_runs):
            for with_master in (False, True):
                readies[with_master].append(time_to_ready(context, with_master))
        report_ready(readies)
        run, profiles = cost_and_fps(context, profile, args.seconds, args.rounds, args.profile,
                                     args.real_time_factor)
        context.close()
    report_cost(run, args.seconds, args.rounds, args.real_time_factor)
    report_server(server_cost(args.seconds, args.rounds))
    report_fps(run)
    if profiles:
        report_profiles(profiles)


if __name__ == '__main__':
    main()
