"""A class graded on a Slurm cluster: one array task per submission.

  grade FOLDER --output DIR [grade options] --slurm [sbatch options] [-- grade options]

Everything after --slurm, up to a lone --, goes to sbatch as it is; grade
options may come before --slurm or after the --. grade then

  1. writes DIR/slurm/job.json (each submission's name and path, and the
     options each task passes on to grade) and DIR/slurm/grade.sbatch (the
     batch script, whose #SBATCH lines hold the defaults: sbatch options given
     on the command line override them);
  2. submits the script as an array job of one task per submission
     (sbatch --array=0-N-1 --parsable);
  3. waits for the array (squeue every few seconds), saying which submission
     finished how; Ctrl-C cancels the array (scancel). Until its task starts,
     each DIR/<name>/grade.log says which task will grade it, so that
     `grade --gather DIR` finds every submission of a job, run or not;
  4. gathers DIR/summary.md and DIR/grades.csv from each DIR/<name>/grade.json
     (grading/gather.py), as a local class grade does.

Task N enters the project's environment (env.sh of this checkout, which must
be at the same path on every node), then runs
`python -m chase_tools.grading.slurm DIR/slurm/job.json`: grade on submission N
into DIR/<name>/, its output in DIR/<name>/grade.log. The task's exit status is
0 when the submission was graded (whether it passed or not), so a failed Slurm
task means the grader itself could not run; its log is DIR/slurm/task_N.log.
"""
import json
import os
import re
import shlex
import signal
import subprocess
import sys
import time

from chase_tools.grading import gather

JOB_FOLDER = 'slurm'
JOB_FILE = 'job.json'
SCRIPT_FILE = 'grade.sbatch'
# Defaults a teacher's own sbatch options override: a grading session runs a
# master, the simulator and the submission's nodes at once, and builds with -j.
#
# --signal: SIGTERM to the batch script (B:, the task's own grade, which passes it on) this
# many seconds before the time limit, so that the grade stops its session and writes its report
# in time; at the limit itself Slurm signals every process at once, then kills them KillWait
# (30 s by default) later. A teacher's own --signal overrides it.
STOP_WARNING_S = 120
DEFAULT_OPTIONS = ('--job-name=grade', '--cpus-per-task=2', '--signal=B:TERM@%d' % STOP_WARNING_S)
# grade makes the array itself, one task per submission, of its own script.
OWN_OPTIONS = ('--array', '-a', '--wrap')
POLL_MIN_S, POLL_MAX_S = 2.0, 30.0
# How long squeue may keep failing (the controller restarting, say) before grade gives up waiting.
SQUEUE_PATIENCE_S = 300.0
# After scancel, how long to wait for the tasks to stop and write what they have.
CANCEL_WAIT_S = 120.0
# The task states in which a task may still write its grade.
ACTIVE_STATES = ('PENDING', 'CONFIGURING', 'RUNNING', 'COMPLETING', 'SUSPENDED', 'REQUEUED',
                 'RESIZING', 'SIGNALING', 'STAGE_OUT')


class SlurmError(Exception):
    """Slurm refused or could not be reached; the message says which and why."""


def split_argv(argv):
    """(grade's arguments with --slurm kept as a flag, sbatch's options): everything after
    --slurm up to a lone -- is sbatch's."""
    if '--slurm' not in argv:
        return list(argv), []
    start = argv.index('--slurm') + 1
    end = argv.index('--', start) if '--' in argv[start:] else len(argv)
    return list(argv[:start]) + list(argv[end + 1:]), list(argv[start:end])


def check_options(sbatch_options):
    """None, or why grade cannot pass these options on."""
    for option in sbatch_options:
        name = option.split('=', 1)[0]
        if name in OWN_OPTIONS or (name.startswith('-a') and not name.startswith('--')):
            return ('%s: grade makes the array itself, one task per submission; give the other '
                    'sbatch options after --slurm' % option)
    return None


def checkout_top():
    """The checkout this grader runs from: the folder with env.sh above this module."""
    folder = os.path.dirname(os.path.realpath(__file__))
    while folder != os.path.dirname(folder):
        if os.path.isfile(os.path.join(folder, 'env.sh')) and os.path.isfile(os.path.join(folder, 'setup.sh')):
            return folder
        folder = os.path.dirname(folder)
    raise SlurmError('cannot find the checkout (env.sh) that this grader runs from; the tasks '
                     'enter its environment')


def batch_script(job_file, task_log_pattern, top):
    """The array job's script: enter the checkout's environment, grade one submission."""
    lines = ['#!/bin/bash']
    lines += ['#SBATCH %s' % option for option in DEFAULT_OPTIONS]
    lines += ['#SBATCH --output=%s' % task_log_pattern,
              '# Written by `grade FOLDER --slurm`: array task N grades submission N of',
              '# %s. The checkout and the report folder must be at' % job_file,
              '# these paths on every node (a shared filesystem).',
              'if ! source %s; then' % shlex.quote(os.path.join(top, 'env.sh')),
              '  echo "grade: cannot enter the grader\'s environment on $(hostname): is %s '
              'there?" >&2' % top,
              '  exit 2',
              'fi',
              'exec python -m chase_tools.grading.slurm %s' % shlex.quote(job_file)]
    return '\n'.join(lines) + '\n'


def write_job(report_dir, names, paths, grade_args, top):
    """DIR/slurm/job.json and DIR/slurm/grade.sbatch; the script's path."""
    folder = os.path.join(report_dir, JOB_FOLDER)
    os.makedirs(folder, exist_ok=True)
    job_file = os.path.join(folder, JOB_FILE)
    with open(job_file, 'w') as stream:
        json.dump({'report_dir': report_dir, 'grade_args': list(grade_args),
                   'submissions': [{'name': name, 'path': os.path.abspath(path)}
                                   for name, path in zip(names, paths)]}, stream, indent=2)
        stream.write('\n')
    for name in names:
        os.makedirs(os.path.join(report_dir, name), exist_ok=True)
    script = os.path.join(folder, SCRIPT_FILE)
    with open(script, 'w') as stream:
        stream.write(batch_script(job_file, os.path.join(report_dir, task_log('%a')), top))
    return script


def run(cmd, timeout=60):
    """A Slurm command's CompletedProcess; SlurmError if it is not installed or hangs."""
    try:
        return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                              timeout=timeout, check=False)
    except FileNotFoundError as error:
        raise SlurmError('%s is not installed here: grade --slurm runs on a machine that can '
                         'submit Slurm jobs' % cmd[0]) from error
    except subprocess.TimeoutExpired as error:
        raise SlurmError('%s did not answer in %d s' % (' '.join(cmd[:2]), timeout)) from error


def submit(script, count, sbatch_options):
    """The array job's id."""
    cmd = ['sbatch', '--parsable', '--array=0-%d' % (count - 1)] + list(sbatch_options) + [script]
    result = run(cmd)
    answer = result.stdout.strip().split(';')[0]
    if result.returncode != 0 or not answer.isdigit():
        raise SlurmError('sbatch refused the job (exit %d): %s' % (
            result.returncode, (result.stderr or result.stdout).strip() or 'no message'))
    return answer


def active_tasks(job_id):
    """{task index: state} of the array's tasks that have not ended; None if squeue failed."""
    try:
        result = run(['squeue', '--noheader', '--array', '--jobs', job_id, '--format', '%K %T'])
    except SlurmError:
        return None
    if result.returncode != 0:
        # A job that ended long ago is forgotten: squeue then knows no such job.
        return {} if 'Invalid job id' in result.stderr else None
    tasks = {}
    for line in result.stdout.splitlines():
        fields = line.split()
        if len(fields) == 2 and fields[0].isdigit() and fields[1] in ACTIVE_STATES:
            tasks[int(fields[0])] = fields[1]
    return tasks


def final_states(job_id):
    """{task index: 'STATE (exit N:S)'} from scontrol, while Slurm still remembers the job."""
    try:
        result = run(['scontrol', '--oneliner', 'show', 'job', job_id])
    except SlurmError:
        return {}
    states = {}
    for line in result.stdout.splitlines() if result.returncode == 0 else []:
        fields = dict(re.findall(r'(\w+)=(\S*)', line))
        for index in task_indices(fields.get('ArrayTaskId', '')):
            states[index] = '%s (exit %s)' % (fields.get('JobState', '?'), fields.get('ExitCode', '?'))
    return states


def task_indices(expression):
    """The indices of an ArrayTaskId: 3, or tasks that never started, which Slurm keeps as one
    record: 0-2,5,7-11:2 (a %N throttle may follow)."""
    indices = []
    for part in expression.split('%')[0].split(','):
        match = re.fullmatch(r'(\d+)(?:-(\d+)(?::(\d+))?)?', part)
        if match:
            first, last, step = match.groups()
            indices += range(int(first), int(last or first) + 1, int(step or 1))
    return indices


def wait(job_id, count, on_done):
    """Wait until no task of the array is pending or running; on_done(index) as each ends."""
    started, failing_since, done = time.monotonic(), None, set()
    while len(done) < count:
        elapsed = time.monotonic() - started
        time.sleep(min(POLL_MAX_S, max(POLL_MIN_S, elapsed / 10)))
        tasks = active_tasks(job_id)
        if tasks is None:
            failing_since = failing_since or time.monotonic()
            if time.monotonic() - failing_since > SQUEUE_PATIENCE_S:
                raise SlurmError('squeue has not answered for %d s; the array may still be '
                                 'running (squeue -j %s); `grade --gather` gathers its results '
                                 'later' % (SQUEUE_PATIENCE_S, job_id))
            continue
        failing_since = None
        for index in sorted(set(range(count)) - set(tasks) - done):
            done.add(index)
            on_done(index)


def cancel(job_id, log=sys.stdout):
    """scancel the array, then wait (bounded) for its tasks to stop."""
    print('grade: cancelling Slurm job %s' % job_id, file=log, flush=True)
    try:
        run(['scancel', job_id])
    except SlurmError as error:
        print('grade: %s; cancel it yourself: scancel %s' % (error, job_id), file=log, flush=True)
        return
    deadline = time.monotonic() + CANCEL_WAIT_S
    while time.monotonic() < deadline:
        tasks = active_tasks(job_id)
        if tasks == {}:
            return
        time.sleep(POLL_MIN_S)


def missing_reasons(job_id, names, states, report_dir):
    """Why a submission may have no grade.json: how its task ended, where its log is."""
    reasons = {}
    for index, name in enumerate(names):
        logs = [log for log in ('%s/%s' % (name, gather.LOG_FILE), task_log(index))
                if os.path.exists(os.path.join(report_dir, log))]
        reasons[name] = 'Slurm task %s_%d ended %s%s' % (
            job_id, index, states.get(index, 'without a grade'),
            '; see %s' % ' and '.join(logs) if logs else '')
    return reasons


def task_log(index):
    """A task's own log (entering the environment, the grade command), relative to DIR;
    index '%a' makes sbatch's pattern of them."""
    return '%s/task_%s.log' % (JOB_FOLDER, index)


def grade_class(report_dir, names, paths, grade_args, sbatch_options, log=sys.stdout):
    """Grade the submissions as one Slurm array job into report_dir/<name>/, then gather them;
    the gather.Rows, or None (and why, on stderr) if Slurm could not take the job.
    KeyboardInterrupt cancels the job and gathers what it left."""
    report_dir = os.path.abspath(report_dir)
    try:
        job_id, started = start(report_dir, names, paths, grade_args, sbatch_options)
    except SlurmError as error:
        print('grade: %s' % error, file=sys.stderr)
        return None
    print('grade: %d submissions as Slurm array job %s (squeue -j %s); each task logs to %s'
          % (len(names), job_id, job_id, os.path.join(report_dir, '<name>', gather.LOG_FILE)),
          file=log, flush=True)

    def done(index):
        row = gather.read(report_dir, names[index])
        print('%-30s %s' % (names[index], gather.row_line(row)), file=log, flush=True)

    try:
        wait(job_id, len(names), done)
    except KeyboardInterrupt:
        cancel(job_id, log)
        finish(report_dir, names, job_id, 'Cancelled Slurm array job %s.' % job_id)
        raise
    except SlurmError as error:
        print('grade: %s' % error, file=sys.stderr)
        return None
    return finish(report_dir, names, job_id, 'Graded as Slurm array job %s in %.0f s.'
                  % (job_id, time.monotonic() - started))


def start(report_dir, names, paths, grade_args, sbatch_options):
    """Write the job, submit it, and leave a first line in each submission's grade.log (the
    task writes it anew), so that `grade --gather` knows the submissions of a job that never
    ran; the job's id and when it was submitted."""
    problem = check_options(sbatch_options)
    if problem:
        raise SlurmError(problem)
    script = write_job(report_dir, names, paths, grade_args, checkout_top())
    started = time.monotonic()
    job_id = submit(script, len(names), sbatch_options)
    for index, name in enumerate(names):
        with open(os.path.join(report_dir, name, gather.LOG_FILE), 'w') as stream:
            stream.write('grade: waiting for Slurm task %s_%d to grade %s\n' % (job_id, index, paths[index]))
    return job_id, started


def finish(report_dir, names, job_id, how):
    reasons = missing_reasons(job_id, names, final_states(job_id), report_dir)
    rows = gather.read_all(report_dir, names, reasons)
    gather.write(report_dir, rows, how)
    return rows


# -- one array task --------------------------------------------------------------------------

def run_task(job_file, index):
    """Grade submission `index` of the job into its folder; 0 when it was graded."""
    with open(job_file) as stream:
        job = json.load(stream)
    entry = job['submissions'][index]
    out_dir = os.path.join(job['report_dir'], entry['name'])
    os.makedirs(out_dir, exist_ok=True)
    cpus = os.environ.get('SLURM_CPUS_PER_TASK', '')
    env = dict(os.environ)
    if cpus.isdigit():
        # The build gets the task's CPUs, not the node's.
        env['ROS_PARALLEL_JOBS'] = '-j%s' % cpus
    cmd = [sys.executable, '-m', 'chase_tools.grading.cli', entry['path'],
           '--output', out_dir] + job['grade_args']
    print('grade: %s in Slurm task %s_%d (job %s) on %s: %s' % (
        entry['name'], os.environ.get('SLURM_ARRAY_JOB_ID', '?'), index,
        os.environ.get('SLURM_JOB_NAME', '?'), os.uname().nodename, ' '.join(map(shlex.quote, cmd))),
        flush=True)
    with open(os.path.join(out_dir, 'grade.log'), 'w') as log:
        status = run_passing_on_stops(cmd, log, env)
    print('grade: %s: exit %d' % (entry['name'], status), flush=True)
    # 1 is a submission that failed an item: graded all the same.
    return 0 if status in (0, 1) else status if status > 0 else 128 - status


def run_passing_on_stops(cmd, log, env):
    """Run the task's grade; its exit status. SIGTERM and SIGHUP that come to this process go on
    to it: the batch script's early warning (--signal=B:TERM@...) reaches this process alone.
    The grade then stops its session and writes its report, which this waits for."""
    proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env)

    def pass_on(signum, _frame):
        if proc.poll() is None:
            proc.send_signal(signum)
    previous = {signum: signal.signal(signum, pass_on) for signum in (signal.SIGTERM, signal.SIGHUP)}
    try:
        return proc.wait()
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    index = os.environ.get('SLURM_ARRAY_TASK_ID', '')
    if len(argv) != 1 or not index.isdigit():
        print('usage: SLURM_ARRAY_TASK_ID=N python -m chase_tools.grading.slurm JOB_FILE '
              '(an array task of `grade FOLDER --slurm`)', file=sys.stderr)
        return 2
    return run_task(argv[0], int(index))


if __name__ == '__main__':
    sys.exit(main())
