"""grade's options, declared once: the table that builds grade's parser also says what a class
grade passes on to the grade of each of its submissions (on this machine or as a Slurm task).

Each option says how it is passed on (passed_on):
  VALUE   --option VALUE, as parsed (when it has one);
  SWITCH  --option, when it is set;
  PATH    --option PATH, made absolute (the submission's grade runs elsewhere);
  CLASS   not passed on: it is the class grade's own (where its report goes, what it compares);
or a function (args, cores) -> the arguments it becomes.
"""
import argparse
import os
from dataclasses import dataclass

from chase_tools import arguments
from chase_tools.grading import course_rubric, formats, limits, rubric, similarity, worlds
from chase_tools.grading.overlay import BUILD_TIMEOUT_S
from chase_tools.reach import SURFACE_REACH_M

VALUE, SWITCH, PATH, CLASS = 'value', 'switch', 'path', 'class'


@dataclass(frozen=True)
class Option:
    flags: tuple                    # ('--trials',), or ('path',) for the positional one
    settings: dict                  # argparse's add_argument() keywords
    passed_on: object               # VALUE, SWITCH, PATH, CLASS, or (args, cores) -> [arguments]
    group: str = ''                 # options of one mutually exclusive group share its name

    @property
    def dest(self):
        return self.settings.get('dest') or self.flags[0].lstrip('-').replace('-', '_')

    def passed_on_as(self, args, cores):
        """The arguments that give a submission's grade this option as args have it."""
        value = getattr(args, self.dest)
        if callable(self.passed_on):
            return self.passed_on(args, cores)
        if self.passed_on == VALUE and value is not None:
            return [self.flags[0], str(value)]
        if self.passed_on == SWITCH and value:
            return [self.flags[0]]
        if self.passed_on == PATH and value:
            return [self.flags[0], os.path.abspath(value)]
        return []


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


def worlds_of(args, cores=None):
    """--worlds, or as many worlds as the cores (this process's, or `cores`) and the limits hold."""
    if args.worlds is not None:
        return min(args.worlds, max(1, args.trials), worlds.MAX_WORLDS)
    return worlds.worlds_for(args.trials, usable_cores() if cores is None else cores,
                             args.memory_limit, args.process_limit)


def rubric_rows(text):
    try:
        return course_rubric.parse_rows(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None


def the_rows_counted(args, _cores):
    return ['--rubric', ','.join(args.rubric) or ',']


def one_submission_at_a_time(_args, _cores):
    return ['--jobs', '1']


def the_worlds_of_one(args, cores):
    """--worlds as the class grade chose them, when it can (see worlds_of)."""
    if args.worlds is not None or cores is not None:
        return ['--worlds', str(worlds_of(args, cores))]
    return []


def always_one(_args, _cores):
    return ['--one']


def option_table():
    """grade's options, in the order its help lists them. Made at each parse: some defaults are
    this process's (its cores, the limits' defaults)."""
    defaults = limits.Limits()
    return (
        Option(('path',), dict(help='a submission (workspace, src folder or repository), '
                                    'or a folder of submissions'), CLASS),
        Option(('--trials',), dict(type=arguments.number(int, 0), default=3,
                                   help='seeded chase placements (default 3)'), VALUE),
        Option(('--seed',), dict(type=arguments.seed, default=0, help='seed of the placements (default 0)'),
               VALUE),
        Option(('--json',), dict(default='', metavar='FILE',
                                 help='also write the result as JSON here (for a folder: a list of them)'),
               CLASS),
        Option(('--output',), dict(default='grade_report', metavar='DIR',
                                   help='report folder (default ./grade_report; one subfolder per '
                                        'submission for a folder of them)'), CLASS),
        Option(('--jobs',), dict(type=arguments.number(int, 1), default=usable_cores(),
                                 help='submissions graded at once (default: one per core this process '
                                      'may use)'), one_submission_at_a_time),
        Option(('--worlds',), dict(type=arguments.number(int, 1), default=None, metavar='N',
                                   help='worlds the chase trials are shared among, each with its own '
                                        'master, simulator and nodes, at most %d (default: as many as the '
                                        'cores this process may use, %d each, and the memory and process '
                                        'limits hold)' % (worlds.MAX_WORLDS, worlds.CORES_PER_WORLD)),
               the_worlds_of_one),
        Option(('--timeout',), dict(type=arguments.positive, default=60.0,
                                    help='sim seconds a chase may take (default 60)'), VALUE),
        Option(('--timeout-build',), dict(type=arguments.positive, default=float(BUILD_TIMEOUT_S),
                                          metavar='SECONDS', help='wall seconds the whole build may take '
                                                                  '(default %d)' % BUILD_TIMEOUT_S), VALUE),
        Option(('--timeout-run',), dict(type=arguments.positive, default=None, metavar='SECONDS',
                                        help='wall seconds the rubric run may take, from the end of the '
                                             'build; the run is then stopped and the report says which '
                                             'step did not finish (default: the sum of what each step may '
                                             'take, from --trials and --timeout)'), VALUE),
        Option(('--reach',), dict(type=arguments.not_negative, default=SURFACE_REACH_M,
                                  help='gap between the robot\'s outline and the ball\'s surface that '
                                       'counts as reached (m, default %g); pushing the ball counts too'
                                  % SURFACE_REACH_M), VALUE),
        Option(('--real-time',), dict(action='store_true',
                                      help='chase in real time instead of in lockstep (sim time waiting '
                                           'for the nodes after each camera frame)'), SWITCH),
        Option(('--pass-rate',), dict(type=arguments.number(float, 0, 1), default=0.8,
                                      help='share of the trials that must reach the ball for the chase '
                                           'item (default 0.8)'), VALUE),
        Option(('--rubric',), dict(type=rubric_rows, default=rubric.ROW_NAMES, metavar='ROWS',
                                   help='the course\'s other rubric rows that count toward the grade '
                                        'line, comma-separated (default: all: %s); the others are '
                                        'still judged and shown, marked "not counted"'
                                   % ', '.join(rubric.ROW_NAMES)), the_rows_counted),
        Option(('--memory-limit',), dict(type=size, default=defaults.memory, metavar='SIZE',
                                         help='memory of the submission\'s processes together, build and '
                                              'run (default 4G)'), VALUE),
        Option(('--process-limit',), dict(type=arguments.number(int, 16, limits.MAX_PROCESSES),
                                          default=defaults.processes, metavar='N',
                                          help='processes and threads of the submission together '
                                               '(default %d)' % defaults.processes), VALUE),
        Option(('--open-file-limit',), dict(type=arguments.number(int, 64, limits.max_open_files()),
                                            default=defaults.open_files, metavar='N',
                                            help='open files per process (default %d)' % defaults.open_files),
               VALUE),
        Option(('--file-size-limit',), dict(type=size, default=defaults.file_size, metavar='SIZE',
                                            help='size of any one file the submission writes (default 1G)'),
               VALUE),
        Option(('--disk-limit',), dict(type=size, default=defaults.disk, metavar='SIZE',
                                       help='space the submission\'s files may take together, build and '
                                            'run (default 2G; see docs/teaching.md for where it can be '
                                            'bounded)'), VALUE),
        Option(('--log-limit',), dict(type=size, default=defaults.log, metavar='SIZE',
                                      help='what is kept of each of the submission\'s logs: the first and '
                                           'the last half of it (default 2M)'), VALUE),
        Option(('--scratch',), dict(default='', metavar='DIR',
                                    help='where the throwaway workspaces go (default: the system\'s '
                                         'temporary folder)'), PATH),
        Option(('--keep-scratch',), dict(action='store_true',
                                         help='keep the built workspace, to look at it afterwards'), SWITCH),
        Option(('--no-isolation',), dict(action='store_true',
                                         help='run the submission without the sandbox: only inside a '
                                              'container that is itself isolated (see docs/teaching.md)'),
               SWITCH),
        Option(('--format',), dict(choices=formats.FORMATS, default='grade',
                                   help='the format of --json FILE: the grader\'s own (default), or '
                                        'gradescope: Gradescope\'s results.json (one submission)'), CLASS),
        Option(('--slurm',), dict(action='store_true',
                                  help='grade a folder as a Slurm array job, one task per submission, and '
                                       'wait for it; every argument after --slurm, up to a lone --, goes '
                                       'to sbatch'), CLASS),
        Option(('--gather',), dict(action='store_true',
                                   help='grade nothing: PATH is the --output DIR of a class grade; write '
                                        'PATH/summary.md and PATH/grades.csv from its PATH/*/grade.json'),
               CLASS),
        Option(('--similar-to',), dict(default='', metavar='DIR',
                                       help='also compare the code of each submission with the known '
                                            'solutions in DIR (one per subfolder, or DIR itself one); pairs '
                                            'go to similarity.md in the --output DIR, as a class\'s own '
                                            'pairs do'), CLASS),
        Option(('--similarity',), dict(type=arguments.number(float, 0, 1), default=similarity.THRESHOLD,
                                       metavar='SHARE',
                                       help='list a pair when at least this share of either one\'s code '
                                            'is found in the other (default %g)' % similarity.THRESHOLD),
               CLASS),
        Option(('--class',), dict(dest='whole_class', action='store_true',
                                  help='PATH is a class: grade each of its subfolders as a submission'),
               CLASS, group='kind'),
        Option(('--one',), dict(action='store_true',
                                help='PATH is one submission, even if its subfolders look like a class'),
               always_one, group='kind'),
    )


def parser(prog, description):
    """grade's parser, from option_table()."""
    made = argparse.ArgumentParser(prog=prog, description=description)
    groups = {}
    for option in option_table():
        target = made
        if option.group:
            if option.group not in groups:
                groups[option.group] = made.add_mutually_exclusive_group()
            target = groups[option.group]
        target.add_argument(*option.flags, **option.settings)
    return made


def submission_args(args, cores=None):
    """The options a class grade passes on to the grade of each submission (one each), as
    option_table() says. cores: the cores each has, when known here (graded on this machine,
    --jobs at once); else each chooses its worlds from its own (a Slurm task's CPUs)."""
    return [word for option in option_table() for word in option.passed_on_as(args, cores)]
