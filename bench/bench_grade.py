"""`grade` on the fixture submissions: where its wall time goes, against a 40 s target.

    python bench/bench_grade.py [--variants py_correct cpp_correct] [--worlds 1 2]
                                [--trials 3] [--timeout 60] [--rounds 1] [--baseline SRC]

Grades each fixture submission (test/fixtures/submissions, base Python and C++
by default) with each --worlds, sandboxed as a teacher runs it, one grade at
a time; with --rounds R it goes round them R times, so that a change in the
machine's load falls on every configuration alike, and prints the median.
For each: the whole grade (the `grade` process), the build and the rubric run
(from grade.json), the build's steps (logs/build.log) and the session's
steps (logs/session.log), and whether the whole grade met the target.

--baseline SRC grades each submission also with another checkout's grader
(SRC: its catkin_ws/src/chase_tools/src, from `git archive`, say), one world,
in the same rounds: before and after, measured in one run. Figures only.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
FIXTURES = os.path.join(HERE, os.pardir, 'catkin_ws', 'src', 'chase_tools', 'test', 'fixtures',
                        'submissions')
sys.path.insert(0, FIXTURES)
import variants  # noqa: E402

TARGET_S = 40.0
# A step's start ('[  4.3 s] chase ...'), or the end of the steps; other lines are notes.
SESSION_STEP = re.compile(r'^\[\s*([\d.]+) s\] (.+ \.\.\.|stopping|done)$')
BUILD_STEP = re.compile(r'^==== (\w[\w ,]*?):.*\(exit -?\d+, ([\d.]+) s\)$')
# What an older grader wrote instead of grade.json's wall_time.
OLD_NOTE = re.compile(r'graded in (\d+) s of wall time \(build (\d+) s, rubric run (\d+) s\)')
# Session steps in the order they are printed, and the column each is counted in.
PHASES = (('master', 'master'), ('world_launches', 'world'), ('sensors', 'checks'),
          ('ball_chaser', 'checks'), ('drive_bot_service', 'checks'), ('lockstep', 'checks'),
          ('chase', 'chase'), ('stops_without_ball', 'stop check'),
          ("chase, every world's trials in", 'chase'), ('process_image_calls', 'checks'),
          ('stopping', 'stopping'))
COLUMNS = ('total', 'build', 'configure', 'make', 'run', 'master', 'world', 'checks', 'chase',
           'stop check', 'stopping')


def session_phases(path):
    """{column: seconds} from a session.log: each step lasts until the next one starts."""
    marks = []
    with open(path, errors='replace') as stream:
        for line in stream:
            match = SESSION_STEP.match(line.rstrip())
            if match:
                marks.append((float(match.group(1)), match.group(2).rsplit(' ...', 1)[0]))
    names = dict(PHASES)
    found = {}
    for (start, name), (end, _next) in zip(marks, marks[1:]):
        if name in names:
            found[names[name]] = found.get(names[name], 0.0) + end - start
    return found


def build_phases(path):
    found = {}
    with open(path, errors='replace') as stream:
        for line in stream:
            match = BUILD_STEP.match(line.rstrip())
            if match:
                column = 'configure' if match.group(1) == 'configure' else 'make'
                found[column] = found.get(column, 0.0) + float(match.group(2))
    return found


def grade_once(submission, out_dir, worlds, args, baseline=None):
    """{column: seconds} of one grade, and its rubric items passed."""
    cmd = ['grade', submission, '--output', out_dir, '--trials', str(args.trials),
           '--timeout', str(args.timeout)]
    env = dict(os.environ)
    if baseline:
        env['PYTHONPATH'] = baseline + os.pathsep + env.get('PYTHONPATH', '')
    else:
        cmd += ['--worlds', str(worlds)]
    started = time.monotonic()
    subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT, check=False)
    figures = {'total': time.monotonic() - started}
    with open(os.path.join(out_dir, 'grade.json')) as stream:
        grade = json.load(stream)
    wall = grade.get('wall_time') or {}
    if wall:
        figures.update(build=wall.get('build', 0.0), run=wall.get('rubric_run', 0.0))
    else:
        match = OLD_NOTE.search(' '.join(grade.get('notes', [])))
        if match:
            figures.update(build=float(match.group(2)), run=float(match.group(3)))
    for path, read in ((os.path.join(out_dir, 'logs', 'build.log'), build_phases),
                       (os.path.join(out_dir, 'logs', 'session.log'), session_phases)):
        if os.path.exists(path):
            figures.update(read(path))
    passed = sum(item['passed'] for item in grade['items'])
    ran_in = sorted({trial.get('world', 1) for trial in grade['trials']})
    return figures, '%d/%d items, worlds %s' % (passed, len(grade['items']), ','.join(map(str, ran_in)))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--variants', nargs='+', default=['py_correct', 'cpp_correct'],
                        help='fixture submissions to grade (variants.py)')
    parser.add_argument('--worlds', nargs='+', type=int, default=[1, 2],
                        help='--worlds of each grade')
    parser.add_argument('--trials', type=int, default=3)
    parser.add_argument('--timeout', type=float, default=60.0, help='sim seconds per trial')
    parser.add_argument('--rounds', type=int, default=1)
    parser.add_argument('--baseline', default='', metavar='SRC',
                        help="another checkout's catkin_ws/src/chase_tools/src, graded alike")
    args = parser.parse_args(argv)
    configs = ([('before', 1, os.path.abspath(args.baseline))] if args.baseline else []) + \
        [('worlds %d' % worlds, worlds, None) for worlds in args.worlds]
    print('grade on %d CPUs, load %.1f: %s, %d trials, %d round%s; seconds, median of the rounds'
          % (len(os.sched_getaffinity(0)), os.getloadavg()[0], ' '.join(args.variants), args.trials,
             args.rounds, '' if args.rounds == 1 else 's'), flush=True)
    results = {}
    with tempfile.TemporaryDirectory() as top:
        for name in args.variants:
            variants.compose(name, top)
        for round_index in range(args.rounds):
            for name in args.variants:
                for label, worlds, baseline in configs:
                    out = os.path.join(top, 'out', '%s_%s_%d' % (name, label.replace(' ', ''), round_index))
                    figures, verdict = grade_once(os.path.join(top, name), out, worlds, args, baseline)
                    results.setdefault((name, label), []).append((figures, verdict))
    print('%-12s %-9s %s  %-6s %s' % ('submission', 'grader', ' '.join('%10s' % c for c in COLUMNS),
                                      'target', 'verdict'))
    for (name, label), runs in results.items():
        cells = []
        for column in COLUMNS:
            values = [figures[column] for figures, _verdict in runs if column in figures]
            cells.append('%10.1f' % statistics.median(values) if values else '%10s' % '-')
        total = statistics.median(figures['total'] for figures, _verdict in runs)
        print('%-12s %-9s %s  %-6s %s' % (name, label, ' '.join(cells),
                                          'met' if total < TARGET_S else 'MISSED',
                                          runs[-1][1]), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
