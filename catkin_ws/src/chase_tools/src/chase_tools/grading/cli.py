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
  2. runs the rubric headless (see grading/session.py) in a network namespace
     of its own: the world launches, the sensors, drive_bot's service,
     process_image's calls, the stop without a ball, and --trials seeded
     chases;
  3. writes DIR/report.md (a table, one line per rubric item with its
     evidence), DIR/trial_NN.png (each chase from above), DIR/grade.json
     (also to --json FILE) and DIR/logs/.

The submission's build, launch files (with their xacro) and nodes run in a
sandbox (grading/sandbox.py): no network beyond loopback, no writes outside
their scratch folder. Exit status: 0 when every item passed, 1 when one
failed, 2 when the grader could not run.
"""
import argparse
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import asdict

from chase_tools.grading import formats, gather, rubric, sandbox, slurm, submission
from chase_tools.grading.evidence import decisive_lines
from chase_tools.grading.overlay import Overlay
from chase_tools.grading.session import SessionSpec
from chase_tools.placement import REACH_GAP_M
from chase_tools.procs import cleanup_on_signals

MD5_LINE = re.compile(r'_md5sum = ["\x27]([0-9a-f]{32})["\x27]')
SESSION_LOG_LINES = 15
# The session stops its three process groups, each within its own grace time.
SESSION_STOP_S = 30.0


def usable_cores():
    """The cores this process may run on: a cluster job's or a container's cpuset, not the
    machine's count."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def parse_args(argv):
    parser = argparse.ArgumentParser(prog='grade', description=__doc__.split('\n')[0])
    parser.add_argument('path', help='a submission (workspace, src folder or repository), '
                                     'or a folder of submissions')
    parser.add_argument('--trials', type=int, default=3, help='seeded chase placements (default 3)')
    parser.add_argument('--seed', type=int, default=0, help='seed of the placements (default 0)')
    parser.add_argument('--json', default='', metavar='FILE',
                        help='also write the result as JSON here (for a folder: a list of them)')
    parser.add_argument('--output', default='grade_report', metavar='DIR',
                        help='report folder (default ./grade_report; one subfolder per '
                             'submission for a folder of them)')
    parser.add_argument('--jobs', type=int, default=usable_cores(),
                        help='submissions graded at once (default: one per core this process '
                             'may use)')
    parser.add_argument('--timeout', type=float, default=60.0,
                        help='sim seconds a chase may take (default 60)')
    parser.add_argument('--reach', type=float, default=REACH_GAP_M,
                        help='gap between the robot\'s outline and the ball\'s surface that counts '
                             'as reached (m, default %g); pushing the ball counts too' % REACH_GAP_M)
    parser.add_argument('--real-time', action='store_true',
                        help='chase in real time instead of in lockstep (sim time waiting for '
                             'the nodes after each camera frame)')
    parser.add_argument('--pass-rate', type=float, default=0.8,
                        help='share of the trials that must reach the ball for the chase item '
                             '(default 0.8)')
    parser.add_argument('--scratch', default='', metavar='DIR',
                        help='where the throwaway workspaces go (default: the system\'s temporary '
                             'folder)')
    parser.add_argument('--keep-scratch', action='store_true',
                        help='keep the built workspace, to look at it afterwards')
    parser.add_argument('--no-isolation', action='store_true',
                        help='run the submission without the sandbox: only inside a container '
                             'that is itself isolated (see the README)')
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
    kind = parser.add_mutually_exclusive_group()
    kind.add_argument('--class', dest='whole_class', action='store_true',
                      help='PATH is a class: grade each of its subfolders as a submission')
    kind.add_argument('--one', action='store_true',
                      help='PATH is one submission, even if its subfolders look like a class')
    args = parser.parse_args(argv)
    if args.trials < 0 or args.jobs < 1 or args.timeout <= 0 or args.reach < 0:
        parser.error('--trials must be at least 0, --jobs at least 1, --timeout positive and '
                     '--reach not negative')
    if not 0.0 <= args.pass_rate <= 1.0:
        parser.error('--pass-rate must lie between 0 and 1')
    if not os.path.isdir(args.path):
        parser.error('%s is not a folder' % args.path)
    if args.format != 'grade' and (args.slurm or args.gather):
        parser.error('--format %s writes one submission\'s result' % args.format)
    return args


def course_md5():
    from ball_chaser.srv import DriveToTarget
    return DriveToTarget._md5sum


def overlay_srv_md5(ws_root, package=submission.CHASER):
    """The md5 of the DriveToTarget the submission built, read from the generated code (not run)."""
    for root, _dirs, files in os.walk(os.path.join(ws_root, 'devel')):
        if '_DriveToTarget.py' in files and root.endswith(os.path.join(package, 'srv')):
            with open(os.path.join(root, '_DriveToTarget.py'), errors='replace') as stream:
                found = MD5_LINE.findall(stream.read())
            # Request, Response, then the service itself.
            return found[-1] if found else None
    return None


def free_port():
    with socket.socket() as sock:
        sock.bind(('127.0.0.1', 0))
        return sock.getsockname()[1]


def grade_one(path, args, out_dir, log=sys.stdout):
    """Grade one submission into out_dir; its rubric.Grade."""
    os.makedirs(os.path.join(out_dir, 'logs'), exist_ok=True)
    for stale in os.listdir(out_dir):
        if re.match(r'trial_\d+\.png$', stale):
            os.remove(os.path.join(out_dir, stale))
    grade = rubric.Grade(os.path.abspath(path), seed=args.seed)
    grade.isolation = ('none (--no-isolation): the container must isolate the submission'
                       if args.no_isolation else
                       'bubblewrap: read-only root, writes only to its scratch folder, no network '
                       'beyond loopback, own process namespace, no capabilities')
    found = submission.find(path)
    grade.folder, grade.ignored = found.folder, found.ignored
    if found.chaser is None or found.robot is None:
        grade.set('builds', False, 'not built: %s' % '; '.join(found.problems))
        grade.not_run('the submission is incomplete')
        return finish(grade, out_dir, args)
    grade.notes += found.choices + found.problems
    scratch = tempfile.mkdtemp(prefix='grade_%s_' % re.sub(r'\W', '_', found.name),
                               dir=args.scratch or None)
    started = time.monotonic()
    try:
        built = build(found, grade, scratch, args, out_dir)
        build_s = time.monotonic() - started
        if built is not None:
            run_session(found, grade, scratch, args, out_dir, built)
        grade.notes.append('graded in %.0f s of wall time (build %.0f s, rubric run %.0f s)'
                           % (time.monotonic() - started, build_s, time.monotonic() - started - build_s))
    finally:
        if args.keep_scratch:
            grade.notes.append('workspace kept in %s' % scratch)
        else:
            shutil.rmtree(scratch, ignore_errors=True)
    return finish(grade, out_dir, args)


def build(found, grade, scratch, args, out_dir):
    """Build the submission's packages; the Overlay when it built, else None (builds failed)."""
    box = None if args.no_isolation else sandbox.Sandbox(
        scratch, visible=sandbox.environment_paths(os.environ), own_network=True)
    overlay = Overlay(os.path.join(scratch, 'ws'), sandbox=box)
    copied, left_out = submission.copy_packages(found, overlay.src)
    if left_out:
        grade.notes.append('links left out of the grader\'s copy (roslaunch would follow them '
                           'out of the submission): %s' % '; '.join(left_out))
    skipped = sorted(set(found.packages) - set(copied))
    outcome = overlay.build_robustly()
    with open(os.path.join(out_dir, 'logs', 'build.log'), 'w') as stream:
        stream.write(outcome.log)
    evidence = 'packages %s: %s' % (', '.join(sorted(copied)), '; '.join(outcome.steps))
    if skipped:
        evidence += '; not built (not needed by them): %s' % ', '.join(skipped)
    if not outcome.passed:
        grade.set('builds', False, evidence + '; see logs/build.log',
                  ['  ' + line for line in decisive_lines(outcome.log, 'logs/build.log')])
        grade.not_run('the build failed')
        return None
    grade.set('builds', True, evidence)
    return overlay


def run_session(found, grade, scratch, args, out_dir, overlay):
    run_scratch = os.path.join(scratch, 'run')
    os.makedirs(run_scratch, exist_ok=True)
    md5, course = overlay_srv_md5(overlay.root), course_md5()
    chain = submission.chaser_launch_includes_world(found)
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
    spec = SessionSpec(overlay_env=overlay_env, overlay_root=overlay.root, run_scratch=run_scratch,
                       out_dir=os.path.abspath(out_dir), robot_package=found.robot.name,
                       chaser_package=found.chaser.name, trials=args.trials, seed=args.seed,
                       timeout=args.timeout, reach=args.reach, pass_rate=args.pass_rate,
                       isolate=not args.no_isolation,
                       lockstep=not args.real_time,
                       chaser_launches_world=bool(chain),
                       master_port=free_port() if args.no_isolation else 11311)
    if md5 not in (course, None):
        grade.notes.append('the submission\'s DriveToTarget (md5 %s) is not the course\'s (md5 %s)'
                           % (md5, course))
    spec_path, result_path = os.path.join(scratch, 'session.json'), os.path.join(scratch, 'result.json')
    with open(spec_path, 'w') as stream:
        json.dump(asdict(spec), stream)
    cmd = [sys.executable, '-m', 'chase_tools.grading.session', spec_path, result_path]
    if not args.no_isolation:
        cmd = sandbox.network_namespace_command(cmd)
    session_log = os.path.join(out_dir, 'logs', 'session.log')
    with open(session_log, 'w') as stream:
        proc = subprocess.Popen(cmd, stdout=stream, stderr=subprocess.STDOUT, start_new_session=True)
        try:
            proc.wait()
        except KeyboardInterrupt:
            stop_session(proc, wrapped=not args.no_isolation)
            raise
    try:
        with open(result_path) as stream:
            result = rubric.Grade.from_json(json.load(stream))
    except (OSError, ValueError, TypeError) as error:
        with open(session_log, errors='replace') as stream:
            tail = stream.read().splitlines()[-SESSION_LOG_LINES:]
        grade.not_run('the grading session failed (exit %d, %s); see logs/session.log'
                      % (proc.returncode, error))
        grade.set('world_launches', False, 'the grading session failed (exit %d); see '
                  'logs/session.log' % proc.returncode, ['  ' + line for line in tail])
        return
    for item in result.items:
        if item.name != 'builds':
            grade.set(item.name, item.passed, item.evidence)
    grade.trials, grade.reach = result.trials, result.reach
    grade.notes += result.notes


def stop_session(proc, wrapped):
    """SIGINT lets the session stop its master, world and nodes; a kill would orphan them.

    Only the session itself gets it: bubblewrap around it would die of it, and
    its --die-with-parent would then kill the session mid-stop.
    """
    pids = child_pids(proc.pid) if wrapped else [proc.pid]
    try:
        for pid in pids:
            os.kill(pid, signal.SIGINT)
        proc.wait(SESSION_STOP_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
    except ProcessLookupError:
        pass


def child_pids(pid):
    try:
        with open('/proc/%d/task/%d/children' % (pid, pid)) as stream:
            return [int(child) for child in stream.read().split()]
    except OSError:
        return []


def finish(grade, out_dir, args):
    grade.not_run('an earlier step failed')
    rubric.write_markdown(grade, os.path.join(out_dir, 'report.md'))
    rubric.write_json(grade, os.path.join(out_dir, 'grade.json'))
    return grade


def grade_folder(paths, args):
    """Grade many submissions, each in a process of its own, up to --jobs at once."""
    os.makedirs(args.output, exist_ok=True)
    names = unique_names(paths)
    # Each build gets its share of the cores.
    env = dict(os.environ, ROS_PARALLEL_JOBS='-j%d' % max(1, usable_cores() // args.jobs))

    running, stopping = set(), threading.Event()

    def one(item):
        path, name = item
        if stopping.is_set():
            return None
        out_dir = os.path.join(args.output, name)
        cmd = [sys.executable, '-m', 'chase_tools.grading.cli', path, '--output', out_dir]
        cmd += submission_args(args)
        os.makedirs(out_dir, exist_ok=True)
        with open(os.path.join(out_dir, gather.LOG_FILE), 'w') as log:
            proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)
            running.add(proc)
            proc.wait()
            running.discard(proc)
        row = gather.read(args.output, name)
        print('%-30s %s' % (name, gather.row_line(row)), flush=True)
        return row

    started = time.monotonic()
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        try:
            rows = list(pool.map(one, zip(paths, names)))
        except KeyboardInterrupt:
            # Each grader stops what it started on SIGINT; the pool then waits for them.
            stopping.set()
            for proc in list(running):
                proc.send_signal(signal.SIGINT)
            raise
    gather.write(args.output, rows, 'Graded %d at a time in %.0f s.'
                 % (args.jobs, time.monotonic() - started))
    return rows


def submission_args(args):
    """The options a class grade passes on to the grade of each submission (one each)."""
    forwarded = ['--one', '--trials', str(args.trials), '--seed', str(args.seed), '--jobs', '1',
                 '--timeout', str(args.timeout), '--reach', str(args.reach),
                 '--pass-rate', str(args.pass_rate)]
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
    try:
        with cleanup_on_signals():
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
    except KeyboardInterrupt:
        return 130
    print(rubric.markdown(grade))
    if args.json:
        formats.write(grade, args.json, args.format, time.monotonic() - started)
    return 0 if grade.passed else 1


if __name__ == '__main__':
    sys.exit(main())
