"""The grade of one submission: its build in an overlay, its rubric session (grading/session.py)
in the sandbox, and its report, also when the grade is stopped."""
import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict, dataclass

from chase_tools.grading import (bounds, course_rubric, course_service, incomplete, limits, rubric,
                                 sandbox, sandbox_processes, submission, worlds)
from chase_tools.grading import session as session_module
from chase_tools.grading.evidence import decisive_lines
from chase_tools.grading.logcap import CappedLog
from chase_tools.grading.options import worlds_of
from chase_tools.grading.overlay import Overlay
from chase_tools.grading.scratch import Scratch, read_beneath, write_new
from chase_tools.grading.session import SessionSpec
from chase_tools.grading.session_user import SessionUser
from chase_tools.procs import wait_or_kill


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
# What the session writes into the report folder, at most: its capped logs (launches, roscore,
# the simulator, each world's), each within --log-limit, and the trial pictures.
REPORT_LOGS = 64
REPORT_PICTURES = 32 << 20


def run_time_limit(args):
    """--timeout-run, or the wall seconds the rubric run may take by the bounds of its steps."""
    if args.timeout_run is not None:
        return args.timeout_run
    return bounds.run_wall_bound(args.trials, args.timeout)


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
        if re.match(r'trial_\d+\.png$', stale) or stale == rubric.WORLD_PICTURE:
            os.remove(os.path.join(out_dir, stale))
    grade = rubric.Grade(os.path.abspath(path), seed=args.seed)
    grade.isolation = isolation_text(args, None)
    found = submission.find(path)
    grade.folder, grade.ignored = found.folder, found.ignored
    grade.counted_rows = list(getattr(args, 'rubric', rubric.ROW_NAMES))
    judge_files(grade, found)
    unbuildable = incomplete.what_it_is(found)
    if unbuildable is not None:
        grade.set('builds', False, unbuildable.evidence)
        grade.not_run('the submission is incomplete' if unbuildable.judged
                      else 'the submission is not one the grader runs')
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
        if confinement is not None and confinement.session_as_root:
            grade.notes.append('the grading session ran as root, not as a uid of its own: this '
                               'machine makes no user namespaces for it (%s)'
                               % confinement.session_as_root)
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
                copy_session_report(session, grade, out_dir, args)
            if confinement is not None:
                sandbox_processes.end_sandbox(confinement)
                confinement.cgroups.remove()
                if confinement.run_cgroups is not None:
                    confinement.run_cgroups.remove()
            if scratch is not None:
                if args.keep_scratch:
                    grade.notes.append('workspace kept in %s' % scratch.top)
                scratch.close(keep=args.keep_scratch)
            grade.wall_time['total'] = round(time.monotonic() - started, 1)
            finish(grade, out_dir, args)
    if stopped is not None:
        raise GradeStopped(str(stopped), grade=grade)
    return grade


def judge_files(grade, found):
    """The course's rubric rows judged from the submission's files; the run judges the others
    (and the robot's drive and world again, as launched)."""
    for name, verdict in course_rubric.file_rows(found).items():
        grade.set_row(name, *verdict)


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
    # The submission's and the session's cgroups, in one group of the grader's own: the
    # session, a uid of its own, moves its sandboxes from its cgroup into the submission's.
    group = limits.Cgroups.create_group('grade_%d' % os.getpid())
    cgroups = limits.Cgroups.create('submission', wanted, within=group)
    confinement = sandbox.Confinement.create(scratch.grader, wanted, cgroups, scratch.disk)
    confinement.run_cgroups = group
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
        left = sandbox_processes.end_sandbox(confinement)
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
    user: SessionUser = None        # the session's uid, when the grader runs as root

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
        if self.user is not None:
            self.user.end()

    @property
    def report(self):
        """The folder the session writes what goes into the report folder."""
        return self.user.report if self.user is not None else None


def copy_session_report(session, grade, out_dir, args):
    """What the session wrote for the report folder, copied there once it has ended (a uid of
    its own wrote it: session_user.copy_tree_beneath), within REPORT_LOGS logs and the pictures."""
    if session.report is None:
        return
    bound = REPORT_LOGS * args.log_limit + REPORT_PICTURES
    left_out = session.user.copy_report(out_dir, bound)
    if left_out:
        grade.notes.append('of what the grading session wrote for the report folder, left out (%s '
                           'at most): %s' % (limits.size_text(bound), '; '.join(left_out)))


def session_cgroups(worlds_count, group):
    """(Cgroups, memory) of a session of worlds_count worlds, in the grader's group (confine):
    bounded, unless none can be made."""
    memory = SESSION_MEMORY_PER_WORLD * worlds_count
    return (limits.Cgroups.create('session', limits.Limits(memory=memory, processes=SESSION_PROCESSES),
                                  within=group), memory)


def session_user(scratch, confinement, worlds_count):
    """The session's own uid and folder (session_user.py) when the grader runs as root, with
    the scratch folders it writes and the cgroups its sandboxes join handed to it."""
    if confinement is None or not confinement.switch_user:
        return None
    user = SessionUser.create(os.path.join(scratch.top, 'session'), worlds_count)
    why = user.refused()
    if why is not None:
        confinement.session_as_root = why
        return None
    user.hand(scratch.caches)
    confinement.cgroups.hand_to(user.uid, user.uid)
    confinement.run_cgroups.hand_ancestor_to(user.uid, user.uid)
    return user


def session_needs(scratch, confinement, env=None):
    """What the session reads or writes outside the system's folders: this checkout, its venv,
    its parts of the scratch, and the sandbox's passwd and group."""
    env = os.environ if env is None else env
    return (sandbox.environment_paths(env) + [sandbox.CHECKOUT, sys.prefix]
            + [scratch.workspace, scratch.run, scratch.caches, os.path.join(scratch.top, 'session')]
            + [path for path in (confinement.passwd, confinement.group) if path])


def start_session(found, scratch, args, out_dir, confinement):
    """The session of the rubric run, started now so that its master and its imports are ready
    when the build is; it waits for the built workspace (run_session) or its end (end_session)."""
    user = session_user(scratch, confinement, worlds_of(args)) if not args.no_isolation else None
    own = user.folder if user is not None else scratch.grader
    spec = SessionSpec(overlay_env={}, overlay_root=scratch.workspace, run_scratch=scratch.run,
                       out_dir=user.report if user is not None else os.path.abspath(out_dir),
                       robot_package=found.robot.name,
                       chaser_package=found.chaser.name, trials=args.trials, seed=args.seed,
                       timeout=args.timeout, reach=args.reach, pass_rate=args.pass_rate,
                       isolate=not args.no_isolation,
                       lockstep=not args.real_time,
                       master_port=worlds.free_port() if args.no_isolation else 11311,
                       worlds=worlds_of(args),
                       confinement=confinement.as_json() if confinement is not None else None,
                       grader_dir=own, caches_dir=scratch.caches, await_build=True,
                       uids=user.uids_json() if user is not None else None)
    spec_path = os.path.join(own, 'session.json')
    result_path = os.path.join(own, 'result.json')
    write_new(spec_path, json.dumps(asdict(spec)), mode=0o644)
    cmd = [sys.executable, '-m', 'chase_tools.grading.session', spec_path, result_path]
    cgroups, memory = None, 0
    if user is not None:
        cgroups, memory = session_cgroups(spec.worlds, confinement.run_cgroups)
        cgroups.hand_to(user.uid, user.uid, own=True)
        cmd = limits.join_command(cgroups.procs_files()) + user.command(
            cmd, confinement.uid, session_needs(scratch, confinement))
    elif not args.no_isolation:
        cmd = sandbox.network_namespace_command(cmd)
    # What the grader's node logs there, the submission can make it log (a connection refused,
    # a message too large): kept as a launch's log is.
    log = CappedLog(os.path.join(out_dir, 'logs', 'session.log'), args.log_limit, mode='wb')
    try:
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stdout=log, stderr=subprocess.STDOUT,
                                start_new_session=True, text=True)
    finally:
        log.started()
    return EarlySession(proc, log, result_path, cgroups, memory, user)


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
        # The session's folder is its uid's: read as data (no link followed, no fifo opened).
        result = rubric.Grade.from_json(json.loads(read_beneath(
            os.path.dirname(result_path), os.path.basename(result_path))))
    except (OSError, ValueError, TypeError) as error:
        if stopped is not None:
            raise stopped
        with open(session_log, errors='replace') as stream:
            tail = stream.read().splitlines()[-SESSION_LOG_LINES:]
        ended = exit_text(proc.returncode) + session.limit_text()
        if how:
            grade.not_run('%s %s' % (session_module.STOPPED, how))
        grade.not_run('the grading session failed (%s, %s); see logs/session.log' % (ended, error))
        grade.not_judged('world_launches', 'the grading session failed (%s); see '
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
        grade.put(rubric.Item(item.name, item.passed, evidence, item.judged))
    for row in result.course_rows:
        # What the run saw replaces what the files said, unless the run could not judge it.
        kept = grade.row(row.name)
        if row.evidence != rubric.ROW_NOT_RUN and (row.judged or kept is None or not kept.judged):
            grade.set_row(row.name, row.passed, row.evidence, row.judged)
    grade.trials, grade.reach, grade.worlds = result.trials, result.reach, result.worlds
    grade.world_png = result.world_png
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
    while time.monotonic() < deadline and proc.poll() is None and not os.path.lexists(heard):
        time.sleep(0.05)
    if confinement is not None:
        sandbox_processes.end_sandbox(confinement)
    wait_or_kill(proc, SESSION_STOP_S)


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
    wait_or_kill(proc, SESSION_STOP_S)


def interrupt_session(proc, wrapped):
    """SIGINT lets the session stop its master, world and nodes; a kill would orphan them.

    Only the session itself gets it: bubblewrap around it would die of it, and
    its --die-with-parent would then kill the session mid-stop.
    """
    for pid in sandbox_processes.child_pids(proc.pid) if wrapped else [proc.pid]:
        try:
            os.kill(pid, signal.SIGINT)
        except ProcessLookupError:
            pass



def finish(grade, out_dir, args):
    grade.not_run('an earlier step failed')
    rubric.write_markdown(grade, os.path.join(out_dir, 'report.md'))
    rubric.write_json(grade, os.path.join(out_dir, 'grade.json'))
    return grade
