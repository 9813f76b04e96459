"""The sandbox's command line and what it lets through, the disk limit, and the cgroups
(v1 and v2) that hold a submission."""
import json
import os
import shutil
import subprocess
import sys
import tempfile

import pytest

from chase_tools.grading import sandbox

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.realpath(os.path.join(HERE, '..', '..', '..', '..'))     # this workspace's checkout
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402


# -- the sandbox ---------------------------------------------------------------------------------

needs_sandbox = pytest.mark.skipif(sandbox.check() is not None, reason='bubblewrap cannot run here')


def test_the_sandbox_shows_a_minimal_tree_and_writes_only_to_its_scratch(tmp_path):
    confinement = sandbox.Confinement(1500000001, 1500000001, True, passwd=str(tmp_path / 'passwd'),
                                      group=str(tmp_path / 'group'))
    cmd = sandbox.Sandbox(str(tmp_path / 'box'), visible=['/home/me/ws'],
                          confinement=confinement).command(['true'])
    text = ' '.join(cmd)
    assert '--ro-bind / /' not in text and '--dev-bind' not in text
    assert '--ro-bind /usr /usr' in text and '--ro-bind /etc/ld.so.cache /etc/ld.so.cache' in text
    assert '/etc/shadow' not in text and '/etc/ssh' not in text and '/etc/sudoers' not in text
    assert '--ro-bind /home ' not in text and '/root' not in text
    assert '--ro-bind %s /etc/passwd' % (tmp_path / 'passwd') in text
    assert '--perms 0755 --dir /home/me' in text       # folders above a bind: enterable
    assert '--ro-bind /home/me/ws /home/me/ws' in text
    assert '--bind %s %s' % (tmp_path / 'box', tmp_path / 'box') in text
    assert '--cap-drop ALL' in text and '--unshare-pid' in text and '--new-session' in text
    assert ('setpriv --reuid 1500000001 --regid 1500000001 --clear-groups --inh-caps=-all '
            '--bounding-set=-all --no-new-privs --') in text
    assert cmd.index('--remount-ro') > cmd.index('--bind')


def test_a_clone_under_tmp_stays_visible_with_the_code_beside_its_bin_folders(tmp_path):
    top = tmp_path / 'clone'
    for folder in ('env/bin', '.venv/bin', 'catkin_ws/src'):
        (top / folder).mkdir(parents=True)
    env = {'PATH': os.pathsep.join([str(top / 'env' / 'bin'), str(top / '.venv' / 'bin'), '/usr/bin']),
           'VIRTUAL_ENV': str(top / '.venv'), 'ROS_PACKAGE_PATH': str(top / 'catkin_ws' / 'src')}
    assert sandbox.environment_paths(env, checkout=str(top)) == sorted(
        os.path.realpath(str(top / folder)) for folder in ('.venv', 'catkin_ws/src', 'env'))


def test_folders_the_environment_names_beside_the_checkout_stay_hidden(tmp_path):
    """A checkout in a home folder, whose PATH and PYTHONPATH also name the owner's own
    folders: only the checkout's and the venv's are shown."""
    home = tmp_path / 'home' / 'teacher'
    top = home / 'proj'
    for folder in ('env/bin', '.venv/bin', 'catkin_ws/src', 'catkin_ws/devel/lib', 'bin'):
        (top / folder).mkdir(parents=True)
    for folder in ('.local/bin', '.local/lib/python3/site-packages', 'lib', 'other/bin', 'notes'):
        (home / folder).mkdir(parents=True)
    env = {'PATH': os.pathsep.join([str(top / 'env' / 'bin'), str(top / '.venv' / 'bin'),
                                    str(top / 'bin'), str(home / '.local' / 'bin'),
                                    str(home / 'other' / 'bin'), '/usr/bin']),
           'VIRTUAL_ENV': str(top / '.venv'), 'ROS_PACKAGE_PATH': str(top / 'catkin_ws' / 'src'),
           'PYTHONPATH': os.pathsep.join([str(home / '.local' / 'lib' / 'python3' / 'site-packages'),
                                          str(home / 'notes')]),
           'LD_LIBRARY_PATH': os.pathsep.join([str(top / 'catkin_ws' / 'devel' / 'lib'), str(home / 'lib')])}
    shown = sandbox.environment_paths(env, checkout=str(top))
    assert shown == sorted(os.path.realpath(str(top / folder))
                           for folder in ('.venv', 'catkin_ws/devel/lib', 'catkin_ws/src', 'env'))
    assert not any(path == os.path.realpath(str(top)) or not path.startswith(os.path.realpath(str(top)))
                   for path in shown)


ENVIRONMENT_PATHS = ('VIRTUAL_ENV', 'CMAKE_PREFIX_PATH', 'ROS_PACKAGE_PATH', 'PYTHONPATH',
                     'LD_LIBRARY_PATH', 'PKG_CONFIG_PATH', 'PATH')


@needs_sandbox
def test_a_checkout_reached_through_a_link_under_a_hidden_folder_is_found_in_the_sandbox(tmp_path):
    """This checkout as the environment names it when it was set up through a link under /tmp,
    which the sandbox hides: without a bind at the link, `rospack find xacro` (roslaunch's
    $(find xacro)) fails with "package 'xacro' not found"."""
    link = tmp_path / 'checkout'
    os.symlink(TOP, str(link))
    env = {name: value.replace(TOP, str(link)) if name in ENVIRONMENT_PATHS else value
           for name, value in os.environ.items()}
    assert env['CMAKE_PREFIX_PATH'].startswith(str(link))
    probe = link / 'catkin_ws' / 'src' / ('grade_probe_%d' % os.getpid())
    box = sandbox.Sandbox(str(tmp_path / 'box'), visible=sandbox.environment_paths(env),
                          confinement=sandbox.Confinement.create(str(tmp_path)))
    box.prepare()
    cmd, outer = box.wrap(['sh', '-c', 'rospack find xacro && touch "$0"', str(probe)], env)
    result = subprocess.run(cmd, env=outer, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, timeout=60, check=False)
    assert result.stdout.splitlines()[0] == str(link / 'catkin_ws' / 'src' / 'gazebo_compat' / 'xacro'), \
        result.stdout
    assert 'Read-only file system' in result.stdout            # shown there read-only, like the rest
    assert not os.path.exists(probe)


PROBE = """\
import os, socket, sys
scratch, secret, sibling, writes = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
print('uid', os.getuid(), os.getgid(), os.getgroups())
open(os.path.join(scratch, 'inside'), 'w').write('x')
for path in writes + ['/var/tmp/grade_probe', '/usr/grade_probe', '/tmp/grade_probe']:
    try:
        open(path, 'w').write('x'); print('wrote', path)
    except OSError as error:
        print('refused', path, error.errno)
for path in ('/etc/shadow', secret, '/root', '/home', '/srv', '/var/lib', sibling,
             os.path.join(sibling, 'key')):
    try:
        print('read', path, open(path).read() if os.path.isfile(path) else os.listdir(path))
    except OSError as error:
        print('unreadable', path, error.errno)
print('beside the checkout', os.listdir(os.path.dirname(sibling)))
try:
    socket.create_connection(('192.0.2.1', 80), timeout=5); print('connected')
except OSError as error:
    print('network', error.errno)
"""


@needs_sandbox
@pytest.mark.skipif(os.geteuid() != 0, reason='a uid of its own needs a grader running as root')
def test_sandboxed_code_runs_as_its_own_uid_and_reads_nothing_private(tmp_path):
    """Fails with a sandbox that keeps uid 0: root-only files and the host tree stay readable.

    A folder beside the checkout (as ~/.ssh lies beside ~/proj), world-readable, must not
    be there, wherever the checkout is cloned."""
    secret_folder = os.path.join(HERE, 'fixtures', 'secret_%d' % os.getpid())
    os.mkdir(secret_folder, 0o755)
    secret = os.path.join(secret_folder, 'secret')
    sibling = os.path.join(os.path.dirname(TOP), '.grade_probe_beside_%d' % os.getpid())
    os.mkdir(sibling, 0o755)
    try:
        with open(os.open(secret, os.O_WRONLY | os.O_CREAT, 0o600), 'w') as stream:
            stream.write('root-only-%d' % os.getpid())
        with open(os.path.join(sibling, 'key'), 'w') as stream:
            stream.write('beside-the-checkout-%d' % os.getpid())
        scratch = tmp_path / 'scratch'
        outside = tmp_path / 'outside'
        confinement = sandbox.Confinement.create(str(tmp_path))
        box = sandbox.Sandbox(str(scratch), visible=sandbox.environment_paths(os.environ) + [secret_folder],
                              own_network=True, confinement=confinement)
        box.prepare()
        cmd, outer = box.wrap([sys.executable, '-c', PROBE, str(scratch), secret, sibling, str(outside),
                               os.path.abspath(__file__)], os.environ)
        result = subprocess.run(cmd, env=outer, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True, timeout=60, check=False)
    finally:
        shutil.rmtree(secret_folder)
        shutil.rmtree(sibling)
    assert 'uid %d %d []' % (confinement.uid, confinement.gid) in result.stdout, result.stdout
    assert confinement.uid >= sandbox.UID_BASE
    assert (scratch / 'inside').read_text() == 'x', result.stdout
    assert (scratch / 'inside').stat().st_uid == confinement.uid
    assert not outside.exists()
    assert result.stdout.count('refused') == 5, result.stdout
    assert 'root-only-' not in result.stdout and 'read /etc/shadow' not in result.stdout
    assert 'beside-the-checkout-' not in result.stdout
    for path in ('/etc/shadow', secret, '/root', '/home', '/srv', '/var/lib', sibling):
        assert 'unreadable %s ' % path in result.stdout, result.stdout
    assert os.path.basename(sibling) not in result.stdout.split('beside the checkout', 1)[1]
    assert 'network 101' in result.stdout, result.stdout        # ENETUNREACH: no route at all


def test_non_finite_or_out_of_range_options_are_refused_with_a_clear_message(tmp_path, capsys):
    from chase_tools.grading import cli
    for option, value, said in (('--timeout', 'nan', "'nan' is not a finite number"),
                                ('--timeout', 'inf', "'inf' is not a finite number"),
                                ('--timeout-build', '-5', '-5 must be more than 0'),
                                ('--reach', 'nan', "'nan' is not a finite number"),
                                ('--pass-rate', 'nan', "'nan' is not a finite number"),
                                ('--pass-rate', '1.5', '1.5 must be at most 1'),
                                ('--memory-limit', 'lots', "'lots' is not a size"),
                                ('--process-limit', '2', '2 must be at least 16'),
                                ('--process-limit', '10000000', '10000000 must be at most 4194304'),
                                ('--open-file-limit', '1e3', "'1e3' is not a whole number"),
                                ('--open-file-limit', '100000000', '100000000 must be at most'),
                                ('--memory-limit', '99999999T', '99999999T is more than the kernel can bound'),
                                ('--seed', '-1', '-1 must be at least 0'),
                                ('--seed', '4294967296', '4294967296 must be at most 2147483647')):
        with pytest.raises(SystemExit) as stop:
            cli.parse_args([str(tmp_path), option, value])
        assert stop.value.code == 2
        assert said in capsys.readouterr().err, (option, value)
    args = cli.parse_args([str(tmp_path), '--memory-limit', '512M', '--timeout-build', '30'])
    assert (args.memory_limit, args.timeout_build) == (512 << 20, 30.0)


def test_a_log_keeps_its_first_and_last_part_and_says_what_was_cut(tmp_path):
    from chase_tools.grading import logcap
    cap = logcap.LogCap(1000)
    for index in range(1000):
        cap.feed(b'line %04d\n' % index)
    text = cap.text()
    assert text.startswith('line 0000\nline 0001')
    assert text.endswith('line 0998\nline 0999\n')
    assert cap.total == 10000 and cap.cut == 9000
    assert '[the grader cut 9000 bytes (8.8 KiB) here' in text
    assert len(text) < 1200
    log = logcap.CappedLog(str(tmp_path / 'node.log'), 1000)
    subprocess.run(['sh', '-c', 'yes flood | head -c 1000000'], stdout=log.fd, check=True)
    log.close()
    written = (tmp_path / 'node.log').read_text()
    assert len(written) < 1200 and 'the grader cut 999000 bytes' in written


def test_a_log_keeps_its_allowance_however_often_its_launch_starts_again(tmp_path):
    """A launch started afresh for each trial appends to its log: the file holds the allowance
    and a cut line for each start, however often it floods."""
    from chase_tools.grading import logcap
    path = str(tmp_path / 'launch.log')
    for start in range(5):
        log = logcap.CappedLog(path, 1000)
        subprocess.run(['sh', '-c', 'echo start %d; yes flood | head -c 100000' % start],
                       stdout=log.fd, check=True)
        log.close()
    written = open(path).read()
    assert written.startswith('start 0\nflood\n')
    assert len(written) < 1000 + 5 * 200, len(written)
    assert written.count('[the grader cut ') == 5
    assert ('here: it keeps 1000 bytes of each log however often its launch starts, and earlier '
            'starts had used all but 0 bytes]') in written
    # A quiet launch started again loses nothing.
    quiet = str(tmp_path / 'quiet.log')
    for start in range(5):
        log = logcap.CappedLog(quiet, 1000)
        subprocess.run(['echo', 'start %d' % start], stdout=log.fd, check=True)
        log.close()
    assert open(quiet).read() == ''.join('start %d\n' % start for start in range(5))


def test_a_folder_is_graded_one_submission_per_core_the_process_may_use(monkeypatch, tmp_path):
    from chase_tools.grading import cli
    monkeypatch.setattr(os, 'sched_getaffinity', lambda _pid: {2, 5, 7})
    assert cli.parse_args([str(tmp_path)]).jobs == 3
    assert cli.parse_args([str(tmp_path), '--jobs', '1']).jobs == 1


def test_class_and_one_decide_what_a_folder_is(tmp_path, capsys):
    from chase_tools.grading import class_grade, cli
    for name in ('py_correct', 'cpp_correct'):
        variants.compose(name, tmp_path)
    shutil.rmtree(tmp_path / 'cpp_correct' / 'ball_chaser')
    variants.compose('py_repository', tmp_path)
    assert class_grade.submission_paths(cli.parse_args([str(tmp_path)])) == [str(tmp_path)]
    assert ('2 subfolders of %s hold a whole submission, but not every one' % tmp_path
            in capsys.readouterr().out)
    assert class_grade.submission_paths(cli.parse_args([str(tmp_path), '--class'])) == [
        str(tmp_path / name) for name in ('cpp_correct', 'py_correct', 'py_repository')]
    variants.compose('cpp_correct', tmp_path / 'again')
    shutil.rmtree(tmp_path / 'cpp_correct')
    assert len(class_grade.submission_paths(cli.parse_args([str(tmp_path)]))) == 3
    assert class_grade.submission_paths(cli.parse_args([str(tmp_path), '--one'])) == [str(tmp_path)]
    with pytest.raises(SystemExit):
        cli.parse_args([str(tmp_path), '--class', '--one'])


# -- the disk limit ------------------------------------------------------------------------------

DISK_PROBE = """
import json, os, sys
from chase_tools.grading import disk
if sys.argv[3] == 'no loop device':
    disk.Disk._mount_image = lambda self: 'no loop device'
made = disk.Disk.create(sys.argv[1], int(sys.argv[2]))
written, error = 0, ''
try:
    while written < 4 * made.limit:
        with open(os.path.join(made.folder, 'fill_%d' % written), 'wb') as stream:
            stream.write(b'x' * (1 << 20))
        written += 1 << 20
except OSError as exc:
    error = exc.strerror
full, kind = made.full(), made.describe()
with open('/proc/self/mountinfo') as stream:
    mounted = made.folder in stream.read()
made.unmount()
print(json.dumps(dict(kind=kind, written=written, error=error, full=full, mounted=mounted)))
"""


def _disk_probe(folder, how, prefix=()):
    """Disk.create in a process of its own (it moves into a mount namespace of its own)."""
    result = subprocess.run(list(prefix) + [sys.executable, '-c', DISK_PROBE, os.path.join(folder, 'disk'),
                                            str(8 << 20), how],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60,
                            check=False)
    assert result.returncode == 0, result.stdout
    return json.loads(result.stdout.splitlines()[-1])


@pytest.mark.skipif(os.geteuid() != 0, reason='mounting needs root')
@pytest.mark.parametrize('how, kind', [
    ('', '8 MiB of disk for its folders together (a filesystem of their own, an ext4 image in the '
         'scratch folder)'),
    ('no loop device', '8 MiB for its folders together (a tmpfs of their own, in memory)'),
])
def test_a_disk_of_the_limit_stops_writes_past_it_and_says_when_it_is_full(tmp_path, how, kind):
    probe = _disk_probe(str(tmp_path), how)
    assert probe['kind'] == kind
    assert probe['error'] == 'No space left on device' and probe['written'] <= 8 << 20, probe
    assert probe['full'] and probe['mounted']
    with open('/proc/self/mountinfo') as stream:
        assert str(tmp_path) not in stream.read()             # the machine's mounts: never there


@pytest.mark.skipif(os.geteuid() != 0 or shutil.which('setpriv') is None,
                    reason='runs the probe as another uid')
def test_a_grader_that_is_not_root_says_the_disk_is_not_bounded():
    folder = tempfile.mkdtemp(prefix='grade_disk_probe_')      # where another uid may write
    try:
        os.chmod(folder, 0o777)
        probe = _disk_probe(folder, '', ['setpriv', '--reuid', '65534', '--regid', '65534',
                                         '--clear-groups'])
    finally:
        shutil.rmtree(folder)
    assert probe['kind'] == 'disk space not bounded (the grader is not root)'
    assert probe['error'] == '' and probe['written'] == 32 << 20 and not probe['full'], probe


def fake_unified_hierarchy(tmp_path, offered, enabled=''):
    """A folder laid out as a cgroup v2 hierarchy's files, with this process in /grading."""
    mount = tmp_path / 'unified'
    (mount / 'grading').mkdir(parents=True)
    (mount / 'grading' / 'cgroup.controllers').write_text(offered + '\n')
    (mount / 'grading' / 'cgroup.subtree_control').write_text(enabled + '\n')
    proc_cgroup = tmp_path / 'cgroup'
    proc_cgroup.write_text('0::/grading\n')
    return str(mount), str(proc_cgroup)


def test_without_cgroup_v1_the_submissions_cgroup_is_made_in_cgroup_v2(tmp_path):
    """Files only: this machine's memory and pids controllers are bound to cgroup v1, so its
    unified hierarchy offers neither (see docs/teaching.md)."""
    from chase_tools.grading import limits
    mount, proc_cgroup = fake_unified_hierarchy(tmp_path, 'cpu memory pids')
    made = limits.Cgroups.create_unified('grade_1', limits.Limits(memory=768 << 20, processes=200),
                                         mount=mount, proc_cgroup=proc_cgroup)
    folder = os.path.join(mount, 'grading', 'grade_1')
    assert made.folders == {limits.UNIFIED: folder} and made.active
    with open(os.path.join(mount, 'grading', 'cgroup.subtree_control')) as stream:
        assert stream.read() == '+memory +pids'
    with open(os.path.join(folder, 'memory.max')) as stream:
        assert stream.read() == str(768 << 20)
    with open(os.path.join(folder, 'pids.max')) as stream:
        assert stream.read() == '200'
    assert made.procs_files() == [os.path.join(folder, 'cgroup.procs')]
    with open(os.path.join(folder, 'memory.events'), 'w') as stream:
        stream.write('low 0\nhigh 0\nmax 7\noom 2\noom_kill 2\n')
    with open(os.path.join(folder, 'pids.events'), 'w') as stream:
        stream.write('max 5\n')
    assert made.usage() == limits.Usage(oom_kills=2, refused_forks=5)
    restored = limits.Cgroups.from_json(made.as_json())
    assert restored.usage() == limits.Usage(oom_kills=2, refused_forks=5)


def test_a_cgroup_v2_without_memory_and_pids_for_the_grader_says_how_to_delegate_them(tmp_path):
    from chase_tools.grading import limits
    mount, proc_cgroup = fake_unified_hierarchy(tmp_path, 'hugetlb')
    made = limits.Cgroups.create_unified('grade_1', limits.Limits(), mount=mount,
                                         proc_cgroup=proc_cgroup)
    assert not made.active
    assert made.why == ("cgroup v2 does not give the grader's cgroup /grading the memory and pids "
                        "controllers (delegate them, as systemd-run --scope -p Delegate=yes does)")
    assert not os.path.exists(os.path.join(mount, 'grading', 'grade_1'))


def test_the_mount_of_the_unified_hierarchy_is_read_from_mountinfo(tmp_path):
    from chase_tools.grading import limits
    mountinfo = tmp_path / 'mountinfo'
    mountinfo.write_text(
        '30 24 0:26 / /sys/fs/cgroup/memory rw,relatime shared:9 - cgroup cgroup rw,memory\n'
        '35 24 0:31 / /sys/fs/cgroup/unified rw,relatime shared:14 - cgroup2 cgroup2 rw\n')
    assert limits.unified_mount(str(mountinfo)) == '/sys/fs/cgroup/unified'
    mountinfo.write_text('30 24 0:26 / /sys/fs/cgroup/memory rw - cgroup cgroup rw,memory\n')
    assert limits.unified_mount(str(mountinfo)) is None


CGROUP2_PROBE = r'''
import json, os, subprocess, sys, time
from chase_tools.grading import limits
mount = sys.argv[1]
subprocess.run(['mount', '-t', 'cgroup2', 'none', mount], check=True)
own = limits.own_unified_cgroup('/proc/self/cgroup')
offered = open(os.path.join(mount, own.lstrip('/'), 'cgroup.controllers')).read().split()
made = limits.Cgroups.create_unified('grade_probe', limits.Limits(memory=64 << 20, processes=20),
                                     mount=mount)
said = {'offered': offered, 'why': made.why, 'active': made.active}
if made.active:
    hog = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(0.5); '
                            'x = bytearray(256 << 20); time.sleep(5)'])
    for path in made.procs_files():
        with open(path, 'w') as stream:
            stream.write(str(hog.pid))
    said['hog_exit'] = hog.wait(30)
    said['usage'] = [made.usage().oom_kills, made.usage().refused_forks]
    made.remove()
    said['removed'] = not any(os.path.exists(folder) for folder in made.folders.values())
print(json.dumps(said))
'''


def test_cgroup_v2_on_this_kernel_bounds_memory_or_says_why_it_cannot(tmp_path):
    """A cgroup v2 hierarchy, mounted in a mount namespace of the test's own: where its
    grader's cgroup offers memory and pids (a Debian 12 machine, delegated), a process past
    memory.max is killed and counted; where the controllers are bound to cgroup v1 (as on
    a machine with both), the grader says so, and why, from the kernel's own files."""
    import json
    import shutil
    import subprocess
    import sys
    if os.geteuid() != 0 or shutil.which('unshare') is None:
        pytest.skip('mounting a cgroup2 hierarchy needs root and unshare')
    mount = tmp_path / 'cgroup2'
    mount.mkdir()
    done = subprocess.run(['unshare', '--mount', '--propagation', 'private', sys.executable, '-c',
                           CGROUP2_PROBE, str(mount)], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=120, check=False)
    if done.returncode != 0 and 'mount' in done.stdout:
        pytest.skip('this machine lets no cgroup2 hierarchy be mounted: %s' % done.stdout[-300:])
    said = json.loads(done.stdout.splitlines()[-1])
    if {'memory', 'pids'} <= set(said['offered']):
        assert said['active'], said
        assert said['hog_exit'] == -9, said
        assert said['usage'][0] >= 1, said
        assert said['removed'], said
    else:
        assert not said['active']
        missing = [name for name in ('memory', 'pids') if name not in said['offered']]
        assert said['why'].startswith('cgroup v2 does not give the grader\'s cgroup / the %s '
                                      'controller' % ' and '.join(missing)), said
