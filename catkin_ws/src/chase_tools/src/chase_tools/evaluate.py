"""evaluate: many headless chase trials, each controller on the same placements.

  rosrun chase_tools evaluate --trials N --seed S [--jobs J] [--timeout 60]

Each trial places the robot and the ball at random (from --seed) in free space
of the world, with the whole ball 1-4 m from the robot's camera, inside its
field of view and in plain sight (see chase_tools.placement), and ends when the
robot base is within --reach (0.4 m) of the ball centre, chase_tools.reach's
centre rule (`grade` measures from the robot's outline to the ball's surface
instead), or after --timeout seconds of sim time. Every placement is chased once per mode.
The table gives the success rate and time-to-ball percentiles per mode.

Each worker (up to --jobs at once) launches the world and ball_chaser in one
mode on a ROS master of its own and chases its share of the placements in
turn: pause, /gazebo/reset_simulation (sim time back to 0, the sensor noise
reseeded), place both models with /gazebo/set_model_state, unpause, and watch
/odom until the robot is within reach. The time to the ball is the stamp of
that odometry message.

By default the world runs in lockstep (flatsim waits after each camera frame
for the controller's command) and as fast as that allows, so a trial's outcome
and time to the ball do not depend on the machine's load or on which worker
ran it: two runs with the same seed print the same table. --real-time runs at
a real-time factor of 1 without lockstep, as Gazebo does; the controller's
delay is then wall time, and times to the ball vary by a few seconds with the
load. SIGTERM and SIGHUP stop it as Ctrl-C does, with every process it started.

Placement sampling is pure (no ROS; the robot's geometry comes from the
robot_description that world.launch sets): the same world, robot and seed
always give the same placements, and trial i's placement does not depend on
--trials.
"""
import argparse
import json
import math
import os
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass
from typing import Optional

import numpy as np

from chase_tools import arguments
from chase_tools.placement import Placement, RobotGeometry, plan_placements
from chase_tools.procs import Launches, cleanup_on_signals, wait_until
from chase_tools.reach import CENTRE_REACH_M
from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import load_world

MODES = ('proportional', 'course')
REACH_M = CENTRE_REACH_M
BASE_PORT = 12000
# Wall seconds a trial may take beyond 20 per sim second of its timeout: the
# limit only catches a simulator that stopped advancing.
TRIAL_WALL_S = 120.0
ROBOT_NAME = 'my_robot'
BALL_NAME = 'white_ball'


@dataclass
class TrialResult:
    index: int                     # placement number
    mode: str
    reached: bool
    time_to_ball: Optional[float]  # s of sim time; None when not reached
    closest: float                 # m, closest robot-to-ball distance seen
    error: str = ''                # why the trial could not run, if it could not
    sim_s: float = 0.0             # sim seconds the chase ran
    wall_s: float = 0.0            # wall seconds the trial took: reset, placing, chase


def launched_robot(world_file, package=ROBOT_NAME, launch_file='world.launch'):
    """The RobotGeometry of the robot that the launch file spawns: its robot_description as
    roslaunch would set it (xacro run), read with flatsim's loader. No master is needed."""
    import roslaunch.config
    import roslaunch.rlutil
    from chase_tools.chase_graph import CAMERA_TOPIC
    try:
        # As `roslaunch PACKAGE FILE` finds it: anywhere in the package.
        path = roslaunch.rlutil.resolve_launch_arguments([package, launch_file])[0]
        config = roslaunch.config.load_config_default(
            [(path, ['gui:=false', 'world_file:=%s' % world_file])], None, verbose=False)
        urdf = config.params['/robot_description'].value
    except Exception as error:  # noqa: BLE001 - roslaunch raises its own types, xacro's, and KeyError
        raise FlatsimError('the robot description of %s/%s could not be read: %s'
                           % (package, launch_file, error)) from None
    return RobotGeometry.from_urdf(urdf, CAMERA_TOPIC, source='%s/%s' % (package, launch_file))


def summarize(results, mode):
    """(successes, trials, p50, p90, max) of time to ball over the reached trials of a mode."""
    runs = [r for r in results if r.mode == mode]
    times = np.array([r.time_to_ball for r in runs if r.reached])
    if times.size == 0:
        return len(times), len(runs), None, None, None
    p50, p90 = np.percentile(times, [50, 90])
    return int(times.size), len(runs), float(p50), float(p90), float(times.max())


def format_table(results, modes=MODES):
    """The summary table: one column per mode."""
    def seconds(value):
        return '-' if value is None else '%.1f s' % value

    stats = {mode: summarize(results, mode) for mode in modes}
    rows = [('', list(modes))]
    rows.append(('success rate', ['%d/%d (%.0f%%)' % (ok, n, 100.0 * ok / n) if n else '-'
                                  for ok, n, *_ in stats.values()]))
    for label, column in (('time to ball p50', 2), ('time to ball p90', 3), ('time to ball max', 4)):
        rows.append((label, [seconds(s[column]) for s in stats.values()]))
    errors = [sum(1 for r in results if r.mode == mode and r.error) for mode in modes]
    if any(errors):
        rows.append(('could not run', [str(e) for e in errors]))
    width = max(len(label) for label, _ in rows)
    lines = ('%-*s  %s' % (width, label, '  '.join('%-14s' % cell for cell in cells)) for label, cells in rows)
    return '\n'.join(line.rstrip() for line in lines)


def placements_for(world_file, count, seed):
    """(placements, notes): count seeded placements in the world for the robot world.launch spawns."""
    return plan_placements(load_world(world_file), launched_robot(world_file), count, seed, BALL_NAME,
                           keep_out=[ROBOT_NAME])


# -- running trials (ROS from here on, imported where a trial runs) ----------

@dataclass(frozen=True)
class WorkerSpec:
    """One launched world and one chaser in one mode, chasing a share of the placements in turn."""
    mode: str
    trials: tuple        # ((placement index, Placement), ...)
    port: int
    seed: int
    timeout: float
    reach: float
    lockstep: bool
    real_time_factor: float
    world_file: str
    log_path: str


def worker_shares(modes, jobs):
    """Workers per mode, to keep jobs of them busy."""
    return max(1, jobs // len(modes))


def worker_count(trials, modes, jobs):
    """How many workers, each with a master of its own, worker_specs makes."""
    return len(modes) * min(worker_shares(modes, jobs), trials)


def worker_specs(placements, modes, jobs, base_port, seed, timeout, reach, lockstep, real_time_factor,
                 world_file, log_dir):
    """The placements of each mode split among enough workers to keep jobs of them busy."""
    shares = worker_shares(modes, jobs)
    specs = []
    for mode in modes:
        for share in range(shares):
            trials = tuple((index, placements[index]) for index in range(share, len(placements), shares))
            if trials:
                specs.append(WorkerSpec(mode, trials, base_port + len(specs), seed, timeout, reach,
                                        lockstep, real_time_factor, world_file,
                                        os.path.join(log_dir, '%s_%d.log' % (mode, share))))
    return specs


def run_worker(spec, emit):
    """Launch the world and the chaser on spec.port, then emit(TrialResult) for each trial."""
    # Trials are local: keep every node on loopback, whatever the shell says.
    os.environ.pop('ROS_IP', None)
    os.environ['ROS_HOSTNAME'] = 'localhost'
    os.environ['ROS_MASTER_URI'] = 'http://localhost:%d' % spec.port
    pending = list(spec.trials)
    with open(spec.log_path, 'w') as log:
        launches = Launches(spec.port)
        try:
            # Never a master already running there: its parameters would mix with the trial's.
            launches.start_master(log)
            launches.launch('my_robot', 'world.launch', 'gui:=false', 'paused:=true',
                            'lockstep:=%s' % str(spec.lockstep).lower(),
                            'real_time_factor:=%g' % spec.real_time_factor, 'seed:=%d' % spec.seed,
                            'world_file:=%s' % spec.world_file, log=log)
            runs = _start_chaser(spec, launches, log)
            while pending:
                index, place = pending[0]
                wall_start = time.monotonic()
                decided, reached_at, closest = runs.run(
                    (place.robot_x, place.robot_y, place.robot_yaw), (place.ball_x, place.ball_y),
                    spec.reach, spec.timeout, TRIAL_WALL_S + 20.0 * spec.timeout, launches.alive)
                if not decided:
                    raise FlatsimError('a launched process died or sim time stalled; see %s'
                                       % spec.log_path)
                pending.pop(0)
                last = runs.watch.progress()
                emit(TrialResult(index, spec.mode, reached_at is not None, reached_at, closest,
                                 sim_s=last[0] if last else 0.0, wall_s=time.monotonic() - wall_start))
        except Exception as error:  # noqa: BLE001 - the trials it could not run are reported, not fatal to the batch
            for index, _ in pending:
                emit(TrialResult(index, spec.mode, False, None, math.inf,
                                 error='%s: %s' % (type(error).__name__, error)))
        finally:
            launches.stop()


def _start_chaser(spec, launches, log):
    import rosgraph
    import rospy

    from chase_tools.chase_graph import (CAMERA_TOPIC, PlacedRuns, chaser_ready, lockstep_ready, sim_service,
                                         wait_for_service)

    if not wait_for_service(sim_service('set_model_state'), launches):
        raise FlatsimError('the simulator did not start; see %s' % spec.log_path)
    # Only once the world's master is up: two roslaunches racing would each start one.
    launches.launch('ball_chaser', 'ball_chaser.launch', 'mode:=%s' % spec.mode, 'output:=screen', log=log)
    rospy.init_node('evaluate_trial', disable_signals=True)
    master = rosgraph.Master('/evaluate_trial')
    ready = lockstep_ready if spec.lockstep else chaser_ready
    if not wait_until(lambda: ready(master, CAMERA_TOPIC), [launches]):
        raise FlatsimError('ball_chaser did not come up; see %s' % spec.log_path)
    return PlacedRuns()


def run_trials(specs, jobs, on_result=None):
    """Results of every trial of the worker specs, by placement then mode, running up to jobs
    workers at once; SIGINT, SIGTERM or SIGHUP stop every worker and what it launched."""
    results = []
    workers = set()
    lock = threading.Lock()

    def run(spec):
        # A fresh interpreter per worker: rospy talks to one master per process.
        code = 'from chase_tools.evaluate import worker_main; worker_main()'
        proc = subprocess.Popen([sys.executable, '-c', code], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                text=True)
        with lock:
            workers.add(proc)
        proc.stdin.write(json.dumps(asdict(spec)))
        proc.stdin.close()
        seen = set()
        for line in proc.stdout:
            try:
                result = TrialResult(**json.loads(line))
            except (ValueError, TypeError):
                continue
            seen.add(result.index)
            with lock:
                results.append(result)
                if on_result is not None:
                    on_result(result)
        proc.wait()
        with lock:
            workers.discard(proc)
            for index, _ in spec.trials:
                if index not in seen:
                    result = TrialResult(index, spec.mode, False, None, math.inf,
                                         error='the worker process failed (exit status %d)' % proc.returncode)
                    results.append(result)
                    if on_result is not None:
                        on_result(result)

    pool = ThreadPoolExecutor(max_workers=jobs)
    try:
        with cleanup_on_signals():
            for future in [pool.submit(run, spec) for spec in specs]:
                future.result()
    except KeyboardInterrupt:
        pool.shutdown(wait=False, cancel_futures=True)
        with lock:
            running = list(workers)
        for proc in running:
            proc.send_signal(signal.SIGINT)
        for proc in running:
            proc.wait()
        raise
    pool.shutdown()
    modes = list(dict.fromkeys(spec.mode for spec in specs))
    return sorted(results, key=lambda r: (r.index, modes.index(r.mode)))


def worker_main():
    """Entry point of a worker process: a WorkerSpec as JSON on stdin, a TrialResult as JSON per
    line out as each trial ends."""
    fields = json.load(sys.stdin)
    fields['trials'] = tuple((index, Placement(**place)) for index, place in fields['trials'])
    spec = WorkerSpec(**fields)

    def emit(result):
        print(json.dumps(asdict(result)), flush=True)
    try:
        with cleanup_on_signals():
            run_worker(spec, emit)
    except KeyboardInterrupt:
        return


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='evaluate', description=__doc__.split('\n')[0])
    parser.add_argument('--trials', type=arguments.number(int, 1), default=10,
                        help='number of placements (each run once per mode)')
    parser.add_argument('--seed', type=arguments.seed, default=0,
                        help='seed of the placements and the sensor noise')
    parser.add_argument('--jobs', type=arguments.number(int, 1), default=os.cpu_count() or 1,
                        help='trials run at once')
    parser.add_argument('--timeout', type=arguments.positive, default=60.0,
                        help='sim seconds before a trial fails')
    parser.add_argument('--reach', type=arguments.positive, default=REACH_M,
                        help='robot base to ball centre distance that counts as reached (m)')
    parser.add_argument('--modes', nargs='+', choices=MODES, default=list(MODES),
                        help='process_image controller modes to compare')
    parser.add_argument('--world', default='', help='SDF world (default: my_robot chase_house.world)')
    parser.add_argument('--real-time', action='store_true',
                        help='run at real time without lockstep, as the course does in Gazebo')
    parser.add_argument('--real-time-factor', type=arguments.not_negative, default=None,
                        help='sim seconds per wall second (default: 0, as fast as lockstep allows; '
                             '1 with --real-time)')
    parser.add_argument('--base-port', type=arguments.port, default=BASE_PORT,
                        help='trial k runs its master on this port + k')
    parser.add_argument('--log-dir', type=arguments.output_folder, default=None,
                        help='folder for the trials\' launch logs')
    args = parser.parse_args(argv)
    # One master per worker, on consecutive ports from --base-port.
    workers = worker_count(args.trials, args.modes, args.jobs)
    if args.base_port + workers - 1 > arguments.MAX_PORT:
        parser.error('argument --base-port: %d workers need ports %d to %d, beyond %d'
                     % (workers, args.base_port, args.base_port + workers - 1, arguments.MAX_PORT))
    if args.real_time_factor is None:
        args.real_time_factor = 1.0 if args.real_time else 0.0
    return args


def evaluate(args, out=sys.stdout):
    """Run the batch that args describe; print progress and the table; return the results."""
    if args.world:
        world_file = os.path.abspath(args.world)
    else:
        from chase_tools.chase_graph import default_world_file
        world_file = default_world_file()
    placements, notes = placements_for(world_file, args.trials, args.seed)
    for note in notes:
        print('evaluate: %s' % note, file=out, flush=True)
    log_dir = args.log_dir or '/tmp/flatsim_evaluate_seed%d' % args.seed
    os.makedirs(log_dir, exist_ok=True)
    lockstep = not args.real_time
    specs = worker_specs(placements, args.modes, args.jobs, args.base_port, args.seed, args.timeout,
                         args.reach, lockstep, args.real_time_factor, world_file, log_dir)
    pace = 'lockstep' if lockstep else 'no lockstep'
    pace += ', as fast as it goes' if args.real_time_factor == 0 else ', %gx real time' % args.real_time_factor
    print('evaluate: %d placements x %d modes in %s, seed %d, %d worlds at once (%s); logs in %s'
          % (len(placements), len(args.modes), os.path.basename(world_file), args.seed,
             min(args.jobs, len(specs)), pace, log_dir), file=out, flush=True)

    def report(result):
        place = placements[result.index]
        outcome = ('reached in %.1f s' % result.time_to_ball if result.reached
                   else 'ERROR %s' % result.error if result.error
                   else 'not reached (closest %.2f m)' % result.closest)
        print('  trial %3d %-12s robot (%5.2f, %5.2f, %5.2f) ball (%5.2f, %5.2f) %.1f m: %s'
              % (result.index, result.mode, place.robot_x, place.robot_y, place.robot_yaw,
                 place.ball_x, place.ball_y, place.ball_distance, outcome), file=out, flush=True)

    wall_start = time.monotonic()
    results = run_trials(specs, args.jobs, on_result=report)
    print('evaluate: %d trials in %.0f s of wall time' % (len(results), time.monotonic() - wall_start),
          file=out, flush=True)
    print('\nreach %.2f m, timeout %g s of sim time\n%s' % (args.reach, args.timeout,
                                                             format_table(results, args.modes)),
          file=out, flush=True)
    return results


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    try:
        with cleanup_on_signals():
            results = evaluate(args)
    except FlatsimError as error:
        print('evaluate: %s' % error, file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return 0 if all(r.reached for r in results) else 1
