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
import os
import sys
import time

from chase_tools.grading import formats, gather, options, rubric, sandbox, slurm
from chase_tools.grading.class_grade import compare_code, grade_folder, submission_paths, unique_names
from chase_tools.grading.submission_grade import GradeStopped, grade_one
from chase_tools.procs import cleanup_on_signals


def parse_args(argv):
    parser = options.parser('grade', __doc__.split('\n')[0])
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
                rows = slurm.grade_class(args.output, names, paths, options.submission_args(args),
                                         sbatch_options)
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
