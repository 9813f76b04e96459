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
import os
import sys
import time

from chase_tools import arguments
from chase_tools.grading import formats, gather, limits, rubric, sandbox, similarity, slurm, worlds
from chase_tools.grading.class_grade import compare_code, grade_folder, submission_paths, unique_names
from chase_tools.grading.options import size, submission_args, usable_cores
from chase_tools.grading.overlay import BUILD_TIMEOUT_S
from chase_tools.grading.submission_grade import GradeStopped, grade_one
from chase_tools.placement import REACH_GAP_M
from chase_tools.procs import cleanup_on_signals


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
