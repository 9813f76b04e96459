"""grade's options: the cores it may use, sizes, the worlds of a submission, and what a class
grade passes on to the grade of each of its submissions."""
import argparse
import os

from chase_tools.grading import limits, worlds


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
        return min(args.worlds, max(1, args.trials))
    return worlds.worlds_for(args.trials, usable_cores() if cores is None else cores,
                             args.memory_limit, args.process_limit)


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
