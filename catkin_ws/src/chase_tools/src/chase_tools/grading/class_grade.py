"""The grade of a class: its submissions graded up to --jobs at once, each in a process of its
own, and their code compared."""
import os
import re
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

from chase_tools.grading import gather, similarity, submission
from chase_tools.grading.options import submission_args, usable_cores
from chase_tools.grading.submission_grade import GradeStopped, signals_held, stop_signal_name


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
    except Exception as error:  # noqa: BLE001 - evidence only: a failure of the comparison never stops the grade
        return 'grade: the code of the submissions could not be compared: %s: %s' % (
            type(error).__name__, error)
    return 'grade: %d pair%s of submissions with unusually similar code; see %s' % (
        len(pairs), '' if len(pairs) == 1 else 's', os.path.join(args.output, similarity.MARKDOWN_FILE))


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
