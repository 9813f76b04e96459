"""grade: the Go Chase It rubric, run headless on a student's submission.

  grade PATH [--trials N] [--seed S] [--json FILE] [--output DIR] [--jobs J] [--class | --one]
  grade FOLDER --output DIR [options] --slurm [sbatch options] [-- options]
  grade --gather DIR

PATH is a catkin workspace, its src folder or a repository holding the robot
package (the one with launch/world.launch) and ball_chaser, written for
Gazebo, in C++ or Python; the folder in it where the two sit together is
graded, and stray copies elsewhere are named (grading/submission.py). A
class, a folder with one submission per subfolder, is graded one subfolder
each: with --class, or when every subfolder that holds a package holds a
whole submission. Its submissions are graded up to --jobs at once, or one
Slurm array task each with --slurm (see grading/slurm.py); DIR/summary.md and
DIR/grades.csv then hold the class (see grading/gather.py).

For each submission the grader
  1. copies the robot package, ball_chaser and what they depend on into a
     throwaway overlay workspace and builds it there: message targets first,
     and once more with standard headers forced in if the compiler says some
     are missing (see grading/overlay.py);
  2. runs the rubric headless (see grading/session.py, started during the
     build) in a network namespace of its own: the world launches, the
     sensors, drive_bot's service, process_image's calls, the stop without a
     ball, and --trials seeded chases, shared among --worlds worlds when they
     take a while (grading/worlds.py);
  3. writes DIR/report.md (its wall time, and a table, one line per rubric
     item with its evidence), DIR/trial_NN.png (each chase from above), DIR/grade.json
     (also to --json FILE) and DIR/logs/.

The submission's build, launch files (with their xacro) and nodes run in a
sandbox (grading/sandbox.py): as a uid of their own, seeing only the system,
this workspace and their copy of the submission, writing only their build or
run folder, no network beyond loopback, within limits of memory, processes,
open files, file size, disk space and log volume (grading/limits.py,
grading/disk.py). A grade that is stopped (SIGTERM, SIGINT, a scheduler's
time limit) still writes its report.
Exit status: 0 when every item passed, 1 when one failed, 2 when the grader
could not run, 130 when it was stopped.
"""
import argparse
import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict, dataclass

from chase_tools import arguments
from chase_tools.grading import (course_service, formats, gather, limits, rubric, sandbox, similarity, slurm,
                                 submission, worlds)
from chase_tools.grading.evidence import decisive_lines
from chase_tools.grading.logcap import CappedLog
from chase_tools.grading.overlay import BUILD_TIMEOUT_S, Overlay
from chase_tools.grading.scratch import Scratch, read_beneath, write_new
from chase_tools.grading import session as session_module
from chase_tools.grading.session import SessionSpec
from chase_tools.placement import REACH_GAP_M
from chase_tools.procs import cleanup_on_signals

MD5_LINE = re.compile(r'_md5sum = ["\x27]([0-9a-f]{32})["\x27]')
SESSION_LOG_LINES = 15
# The session stops its three process groups, each within its own grace time.
SESSION_STOP_S = 30.0
# Wall seconds an interrupted session may take to say it heard the stop (session.heard_path);
# a busy machine can delay its signal handler by seconds.
SESSION_HEARS_S = 15.0
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)
# The session (the grader's ROS node, which every node of the submission can reach) and its
# extra worlds, in a cgroup of their own: memory per world, and processes and threads (rospy
# starts a thread per connection). Its node refuses messages larger than a camera frame; this
# holds whatever else the submission makes it hold.
SESSION_MEMORY_PER_WORLD = 1 << 30
SESSION_PROCESSES = 4096


def usable_cores():
    """The cores this process may run on: a cluster job's or a container's cpuset, not the
    machine's count."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def size(text):
    try:
        value = limits.parse_size(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    if value > limits.MAX_LIMIT:
        raise argparse.ArgumentTypeError('%s is more than the kernel can bound (%s)'
                                         % (text, limits.size_text(limits.MAX_LIMIT)))
    return value


def parse_args(argv):
    defaults = limits.Limits()
    parser = argparse.ArgumentParser(prog='grade', description=__doc__.split('\n')[0])
    parser.add_argument('path', help='a submission (workspace, src folder or repository), '
                                     'or a folder of submissions')
    parser.add_argument('--trials', type=arguments.number(int, 0), default=3,
                        help='seeded chase placements (default 3)')
    parser.add_argument('--seed', type=arguments.seed, default=0, help='seed of the placements (default 0)')
    parser.add_argument('--json', default='', metavar='FILE',
                        help='also write the result as JSON here (for a folder: a list of them)')
    parser.add_argument('--output', default='grade_report', metavar='DIR',
                        help='report folder (default ./grade_report; one subfolder per '
                             'submission for a folder of them)')
    parser.add_argument('--jobs', type=arguments.number(int, 1), default=usable_cores(),
                        help='submissions graded at once (default: one per core this process '
                             'may use)')
    parser.add_argument('--worlds', type=arguments.number(int, 1), default=None, metavar='N',
                        help='worlds the chase trials are shared among, each with its own master, '
                             'simulator and nodes (default: as many as the cores this process may '
                             'use, %d each, and the memory and process limits hold)'
                        % worlds.CORES_PER_WORLD)
    parser.add_argument('--timeout', type=arguments.positive, default=60.0,
                        help='sim seconds a chase may take (default 60)')
    parser.add_argument('--timeout-build', type=arguments.positive,
                        default=float(BUILD_TIMEOUT_S), metavar='SECONDS',
                        help='wall seconds the whole build may take (default %d)' % BUILD_TIMEOUT_S)
    parser.add_argument('--timeout-run', type=arguments.positive, default=None, metavar='SECONDS',
                        help='wall seconds the rubric run may take, from the end of the build; '
                             'the run is then stopped and the report says which step did not '
                             'finish (default: the sum of what each step may take, from '
                             '--trials and --timeout)')
    parser.add_argument('--reach', type=arguments.not_negative, default=REACH_GAP_M,
                        help='gap between the robot\'s outline and the ball\'s surface that counts '
                             'as reached (m, default %g); pushing the ball counts too' % REACH_GAP_M)
    parser.add_argument('--real-time', action='store_true',
                        help='chase in real time instead of in lockstep (sim time waiting for '
                             'the nodes after each camera frame)')
    parser.add_argument('--pass-rate', type=arguments.number(float, 0, 1), default=0.8,
                        help='share of the trials that must reach the ball for the chase item '
                             '(default 0.8)')
    parser.add_argument('--memory-limit', type=size, default=defaults.memory, metavar='SIZE',
                        help='memory of the submission\'s processes together, build and run '
                             '(default 4G)')
    parser.add_argument('--process-limit', type=arguments.number(int, 16, limits.MAX_PROCESSES),
                        default=defaults.processes,
                        metavar='N', help='processes and threads of the submission together '
                                          '(default %d)' % defaults.processes)
    parser.add_argument('--open-file-limit', type=arguments.number(int, 64, limits.max_open_files()),
                        default=defaults.open_files,
                        metavar='N', help='open files per process (default %d)' % defaults.open_files)
    parser.add_argument('--file-size-limit', type=size, default=defaults.file_size, metavar='SIZE',
                        help='size of any one file the submission writes (default 1G)')
    parser.add_argument('--disk-limit', type=size, default=defaults.disk, metavar='SIZE',
                        help='space the submission\'s files may take together, build and run '
                             '(default 2G; see docs/teaching.md for where it can be bounded)')
    parser.add_argument('--log-limit', type=size, default=defaults.log, metavar='SIZE',
                        help='what is kept of each of the submission\'s logs: the first and the '
                             'last half of it (default 2M)')
    parser.add_argument('--scratch', default='', metavar='DIR',
                        help='where the throwaway workspaces go (default: the system\'s temporary '
                             'folder)')
    parser.add_argument('--keep-scratch', action='store_true',
                        help='keep the built workspace, to look at it afterwards')
    parser.add_argument('--no-isolation', action='store_true',
                        help='run the submission without the sandbox: only inside a container '
                             'that is itself isolated (see docs/teaching.md)')
    parser.add_argument('--format', choices=formats.FORMATS, default='grade',
                        help='the format of --json FILE: the grader\'s own (default), or '
                             'gradescope: Gradescope\'s results.json (one submission)')
    parser.add_argument('--slurm', action='store_true',
                        help='grade a folder as a Slurm array job, one task per submission, and '
                             'wait for it; every argument after --slurm, up to a lone --, goes '
                             'to sbatch')
    parser.add_argument('--gather', action='store_true',
                        help='grade nothing: PATH is the --output DIR of a class grade; write '
                             'PATH/summary.md and PATH/grades.csv from its PATH/*/grade.json')
    parser.add_argument('--similar-to', default='', metavar='DIR',
                        help='also compare the code of each submission with the known solutions '
                             'in DIR (one per subfolder, or DIR itself one); pairs go to '
                             'similarity.md in the --output DIR, as a class\'s own pairs do')
    parser.add_argument('--similarity', type=arguments.number(float, 0, 1),
                        default=similarity.THRESHOLD, metavar='SHARE',
                        help='list a pair when at least this share of either one\'s code is '
                             'found in the other (default %g)' % similarity.THRESHOLD)
    kind = parser.add_mutually_exclusive_group()
    kind.add_argument('--class', dest='whole_class', action='store_true',
                      help='PATH is a class: grade each of its subfolders as a submission')
    kind.add_argument('--one', action='store_true',
                      help='PATH is one submission, even if its subfolders look like a class')
    args = parser.parse_args(argv)
    if not os.path.isdir(args.path):
        parser.error('%s is not a folder' % args.path)
    if args.similar_to and not os.path.isdir(args.similar_to):
        parser.error('--similar-to: %s is not a folder' % args.similar_to)
    if args.format != 'grade' and (args.slurm or args.gather):
        parser.error('--format %s writes one submission\'s result' % args.format)
    if args.json:
        problem = json_path_problem(args.json)
        if problem:
            parser.error('--json %s: %s' % (args.json, problem))
    return args


def json_path_problem(path):
    """Why --json FILE cannot be written, or ''; its folder is made if it is missing, now rather
    than after hours of grading."""
    if os.path.isdir(path):
        return 'is a folder; give a file name in it'
    folder = os.path.dirname(os.path.abspath(path))
    try:
        os.makedirs(folder, exist_ok=True)
    except OSError as error:
        return 'cannot make its folder %s: %s' % (folder, error.strerror or error)
    if not os.access(folder, os.W_OK):
        return 'its folder %s is not writable' % folder
    return ''


def worlds_of(args, cores=None):
    """--worlds, or as many worlds as the cores (this process's, or `cores`) and the limits hold."""
    if args.worlds is not None:
        return min(args.worlds, max(1, args.trials))
    return worlds.worlds_for(args.trials, usable_cores() if cores is None else cores,
                             args.memory_limit, args.process_limit)


def run_time_limit(args):
    """--timeout-run, or the wall seconds the rubric run may take by the bounds of its steps."""
    if args.timeout_run is not None:
        return args.timeout_run
    return session_module.run_wall_bound(args.trials, args.timeout)


def limits_of(args):
    return limits.Limits(memory=args.memory_limit, processes=args.process_limit,
                         open_files=args.open_file_limit, file_size=args.file_size_limit,
                         disk=args.disk_limit, log=args.log_limit)


def overlay_srv_md5(ws_root, package=submission.CHASER):
    """The md5 of the DriveToTarget the submission built, read from the generated code as data
    (not run; no link followed)."""
    for root, _dirs, files in os.walk(os.path.join(ws_root, 'devel')):
        if '_DriveToTarget.py' in files and root.endswith(os.path.join(package, 'srv')):
            path = os.path.relpath(os.path.join(root, '_DriveToTarget.py'), ws_root)
            try:
                found = MD5_LINE.findall(read_beneath(ws_root, path).decode(errors='replace'))
            except OSError:
                return None
            # Request, Response, then the service itself.
            return found[-1] if found else None
    return None


def grade_one(path, args, out_dir, log=sys.stdout):
    """Grade one submission into out_dir; its rubric.Grade.

    Stopped (KeyboardInterrupt: SIGINT, or SIGTERM and SIGHUP under
    cleanup_on_signals), it ends the submission's processes, writes the report
    with what it found and why it stopped, and raises GradeStopped with the grade.
    """
    started = time.monotonic()
    os.makedirs(os.path.join(out_dir, 'logs'), exist_ok=True)
    for stale in os.listdir(out_dir):
        if re.match(r'trial_\d+\.png$', stale):
            os.remove(os.path.join(out_dir, stale))
    grade = rubric.Grade(os.path.abspath(path), seed=args.seed)
    grade.isolation = isolation_text(args, None)
    found = submission.find(path)
    grade.folder, grade.ignored = found.folder, found.ignored
    if found.chaser is None or found.robot is None:
        grade.set('builds', False, 'not built: %s' % '; '.join(found.problems))
        grade.not_run('the submission is incomplete')
        grade.wall_time['total'] = round(time.monotonic() - started, 1)
        return finish(grade, out_dir, args)
    grade.notes += found.choices + found.problems
    phase, scratch, confinement, session, stopped = 'preparation', None, None, None, None
    phase_started = time.monotonic()
    try:
        scratch = Scratch.create(args.scratch or None, 'grade_%s_' % re.sub(r'\W', '_', found.name),
                                 disk_limit=None if args.no_isolation else args.disk_limit)
        confinement = confine(scratch, args)
        grade.isolation = isolation_text(args, confinement)
        phase, phase_started = 'build', time.monotonic()
        session = start_session(found, scratch, args, out_dir, confinement)
        say(log, 'building %s' % found.name)
        built = build(found, grade, scratch, args, out_dir, confinement)
        grade.wall_time['build'] = round(time.monotonic() - phase_started, 1)
        if built is not None:
            phase, phase_started = 'rubric run', time.monotonic()
            say(log, 'running the rubric on %s' % found.name)
            run_session(found, grade, scratch, args, out_dir, built, confinement, session)
            grade.wall_time['rubric_run'] = round(time.monotonic() - phase_started, 1)
    except KeyboardInterrupt as error:
        stopped = error
        why = 'the grade was stopped by %s during the %s' % (stop_signal_name(error), phase)
        grade.notes.append('%s, after %.0f s; the items not yet graded are failed'
                           % (why, time.monotonic() - started))
        if phase == 'build' and grade.item('builds') is None:
            grade.set('builds', False, 'not finished: %s' % why)
        if phase in ('build', 'rubric run'):
            grade.wall_time[phase.replace(' ', '_')] = round(time.monotonic() - phase_started, 1)
        grade.not_run(why)
    finally:
        with signals_held():
            if session is not None:
                end_session(session, wrapped=not args.no_isolation)
                session.end()
            if confinement is not None:
                sandbox.end_sandbox(confinement)
                confinement.cgroups.remove()
            if scratch is not None:
                if args.keep_scratch:
                    grade.notes.append('workspace kept in %s' % scratch.top)
                scratch.close(keep=args.keep_scratch)
            grade.wall_time['total'] = round(time.monotonic() - started, 1)
            finish(grade, out_dir, args)
    if stopped is not None:
        raise GradeStopped(str(stopped), grade=grade)
    return grade


class GradeStopped(KeyboardInterrupt):
    """A grade stopped by a signal, with what it had found: a submission's grade, or a class's
    rows (gather.Row)."""

    def __init__(self, why, grade=None, rows=None):
        super().__init__(why)
        self.grade, self.rows = grade, rows


def say(log, text):
    print('grade: %s' % text, file=log, flush=True)


def stop_signal_name(error):
    """'SIGTERM' for cleanup_on_signals' KeyboardInterrupt('signal 15'), 'SIGINT' for Ctrl-C."""
    text = str(error)
    if text.startswith('signal '):
        try:
            return signal.Signals(int(text.split()[1])).name
        except ValueError:
            return text
    return 'SIGINT'


@contextlib.contextmanager
def signals_held():
    """Within the block, a further stop signal waits: the report is written whole first."""
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def confine(scratch, args):
    """The submission's Confinement (None with --no-isolation), its cgroups made and the
    scratch folders its sandboxes write handed to its uid."""
    if args.no_isolation:
        return None
    wanted = limits_of(args)
    cgroups = limits.Cgroups.create('grade_%d' % os.getpid(), wanted)
    confinement = sandbox.Confinement.create(scratch.grader, wanted, cgroups, scratch.disk)
    with tempfile.TemporaryDirectory(prefix='grade_userns_') as trial:
        sandbox.close_userns_where_possible(confinement, os.path.join(trial, 'box'))
    if confinement.switch_user:
        scratch.owner = (confinement.uid, confinement.gid)
    scratch.hand_over(scratch.run)
    return confinement


def isolation_text(args, confinement):
    if args.no_isolation:
        return 'none (--no-isolation): the container must isolate the submission and bound its disk'
    if confinement is None:
        return 'bubblewrap (not set up: the grade stopped before)'
    return ('bubblewrap, %s; sees only the system (/usr, /bin, /lib, part of /etc), this workspace '
            'and its own copy of the submission, all read-only; writes only its build folder while '
            'it builds and its run folder while its nodes run; no network beyond loopback; its own '
            'process, IPC and host-name namespaces' % confinement.describe())


def build(found, grade, scratch, args, out_dir, confinement):
    """Build the submission's packages; the Overlay when it built, else None (builds failed)."""
    box = None if confinement is None else sandbox.Sandbox(
        scratch.build, visible=sandbox.environment_paths(os.environ), own_network=True,
        confinement=confinement)
    overlay = Overlay(scratch.workspace, sandbox=box)
    shadowing = submission.named_like_ours(found)
    if shadowing:
        one = len(shadowing) == 1
        grade.set('builds', False, 'not built: the submission\'s package%s %s ha%s the name of a '
                  'package of the grader\'s own (the simulator, its stand-ins for Gazebo\'s '
                  'packages and the grader), which it would take the place of; rename %s or '
                  'leave %s out of the submission'
                  % ('' if one else 's', ', '.join(shadowing), 's' if one else 've',
                     'it' if one else 'them', 'it' if one else 'them'))
        grade.not_run('the build failed')
        return None
    before = usage(confinement)
    try:
        copied, left_out = submission.copy_packages(found, overlay.src)
    except (OSError, ValueError) as error:
        grade.set('builds', False, 'not built: the submission could not be copied into the grader\'s '
                  'workspace: %s%s' % (getattr(error, 'strerror', None) or error,
                                       limit_evidence(confinement, before, 'the copy of the submission')))
        grade.not_run('the build failed')
        return None
    overlay.packages = set(copied)
    if left_out:
        grade.notes.append('links left out of the grader\'s copy (roslaunch would follow them '
                           'out of the submission): %s' % '; '.join(left_out))
    scratch.hand_over(scratch.build)
    before = usage(confinement)
    outcome = overlay.build_robustly(timeout=args.timeout_build)
    with open(os.path.join(out_dir, 'logs', 'build.log'), 'w') as stream:
        stream.write(outcome.log)
    skipped = sorted(set(found.packages) - set(copied))
    evidence = 'packages %s: %s' % (', '.join(sorted(copied)), '; '.join(outcome.steps))
    if outcome.timed_out:
        evidence = 'packages %s: the build did not finish within %g s (--timeout-build); %s' % (
            ', '.join(sorted(copied)), args.timeout_build, '; '.join(outcome.steps[:-1]) or 'killed')
    if skipped:
        evidence += '; not built (not needed by them): %s' % ', '.join(skipped)
    evidence += limit_evidence(confinement, before, 'the build')
    if usage(confinement).since(before).disk_full:
        # Whether or not make noticed: what the build could not write may be missing.
        outcome.passed = False
    if outcome.cut:
        evidence += '; %s of its output not kept (see logs/build.log)' % limits.size_text(outcome.cut)
    if confinement is not None:
        left = sandbox.end_sandbox(confinement)
        if left:
            grade.notes.append('%d process%s of the build still ran after it (%s); they were killed'
                               % (len(left), '' if len(left) == 1 else 'es', ', '.join(left)))
    linked = scratch.linked([scratch.workspace, overlay.src, os.path.join(overlay.root, 'devel')]
                            + list(copied.values()))
    if linked:
        outcome.passed = False
        evidence += ('; the build put links in place of %s, which the grader does not follow'
                     % ', '.join(os.path.relpath(path, scratch.build) for path in linked))
    if not outcome.passed:
        grade.set('builds', False, evidence + '; see logs/build.log',
                  ['  ' + line for line in decisive_lines(outcome.log, 'logs/build.log')])
        grade.not_run('the build failed')
        return None
    grade.set('builds', True, evidence)
    return overlay


def usage(confinement):
    return confinement.usage() if confinement is not None else limits.Usage()


def limit_evidence(confinement, before, where):
    """'; the build hit the memory limit of 4 GiB (...)', or '' when no limit was hit."""
    if confinement is None:
        return ''
    hit = limits.hit_text(usage(confinement).since(before), confinement.limits, where)
    return '; ' + hit if hit else ''


@dataclass
class EarlySession:
    """The rubric run's session, started before the build (start_session)."""
    proc: subprocess.Popen
    log: object                     # its logs/session.log, open
    result_path: str
    cgroups: limits.Cgroups = None  # its own (session_cgroups), when they could be made
    memory: int = 0

    def limit_text(self):
        """'; the session hit its memory limit of 2 GiB (...)', or ''."""
        if self.cgroups is None or not self.cgroups.active:
            return ''
        hit = limits.hit_text(self.cgroups.usage(), limits.Limits(memory=self.memory,
                                                                 processes=SESSION_PROCESSES),
                              'the grader\'s session')
        return '; ' + hit if hit else ''

    def end(self):
        if self.cgroups is not None and self.cgroups.active:
            self.cgroups.kill_all()
            self.cgroups.remove()


def session_cgroups(worlds_count):
    """(Cgroups, memory) of a session of worlds_count worlds: bounded, unless none can be made."""
    memory = SESSION_MEMORY_PER_WORLD * worlds_count
    return (limits.Cgroups.create('grade_session_%d' % os.getpid(),
                                  limits.Limits(memory=memory, processes=SESSION_PROCESSES)), memory)


def start_session(found, scratch, args, out_dir, confinement):
    """The session of the rubric run, started now so that its master and its imports are ready
    when the build is; it waits for the built workspace (run_session) or its end (end_session)."""
    spec = SessionSpec(overlay_env={}, overlay_root=scratch.workspace, run_scratch=scratch.run,
                       out_dir=os.path.abspath(out_dir), robot_package=found.robot.name,
                       chaser_package=found.chaser.name, trials=args.trials, seed=args.seed,
                       timeout=args.timeout, reach=args.reach, pass_rate=args.pass_rate,
                       isolate=not args.no_isolation,
                       lockstep=not args.real_time,
                       master_port=worlds.free_port() if args.no_isolation else 11311,
                       worlds=worlds_of(args),
                       confinement=confinement.as_json() if confinement is not None else None,
                       grader_dir=scratch.grader, caches_dir=scratch.caches, await_build=True)
    spec_path = os.path.join(scratch.grader, 'session.json')
    result_path = os.path.join(scratch.grader, 'result.json')
    write_new(spec_path, json.dumps(asdict(spec)))
    cmd = [sys.executable, '-m', 'chase_tools.grading.session', spec_path, result_path]
    cgroups, memory = None, 0
    if not args.no_isolation:
        cmd = sandbox.network_namespace_command(cmd)
        if confinement is not None and confinement.switch_user:
            cgroups, memory = session_cgroups(spec.worlds)
            cmd = limits.join_command(cgroups.procs_files()) + cmd
    # What the grader's node logs there, the submission can make it log (a connection refused,
    # a message too large): kept as a launch's log is.
    log = CappedLog(os.path.join(out_dir, 'logs', 'session.log'), args.log_limit, mode='wb')
    try:
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True, text=True)
    finally:
        log.started()
    return EarlySession(proc, log, result_path, cgroups, memory)


def end_session(session, wrapped):
    """A session whose workspace never came: told so (the end of its input), it stops its master."""
    if session.proc.poll() is None:
        try:
            session.proc.stdin.close()
            session.proc.wait(SESSION_STOP_S)
        except (OSError, subprocess.TimeoutExpired):
            stop_session(session.proc, wrapped)
    session.log.close()


def run_session(found, grade, scratch, args, out_dir, overlay, confinement, session):
    md5, course = overlay_srv_md5(overlay.root), course_service.COURSE_MD5
    chain = submission.chaser_launch_includes_world(found, overlay.src)
    if chain:
        through = ' (through %s)' % ', '.join(chain[1:-1]) if len(chain) > 2 else ''
        grade.notes.append('%s includes %s%s, so ball_chaser.launch was launched alone, as the '
                           'submission runs it, and world.launch was not launched before it'
                           % (chain[0], chain[-1], through))
    try:
        overlay_env = overlay.env()
    except RuntimeError as error:
        grade.notes.append(str(error))
        grade.not_run('the built workspace could not be sourced')
        return
    if md5 not in (course, None):
        grade.notes.append('the submission\'s DriveToTarget (md5 %s) is not the course\'s (md5 %s)'
                           % (md5, course))
    proc, result_path = session.proc, session.result_path
    session_log = session.log.name
    before = usage(confinement)
    stopped = None
    # How the run was cut short, said after "the grade was stopped" wherever the session says it.
    how = ''
    limit = run_time_limit(args)
    try:
        try:
            proc.stdin.write(json.dumps({'overlay_env': overlay_env,
                                         'chaser_launches_world': bool(chain)}) + '\n')
            proc.stdin.close()
        except OSError:
            pass                    # it has ended: its log says why
        try:
            proc.wait(limit)
        except subprocess.TimeoutExpired:
            how = 'at the time limit of the rubric run (%g s, --timeout-run)' % limit
            grade.notes.append('the rubric run did not finish within %g s (--timeout-run%s), so it '
                               'was stopped; the items not yet graded are failed'
                               % (limit, '' if args.timeout_run is not None else ': by default '
                                  'the sum of what each of its steps may take'))
            with signals_held():
                stop_running_session(proc, result_path, confinement, args)
    except KeyboardInterrupt as error:
        stopped = error
        how = 'by %s during the rubric run' % stop_signal_name(error)
        with signals_held():
            stop_running_session(proc, result_path, confinement, args)
    session.log.close()
    hit = limit_evidence(confinement, before, 'the submission\'s nodes')
    try:
        with open(result_path) as stream:
            result = rubric.Grade.from_json(json.load(stream))
    except (OSError, ValueError, TypeError) as error:
        if stopped is not None:
            raise stopped
        with open(session_log, errors='replace') as stream:
            tail = stream.read().splitlines()[-SESSION_LOG_LINES:]
        ended = exit_text(proc.returncode) + session.limit_text()
        if how:
            grade.not_run('%s %s' % (session_module.STOPPED, how))
        grade.not_run('the grading session failed (%s, %s); see logs/session.log' % (ended, error))
        grade.set('world_launches', False, 'the grading session failed (%s); see '
                  'logs/session.log%s' % (ended, hit), ['  ' + line for line in tail])
        return
    for item in result.items:
        if item.name == 'builds':
            continue
        evidence = item.evidence
        if how:
            evidence = stopped_how(evidence, how)
        if hit and not item.passed and not evidence.startswith('not run'):
            first, newline, rest = evidence.partition('\n')
            evidence = first + hit + newline + rest
        grade.put(rubric.Item(item.name, item.passed, evidence))
    grade.trials, grade.reach, grade.worlds = result.trials, result.reach, result.worlds
    grade.notes += [stopped_how(note, how) if how else note for note in result.notes]
    grade.advisories += result.advisories
    if hit:
        grade.notes.append(hit[2:])
    if stopped is not None:
        raise stopped


def stopped_how(text, how):
    """The session's "not run: the grade was stopped" (or "not finished: ...", or its note of the
    step under way) with how it was stopped."""
    if not text.startswith(('not run: ', 'not finished: ', 'the step ')):
        return text
    return text.replace(session_module.STOPPED, '%s %s' % (session_module.STOPPED, how), 1)


def stop_running_session(proc, result_path, confinement, args):
    """Stop the session under way: it says it heard of it before the submission is killed (an
    item it judged on a submission that the stop was killing would read as the student's
    failure), then the submission, which needs no clean shutdown, so that the session stops at
    once."""
    interrupt_session(proc, wrapped=not args.no_isolation)
    heard = session_module.heard_path(result_path)
    deadline = time.monotonic() + SESSION_HEARS_S
    while time.monotonic() < deadline and proc.poll() is None and not os.path.exists(heard):
        time.sleep(0.05)
    if confinement is not None:
        sandbox.end_sandbox(confinement)
    wait_session(proc)


def exit_text(status):
    """'exit 1', or 'killed by SIGKILL' for a process a signal ended."""
    if status is not None and status < 0:
        try:
            return 'killed by %s' % signal.Signals(-status).name
        except ValueError:
            return 'killed by signal %d' % -status
    return 'exit %s' % status


def stop_session(proc, wrapped):
    interrupt_session(proc, wrapped)
    wait_session(proc)


def interrupt_session(proc, wrapped):
    """SIGINT lets the session stop its master, world and nodes; a kill would orphan them.

    Only the session itself gets it: bubblewrap around it would die of it, and
    its --die-with-parent would then kill the session mid-stop.
    """
    for pid in sandbox.child_pids(proc.pid) if wrapped else [proc.pid]:
        try:
            os.kill(pid, signal.SIGINT)
        except ProcessLookupError:
            pass


def wait_session(proc):
    try:
        proc.wait(SESSION_STOP_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()


def finish(grade, out_dir, args):
    grade.not_run('an earlier step failed')
    rubric.write_markdown(grade, os.path.join(out_dir, 'report.md'))
    rubric.write_json(grade, os.path.join(out_dir, 'grade.json'))
    return grade


def grade_folder(paths, args):
    """Grade many submissions, each in a process of its own, up to --jobs at once.

    The class's summary.md and grades.csv are written again as each submission finishes, so a
    class grade that is stopped, or killed, keeps every result it had. A stop signal goes on
    to each running grader, which stops what it started and writes its report; the submissions
    not yet started are rows that say the class grade was stopped before their turn."""
    os.makedirs(args.output, exist_ok=True)
    names = unique_names(paths)
    # Each build, and each submission's worlds, get its share of the cores.
    share = max(1, usable_cores() // args.jobs)
    env = dict(os.environ, ROS_PARALLEL_JOBS='-j%d' % share)

    running, stop_reason, lock = set(), [], threading.Lock()
    finished = {}
    started = time.monotonic()

    def write_so_far():
        rows = [finished.get(name) or gather.Row(name, None, 'not finished yet: the class grade '
                                                 'is still running')
                for name in names]
        gather.write(args.output, rows, 'Graded %d at a time; %d of %d finished after %.0f s.'
                     % (args.jobs, len(finished), len(names), time.monotonic() - started))

    def one(item):
        path, name = item
        out_dir = os.path.join(args.output, name)
        cmd = [sys.executable, '-m', 'chase_tools.grading.cli', path, '--output', out_dir]
        cmd += submission_args(args, cores=share)
        # Started and registered under the lock that the stop takes: none starts unstopped.
        with lock:
            if stop_reason:
                # Not what an earlier grade may have left in its folder.
                return gather.Row(name, None, stop_reason[0])
            os.makedirs(out_dir, exist_ok=True)
            with open(os.path.join(out_dir, gather.LOG_FILE), 'w') as log:
                proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
            running.add(proc)
        proc.wait()
        with lock:
            running.discard(proc)
        row = gather.read(args.output, name)
        with lock:
            finished[name] = row
            if not stop_reason:
                write_so_far()
        print('%-30s %s' % (name, gather.row_line(row)), flush=True)
        return row

    stopped = None
    pool = ThreadPoolExecutor(max_workers=args.jobs)
    futures = [pool.submit(one, item) for item in zip(paths, names)]
    try:
        for future in futures:
            future.result()
    except KeyboardInterrupt as error:
        stopped = error
        name = stop_signal_name(error)
        # Each grader stops what it started and writes its report; the rest do not start.
        with signals_held():
            with lock:
                stop_reason.append('the class grade was stopped by %s before its turn' % name)
                for proc in list(running):
                    proc.send_signal(getattr(signal, name, signal.SIGINT))
            pool.shutdown(wait=True)
    with signals_held():
        pool.shutdown(wait=True)
        rows = [future.result() for future in futures]
        gather.write(args.output, rows, 'Graded %d at a time in %.0f s%s.'
                     % (args.jobs, time.monotonic() - started,
                        ', then stopped by %s' % stop_signal_name(stopped) if stopped else ''))
    if stopped is not None:
        raise GradeStopped(str(stopped), rows=rows)
    return rows


def compare_code(args, named_paths):
    """similarity.md and similarity.html in the --output DIR: for a class, and for any grade
    with --similar-to. Before the grading, from the submissions' files alone; the line that
    says what it found ('' when it did not compare), printed once the grade is over, so that
    the grade's own first lines stay first (a Slurm job's number, say)."""
    if len(named_paths) < 2 and not args.similar_to:
        return ''
    known = {}
    if args.similar_to:
        known_paths = similarity.known_solutions(args.similar_to)
        known = dict(zip(['known:%s' % name for name in unique_names(known_paths)], known_paths))
    os.makedirs(args.output, exist_ok=True)
    os.environ.setdefault('MPLBACKEND', 'Agg')     # copydetect imports matplotlib
    try:
        pairs = similarity.write(args.output, named_paths, known, args.similarity)
    except Exception as error:  # evidence only: a failure of the comparison never stops the grade
        return 'grade: the code of the submissions could not be compared: %s: %s' % (
            type(error).__name__, error)
    return 'grade: %d pair%s of submissions with unusually similar code; see %s' % (
        len(pairs), '' if len(pairs) == 1 else 's', os.path.join(args.output, similarity.MARKDOWN_FILE))


def submission_args(args, cores=None):
    """The options a class grade passes on to the grade of each submission (one each). cores:
    the cores each has, when known here (graded on this machine, --jobs at once); else each
    chooses its worlds from its own (a Slurm task's CPUs)."""
    forwarded = ['--one', '--trials', str(args.trials), '--seed', str(args.seed), '--jobs', '1',
                 '--timeout', str(args.timeout), '--reach', str(args.reach),
                 '--pass-rate', str(args.pass_rate), '--timeout-build', str(args.timeout_build),
                 '--memory-limit', str(args.memory_limit), '--process-limit', str(args.process_limit),
                 '--open-file-limit', str(args.open_file_limit),
                 '--file-size-limit', str(args.file_size_limit), '--disk-limit', str(args.disk_limit),
                 '--log-limit', str(args.log_limit)]
    if args.worlds is not None or cores is not None:
        forwarded += ['--worlds', str(worlds_of(args, cores))]
    if args.timeout_run is not None:
        forwarded += ['--timeout-run', str(args.timeout_run)]
    if args.scratch:
        forwarded += ['--scratch', os.path.abspath(args.scratch)]
    for flag in ('no_isolation', 'keep_scratch', 'real_time'):
        if getattr(args, flag):
            forwarded.append('--' + flag.replace('_', '-'))
    return forwarded


def unique_names(paths):
    names, seen = [], {}
    for path in paths:
        base = re.sub(r'[^\w.-]', '_', os.path.basename(os.path.abspath(path))) or 'submission'
        seen[base] = seen.get(base, 0) + 1
        names.append(base if seen[base] == 1 else '%s_%d' % (base, seen[base]))
    return names


def submission_paths(args):
    """The submissions to grade: [PATH], or the subfolders of a class."""
    if args.one:
        return [args.path]
    paths = submission.submissions_in(args.path, args.whole_class)
    if paths == [args.path]:
        whole = submission.complete_subfolders(args.path)
        if len(whole) >= 2:
            print('grade: %d subfolders of %s hold a whole submission, but not every one that '
                  'holds a package: grading it as one submission; pass --class to grade each '
                  'subfolder' % (len(whole), args.path), flush=True)
    return paths


def main(argv=None):
    argv, sbatch_options = slurm.split_argv(sys.argv[1:] if argv is None else argv)
    args = parse_args(argv)
    if args.gather:
        return gather.gather_folder(args.path, args.json)
    # With --slurm each task checks on its own node.
    if not args.no_isolation and not args.slurm:
        problem = sandbox.check()
        if problem:
            print('grade: cannot isolate the submission: %s' % problem, file=sys.stderr)
            return 2
    paths = submission_paths(args)
    if not paths:
        print('grade: %s has no subfolders to grade as a class' % args.path, file=sys.stderr)
        return 2
    names = unique_names(paths)
    started = time.monotonic()
    compared = ['']
    try:
        with cleanup_on_signals():
            compared[0] = compare_code(args, dict(zip(names, paths)))
            if args.slurm:
                rows = slurm.grade_class(args.output, names, paths, submission_args(args), sbatch_options)
                return gather.status(rows, args.json, dict(zip(names, paths)))
            if paths != [args.path]:
                if args.format != 'grade':
                    print('grade: --format %s writes one submission\'s result, and %s holds %d'
                          % (args.format, args.path, len(paths)), file=sys.stderr)
                    return 2
                print('grade: %d submissions in %s, %d at a time' % (len(paths), args.path, args.jobs),
                      flush=True)
                return gather.status(grade_folder(paths, args), args.json, dict(zip(names, paths)))
            grade = grade_one(args.path, args, args.output)
    except GradeStopped as stop:
        if stop.rows is not None:
            gather.status(stop.rows, args.json, dict(zip(names, paths)))
        elif stop.grade is not None and args.json:
            formats.write(stop.grade, args.json, args.format, time.monotonic() - started)
        print('grade: stopped; the report says how far it got', file=sys.stderr)
        return 130
    except KeyboardInterrupt:
        return 130
    finally:
        if compared[0]:
            print(compared[0], flush=True)
    print(rubric.markdown(grade))
    if args.json:
        formats.write(grade, args.json, args.format, time.monotonic() - started)
    return 0 if grade.passed else 1


if __name__ == '__main__':
    sys.exit(main())
