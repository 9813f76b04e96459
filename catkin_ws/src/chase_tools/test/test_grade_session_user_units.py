"""The grading session as a user of its own (session_user.py): what it can and cannot do."""
import json
import os
import pathlib
import shutil
import stat
import subprocess
import sys
import tempfile

import pytest

from chase_tools.grading import sandbox
from chase_tools.grading.session_user import (SessionUser, copy_tree_beneath, id_map, reach_args,
                                              report_name, searchable)

as_root = pytest.mark.skipif(os.geteuid() != 0 or shutil.which('bwrap') is None,
                             reason='the session gets a uid of its own only from a grader that is '
                                    'root, with bubblewrap')

# What the session tries, run as the session would be: its results as JSON on stdout.
TRIES = r'''
import json, os, socket, sys
secret, own_folder, mapped, unmapped, grader_pid = sys.argv[1:6]
done = {'uid_in_namespace': os.getuid()}
def attempt(name, action):
    try:
        action()
        done[name] = 'done'
    except OSError as error:
        done[name] = error.strerror
attempt('read_root_only', lambda: open(secret).read())
attempt('write_own_folder', lambda: open(os.path.join(own_folder, 'made'), 'w').write('x'))
attempt('chown_to_mapped', lambda: os.chown(os.path.join(own_folder, 'made'), int(mapped), int(mapped)))
attempt('chown_to_unmapped', lambda: os.chown(os.path.join(own_folder, 'made'), int(unmapped),
                                              int(unmapped)))
attempt('signal_grader', lambda: os.kill(int(grader_pid), 0))
attempt('reach_network', lambda: socket.create_connection(('192.0.2.1', 80), timeout=2))
with open('/proc/self/status') as stream:
    done['no_new_privs'] = [line.split()[1] for line in stream if line.startswith('NoNewPrivs')][0]
print(json.dumps(done))
'''


@pytest.fixture
def open_folder():
    """A folder any uid may enter (pytest's own are root's alone)."""
    folder = tempfile.mkdtemp(prefix='session_user_', dir='/tmp')
    os.chmod(folder, 0o755)
    yield pathlib.Path(folder)
    shutil.rmtree(folder, ignore_errors=True)


def test_the_namespace_maps_its_root_to_the_session_and_every_other_uid_to_itself():
    assert id_map(1768000000, [1500000007, 1634000007, 1500000007]) == (
        '0 1768000000 1\n1500000007 1500000007 1\n1634000007 1634000007 1\n')


def test_a_folder_the_uid_cannot_enter_is_replaced_by_a_tmpfs_that_shows_only_what_is_needed(
        open_folder):
    closed = open_folder / 'home'
    (closed / 'proj' / 'src').mkdir(parents=True)
    (closed / 'secret').mkdir()
    closed.chmod(0o700)
    (open_folder / 'open').mkdir()
    uid = 1768000000
    assert not searchable(str(closed), uid, uid)
    args = reach_args([str(closed / 'proj' / 'src'), str(open_folder / 'open')], uid, uid)
    assert args[:4] == ['--perms', '0755', '--tmpfs', str(closed)]
    # The folder on the way is made enterable, then what is needed is bound back.
    assert args[4:] == ['--perms', '0755', '--dir', str(closed / 'proj'),
                        '--bind', str(closed / 'proj' / 'src'), str(closed / 'proj' / 'src')]
    assert str(closed / 'secret') not in args


def test_nothing_is_mounted_where_every_folder_on_the_way_can_be_entered(open_folder):
    (open_folder / 'a' / 'b').mkdir(parents=True)
    (open_folder / 'a').chmod(0o755)
    assert reach_args([str(open_folder / 'a' / 'b')], 1768000000, 1768000000) == []


@as_root
def test_the_session_is_its_own_uid_reaches_only_what_it_was_handed_and_no_network(tmp_path,
                                                                                     open_folder):
    """Started as the grader starts it, the session cannot read a root-only file, signal the
    grader, chown to a uid it was not given or reach a network; it writes its own folder as
    its own uid, chowns to the uids it was given, and has no_new_privs."""
    tmp_path.chmod(0o700)           # a folder of root's that its uid cannot enter
    user = SessionUser.create(str(tmp_path / 'session'), worlds=1)
    secret = open_folder / 'secret'       # where its uid can look, but not read
    secret.write_text('root only')
    secret.chmod(0o600)
    submission_uid = sandbox.sandbox_uid()
    script = tmp_path / 'tries.py'
    script.write_text(TRIES)
    script.chmod(0o644)
    cmd = [sys.executable, str(script), str(secret), user.folder, str(submission_uid),
           str(submission_uid + 12345), str(os.getpid())]
    needed = sandbox.environment_paths(os.environ) + [sandbox.CHECKOUT, sys.prefix, user.folder,
                                                        str(script)]
    done = subprocess.run(user.command(cmd, submission_uid, needed), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stdout
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    assert seen['uid_in_namespace'] == 0
    assert seen['read_root_only'] == 'Permission denied'
    assert seen['write_own_folder'] == 'done'
    assert seen['chown_to_mapped'] == 'done'
    assert seen['chown_to_unmapped'] == 'Invalid argument'
    assert seen['signal_grader'] == 'Operation not permitted'
    assert seen['reach_network'] != 'done'
    assert seen['no_new_privs'] == '1'
    made = os.stat(os.path.join(user.folder, 'made'))
    assert made.st_uid == submission_uid            # chowned there by the session
    assert user.uid not in (0, submission_uid) and user.uid > sandbox.UID_BASE


@as_root
def test_a_session_that_cannot_be_made_a_user_of_its_own_says_so_and_does_not_run():
    # 4294967295 is (uid_t)-1, which no map may hold.
    done = subprocess.run([sys.executable, '-m', 'chase_tools.grading.session_user', '1768000000',
                           '4294967295', '--', 'sh', '-c', 'echo ran'], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=60, check=False)
    assert done.returncode == 125, done.stdout
    assert 'could not be mapped' in done.stdout and 'could not start as uid 1768000000' in done.stdout
    assert 'ran' not in done.stdout.split() and 'Traceback' not in done.stdout


@as_root
def test_sigint_to_the_grader_side_reaches_the_session(tmp_path):
    user = SessionUser.create(str(tmp_path / 'session'), worlds=1)
    waiter = ('import signal, sys, time\n'
              'signal.signal(signal.SIGINT, lambda *_: sys.exit(42))\n'
              'print("ready", flush=True)\ntime.sleep(60)\n')
    needed = sandbox.environment_paths(os.environ) + [sandbox.CHECKOUT, sys.prefix]
    proc = subprocess.Popen(user.command([sys.executable, '-c', waiter], sandbox.sandbox_uid(), needed),
                            stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == 'ready'
        from chase_tools.grading.sandbox_processes import child_pids
        # As the grader does: SIGINT to what bwrap started, the process that stays root.
        for pid in child_pids(proc.pid):
            os.kill(pid, 2)
        assert proc.wait(30) == 42
    finally:
        proc.kill()
        proc.wait()


def test_the_report_folder_gets_regular_files_only_and_no_more_than_the_bound(tmp_path):
    top, out = tmp_path / 'written', tmp_path / 'report'
    (top / 'logs' / 'ros').mkdir(parents=True)
    (top / 'logs' / 'a.log').write_text('a' * 100)
    (top / 'logs' / 'ros' / 'b.log').write_text('b' * 100)
    (top / 'trial_00.png').write_bytes(b'p' * 100)
    (top / 'logs' / 'passwd').symlink_to('/etc/passwd')
    (top / 'linked').symlink_to('/etc')
    os.mkfifo(top / 'logs' / 'pipe')
    out.mkdir()
    (out / 'logs').mkdir()
    (out / 'logs' / 'session.log').write_text('the grader\'s own')
    (top / 'logs' / 'session.log').write_text('forged')
    notes = copy_tree_beneath(str(top), str(out), limit=250, most_files=10)
    copied = sorted(os.path.relpath(os.path.join(root, name), out)
                    for root, _dirs, files in os.walk(out) for name in files)
    assert 'logs/passwd' not in copied and 'linked' not in copied and 'logs/pipe' not in copied
    assert (out / 'logs' / 'session.log').read_text() == 'the grader\'s own'
    total = sum(os.lstat(out / name).st_size for name in copied if name != 'logs/session.log')
    assert total <= 250
    assert all(stat.S_ISREG(os.lstat(out / name).st_mode) for name in copied)
    assert notes == ['links or special files: 3', 'files past the bound: 1',
                     'files already there: 1'], notes


@as_root
def test_a_machine_that_cannot_make_the_sessions_namespace_is_told_before_the_grade():
    """The grader asks first: where the namespace cannot be made, the session runs as root and
    the grade says why (submission_grade.session_user), instead of a session that never starts."""
    assert SessionUser(uid=4294967295, cores=[], simulators=[]).refused() is not None
    assert SessionUser.uids_for(worlds=1).refused() is None


def _cgroup_files(folder, names=('cgroup.procs', 'cgroup.subtree_control', 'memory.max', 'pids.max')):
    """What the kernel puts in a new cgroup v2 folder, as files (a fake hierarchy)."""
    for name in names:
        open(os.path.join(folder, name), 'a').close()


@pytest.mark.skipif(os.geteuid() != 0, reason='chown to another uid needs root')
def test_in_cgroup_v2_the_session_may_move_processes_between_its_cgroups_and_the_submissions_only(
        tmp_path):
    """cgroup v2 lets a uid move a process only with write access to the cgroup.procs of the
    common ancestor: the submission's and the session's cgroups are made in one group of the
    grader's, whose cgroup.procs the session gets, and nothing else of it; the limits stay
    root's. (Files only: this machine's memory and pids controllers are cgroup v1's.)"""
    from chase_tools.grading import limits
    group_folder = tmp_path / 'grade_1'
    group_folder.mkdir()
    _cgroup_files(group_folder)
    group = limits.Cgroups({limits.UNIFIED: str(group_folder)})
    submission = limits.Cgroups.create('submission', limits.Limits(memory=1 << 30, processes=100),
                                       within=group)
    session = limits.Cgroups.create('session', limits.Limits(memory=2 << 30, processes=4096),
                                    within=group)
    for made in (submission, session):
        assert made.active, made.why
        _cgroup_files(made.folders[limits.UNIFIED])
    uid = 1768000000
    group.hand_ancestor_to(uid, uid)
    submission.hand_to(uid, uid)
    session.hand_to(uid, uid, own=True)

    def owner(*parts):
        return os.stat(os.path.join(*map(str, parts))).st_uid
    assert owner(group_folder, 'cgroup.procs') == uid
    assert owner(group_folder) == 0 and owner(group_folder, 'cgroup.subtree_control') == 0
    assert owner(group_folder, 'submission', 'cgroup.procs') == uid
    assert owner(group_folder, 'submission') == 0
    assert owner(group_folder, 'session') == uid                       # roscore's are made in it
    assert owner(group_folder, 'session', 'cgroup.subtree_control') == uid
    for name in ('submission', 'session'):
        assert owner(group_folder, name, 'memory.max') == 0
        assert owner(group_folder, name, 'pids.max') == 0
    with open(group_folder / 'session' / 'memory.max') as stream:
        assert stream.read() == str(2 << 30)


@pytest.mark.skipif(os.geteuid() != 0, reason='chown to another uid needs root')
def test_in_cgroup_v1_the_group_itself_is_never_handed_over(tmp_path):
    """cgroup v1 asks for no common ancestor, and there a uid that could write the group's own
    cgroup.procs could move processes into it, where no limit holds."""
    from chase_tools.grading import limits
    folders = {}
    for controller in ('memory', 'pids'):
        folders[controller] = str(tmp_path / controller / 'grade_1')
        os.makedirs(folders[controller])
        _cgroup_files(folders[controller], ('cgroup.procs', 'tasks'))
    limits.Cgroups(folders).hand_ancestor_to(1768000000, 1768000000)
    for folder in folders.values():
        assert os.stat(os.path.join(folder, 'cgroup.procs')).st_uid == 0
        assert os.stat(os.path.join(folder, 'tasks')).st_uid == 0


def test_the_report_folder_gets_only_the_names_the_session_writes(tmp_path):
    """A session taken over could write the grader's own names (a folder named grade.json
    would stop the grader writing its report); they are left out, and a folder where the
    grader has a file is skipped, not an error."""
    top, out = tmp_path / 'written', tmp_path / 'report'
    (top / 'logs').mkdir(parents=True)
    (top / 'logs' / 'world_launch.log').write_text('kept')
    (top / 'trial_03.png').write_bytes(b'png')
    (top / 'world.png').write_bytes(b'png')
    (top / 'grade.json').mkdir()
    (top / 'report.md').write_text('# Grade: PASS')
    (top / 'extra').mkdir()
    (top / 'extra' / 'x.log').write_text('x')
    out.mkdir()
    (out / 'logs').write_text('a file of the grader\'s where a folder would go')
    notes = copy_tree_beneath(str(top), str(out), 1 << 20, 10, report_name)
    assert sorted(os.listdir(out)) == ['logs', 'trial_03.png', 'world.png']
    assert (out / 'logs').read_text().startswith('a file of the grader')
    assert notes == ['files already there: 1', 'names the session does not write: 3'], notes
