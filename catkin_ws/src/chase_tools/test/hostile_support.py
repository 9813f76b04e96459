"""What the hostile suites share: the host the submissions aim at and its snapshot, a
grade run under watch, and readers of what it wrote."""
import hashlib
import os
import re
import shutil
import socket
import stat
import subprocess
import sys
import threading
import time
import uuid

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import hostile_variants  # noqa: E402

TOP = os.path.realpath(os.path.join(HERE, '..', '..', '..', '..'))
GRADE_TIMEOUT_S = 1200
# The class of hostile submissions, two at a time: a guard against a grade that never ends,
# with room for a machine whose two cores are shared with other work.
CLASS_GRADE_TIMEOUT_S = 3600
LIMITS = ['--memory-limit', '768M', '--process-limit', '200', '--log-limit', '256K',
          '--disk-limit', '64M']
# Each needs a run of its own: a build that never ends, a trial to be shut down in.
ALONE = {'hostile_endless_build', 'hostile_shuts_down_grader'}
IN_FOLDER = sorted(set(hostile_variants.HOSTILE) - ALONE)
PROJECT_FILES = [os.path.join(TOP, 'catkin_ws', 'src', 'ball_chaser', 'launch', 'ball_chaser.launch'),
                 os.path.join(TOP, 'catkin_ws', 'src', 'my_robot', 'launch', 'world.launch')] + [
    os.path.join(HERE, '..', 'src', 'chase_tools', 'grading', name)
    for name in ('cli.py', 'session.py', 'sandbox.py', 'submission.py')]
CORE_PATTERN = '/proc/sys/kernel/core_pattern'
UID_BASE = 1500000000      # sandbox.UID_BASE: the sandbox's uids lie above it
CORE_UID_BASE = UID_BASE + (1 << 27)   # core.CORE_UID_OFFSET: roscore's uids lie above this
SESSION_MODULE = 'chase_tools.grading.session'  # the session: the grader's node /grade_probe
# What the grader's own processes (the grade, its session and its node, roscore, and what runs
# as root on the way into a sandbox) hold together for one submission at any time, and what
# the report folder of one submission may hold: a capped log is 256 KiB (--log-limit) and a
# line, and there are a dozen of them.
GRADER_MEMORY_BOUND = 1280 << 20
REPORT_BOUND = 4 << 20
# Wall seconds the grade whose node is shut down in its one trial may take: a trial that
# waited for the sim time of a node that no longer listens would take 21 minutes.
SHUT_DOWN_GRADE_S = 600
STOP_WAIT_S = 120

# The teacher's own environment, which no sandbox may see.
GRADER_SECRETS = {'AWS_SECRET_ACCESS_KEY': 'aws-%s' % uuid.uuid4().hex,
                  'GITHUB_TOKEN': 'token-%s' % uuid.uuid4().hex,
                  'SSH_AUTH_SOCK': '/tmp/ssh-%s/agent.1' % uuid.uuid4().hex}
# Where the fixtures that reach for the programs the grader runs as root leave their marks.
ESCAPE_MARKERS = ('escaped_preload', 'escaped_library', 'escaped_path')

SECRET_BALL = '<sphere><radius>0.4321</radius></sphere>'
SECRET_WORLD = '''<sdf version="1.6"><world name="secret"><model name="white_ball"><pose>1 0 0.5 0 0 0</pose>
<link name="ball"><collision name="c"><geometry>%s</geometry></collision>
<visual name="v"><geometry>%s</geometry><material><ambient>1 1 1 1</ambient><diffuse>1 1 1 1</diffuse>
<specular>1 1 1 1</specular></material></visual></link></model></world></sdf>
''' % (SECRET_BALL, SECRET_BALL)


NEEDS_ROOT_AND_BWRAP = [
    pytest.mark.skipif(shutil.which('bwrap') is None, reason='the grader needs bubblewrap'),
    pytest.mark.skipif(os.geteuid() != 0, reason='the sandbox runs as a uid of its own only when '
                                                 'the grader runs as root'),
]

class Listener:
    """A server outside the session's network namespace, counting who reaches it."""

    def __init__(self, family, address):
        self.sock = socket.socket(family)
        self.sock.bind(address)
        self.sock.listen(8)
        self.sock.settimeout(0.5)
        self.accepted = 0
        self.stopping = False
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self):
        while not self.stopping:
            try:
                conn, _peer = self.sock.accept()
            except OSError:
                continue
            self.accepted += 1
            conn.close()

    def close(self):
        self.stopping = True
        self.thread.join(5)
        self.sock.close()


class Host:
    """What the hostile submissions aim at, and a snapshot of it to compare."""

    def __init__(self, base):
        self.canary = os.path.join(base, 'canary')
        for name in ('run', 'caches', 'grader', 'launch', 'home', 'tmp'):
            os.makedirs(os.path.join(self.canary, name))
        for name in ('session.json', 'result.json'):
            with open(os.path.join(self.canary, name), 'w') as stream:
                stream.write('canary\n')
        # A launch file the grader would rewrite (it drops rviz) if it followed a link to it.
        with open(PROJECT_FILES[0]) as stream:
            launch = stream.read()
        with open(os.path.join(self.canary, 'host.launch'), 'w') as stream:
            stream.write(launch.replace('</launch>', '  <node name="rviz" pkg="rviz" type="rviz"/>\n'
                                                     '</launch>'))
        # Inside this workspace, which the sandbox shows read-only: a root-only secret, a
        # canary file and a Unix socket.
        self.private = os.path.join(HERE, 'fixtures', 'secret_%d' % os.getpid())
        os.mkdir(self.private, 0o755)
        self.secret = os.path.join(self.private, 'secret')
        self.secret_text = 'root-only-%s' % uuid.uuid4().hex
        with open(os.open(self.secret, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), 'w') as stream:
            stream.write(self.secret_text)
        # A root-only world whose white ball is of a size no world of the fixtures has.
        self.secret_world = os.path.join(self.private, 'secret.world')
        with open(os.open(self.secret_world, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), 'w') as stream:
            stream.write(SECRET_WORLD)
        # A root-only folder holding a package.xml of a name no fixture knows but from here;
        # outside this workspace, whose packages other tests list and build meanwhile.
        self.root_only_package = 'root_only_%s' % uuid.uuid4().hex
        self.root_only_folder = os.path.join(base, 'root_only_package')
        os.mkdir(self.root_only_folder, 0o700)
        with open(os.path.join(self.root_only_folder, 'package.xml'), 'w') as stream:
            stream.write('<package format="2"><name>%s</name><version>0.0.1</version>'
                         '<description>root only</description><maintainer email="root@localhost">'
                         'root</maintainer><license>BSD</license></package>\n' % self.root_only_package)
        self.project_file = os.path.join(self.private, 'project_canary')
        with open(self.project_file, 'w') as stream:
            stream.write('project canary\n')
        with open('/etc/shadow') as stream:
            self.shadow_line = stream.readline().strip()
        self.tcp = Listener(socket.AF_INET, ('127.0.0.1', 0))
        self.unix_path = os.path.join(self.private, 's')
        self.unix = Listener(socket.AF_UNIX, self.unix_path)
        self.before = self.snapshot()

    @property
    def params(self):
        return dict(CANARY=self.canary, SECRET=self.secret, SECRET_WORLD=self.secret_world,
                    PROJECT_FILE=self.project_file, ROOT_ONLY_PACKAGE=self.root_only_package,
                    ROOT_ONLY_FOLDER=self.root_only_folder,
                    PORT=self.tcp.sock.getsockname()[1], SOCKET=self.unix_path)

    def snapshot(self):
        seen = {CORE_PATTERN: _read(CORE_PATTERN)}
        for top in (self.canary, self.private):
            for root, dirs, files in os.walk(top):
                for name in dirs + files:
                    path = os.path.join(root, name)
                    info = os.lstat(path)
                    seen[path] = (stat.filemode(info.st_mode), info.st_uid, _digest(path, info))
        for path in PROJECT_FILES:
            seen[path] = _digest(path, os.lstat(path))
        return seen

    def assert_unchanged(self):
        after = self.snapshot()
        changed = sorted(path for path in set(self.before) | set(after)
                         if self.before.get(path) != after.get(path))
        assert changed == [], 'changed outside the scratch folder: %s' % changed

    def close(self):
        self.tcp.close()
        self.unix.close()
        shutil.rmtree(self.private, ignore_errors=True)


@pytest.fixture(scope='module')
def host(tmp_path_factory):
    """The Host of a module's tests; each test module imports it."""
    watched = Host(str(tmp_path_factory.mktemp('host')))
    yield watched
    watched.close()


def _read(path):
    with open(path) as stream:
        return stream.read()


def _digest(path, info):
    if stat.S_ISLNK(info.st_mode):
        return os.readlink(path)
    if not stat.S_ISREG(info.st_mode):
        return None
    with open(path, 'rb') as stream:
        return hashlib.sha256(stream.read()).hexdigest()


def grade(args, timeout=GRADE_TIMEOUT_S, env=None):
    return subprocess.run(['grade'] + [str(arg) for arg in args], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=timeout, check=False, env=env)


class GraderMemory:
    """The largest memory (resident, summed) that the grader's own processes held at once, per
    submission, while a grade ran: every process under the grade's that runs as root or as
    roscore's uid. The submission's own (uids from UID_BASE to CORE_UID_BASE) are bounded by
    its cgroup and are not counted. A class grade's processes count under the submission
    whose grader (`grade PATH --one`) started them, the class's own under ''."""

    EVERY_S = 0.1

    def __init__(self, pid):
        self.pid = pid
        self.peaks = {}
        # {submission: the uids its session processes (the grader's node) ran as}
        self.session_uids = {}
        self.stopping = False
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        while not self.stopping:
            self.sample()
            time.sleep(self.EVERY_S)

    def sample(self):
        table = {}
        for entry in os.listdir('/proc'):
            if not entry.isdigit():
                continue
            try:
                with open('/proc/%s/status' % entry) as stream:
                    status = dict(line.split(':', 1) for line in stream if ':' in line)
                with open('/proc/%s/cmdline' % entry, 'rb') as stream:
                    argv = stream.read().decode(errors='replace').split('\0')
            except (OSError, ValueError):
                continue
            table[int(entry)] = (int(status['PPid']), int(status['Uid'].split()[0]),
                                 int(status.get('VmRSS', '0 kB').split()[0]) << 10, argv)
        held = {}
        for pid, (_ppid, uid, rss, argv) in table.items():
            # The session's own process, not one whose command line starts it.
            if argv[1:3] == ['-m', SESSION_MODULE]:
                owner = self.owner(pid, table)
                if owner is not None:
                    self.session_uids.setdefault(owner, set()).add(uid)
            if uid != 0 and uid < CORE_UID_BASE:
                continue
            owner = self.owner(pid, table)
            if owner is not None:
                held[owner] = held.get(owner, 0) + rss
        for owner, total in held.items():
            self.peaks[owner] = max(self.peaks.get(owner, 0), total)

    def owner(self, pid, table):
        """The submission whose grader pid runs under, '' for the class's own; None if it is
        not the grade's."""
        submission = ''
        while pid in table:
            ppid, _uid, _rss, argv = table[pid]
            if '--one' in argv and 'chase_tools.grading.cli' in argv and not submission:
                submission = os.path.basename(argv[argv.index('chase_tools.grading.cli') + 1])
            if pid == self.pid:
                return submission
            pid = ppid
        return None

    def stop(self):
        self.stopping = True
        self.thread.join(5)
        return self


def watched_grade(args, timeout=GRADE_TIMEOUT_S, env=None):
    """(grade's CompletedProcess, its GraderMemory: peaks and session_uids); TimeoutExpired past
    timeout."""
    proc = subprocess.Popen(['grade'] + [str(arg) for arg in args], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, env=env)
    memory = GraderMemory(proc.pid)
    try:
        output, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise
    finally:
        memory.stop()
    return subprocess.CompletedProcess(proc.args, proc.returncode, output), memory


def folder_size(path):
    return sum(os.lstat(os.path.join(root, name)).st_size
               for root, _dirs, files in os.walk(path) for name in files)


def items(graded, name):
    return {item['name']: item for item in graded[1][name]['items']}


def notes(graded, name):
    return '\n'.join(graded[1][name]['notes'])


def log(graded, name, log_name):
    path = os.path.join(graded[2], name, 'logs', log_name)
    with open(path, errors='replace') as stream:
        return stream.read()


def everything_written(out_dir):
    """Every file the grader wrote for a submission, as one text."""
    texts = []
    for root, _dirs, files in os.walk(out_dir):
        for name in files:
            with open(os.path.join(root, name), 'rb') as stream:
                texts.append(stream.read().decode(errors='replace'))
    return '\n'.join(texts)


def sandbox_uid(result):
    match = re.search(r'as uid (\d+), a uid of its own', result['isolation'])
    assert match, result['isolation']
    return int(match.group(1))
