"""Running untrusted code: a submission's build, its launch files (xacro runs Python) and its nodes.

Each command runs under bubblewrap (bwrap), and there:
  - as a uid and gid of the submission's own (when the grader runs as root: a
    high uid no account has, one per submission graded at once), with no
    supplementary groups, no capabilities and no_new_privs, so nothing
    root-only can be read and no setuid program helps; a grader that is not
    root runs it as its own uid;
  - in a file tree of its own, all read-only: the system (/usr, /bin, /lib*,
    /sbin, a few files of /etc, never shadow or keys), this workspace
    (the folders its environment names inside the checkout, and the venv:
    environment_paths) and what the caller shows (the built submission);
    nothing else of the machine (/home, /root, /srv, /tmp, /var, /run, data
    folders) is there; /tmp is an empty read-only folder;
  - writable: only the folder given to it (its build or run folder), which lies
    on a filesystem of the submission's own, of the disk limit (disk.py);
  - in namespaces of its own for processes (it sees and can signal only its
    own, and they all end with it), IPC and host name; a build also for the
    network (loopback only); launched nodes share the network namespace of
    the grading session, which holds nothing but loopback, the ROS master and
    the simulator;
  - unable to make user namespaces of its own (which would let it mount and
    rearrange what it sees): where bubblewrap has --disable-userns, a second,
    unprivileged bwrap inside the sandbox closes them (USERNS_LAYER);
  - with a /dev/shm of its own, of limits.shm_size() (a tmpfs takes half the
    machine's memory unless told otherwise);
  - within limits (see limits.py): memory and processes for the submission as
    a whole, open files and file size per process;
  - with an environment of its own: only the variables ALLOWED_VARIABLES names
    (ROS's, the search paths, the locale), taken from the environment the caller
    hands over, with HOME, ROS_HOME and TMPDIR in its scratch.

What runs as root on the way in (the cgroup join, bwrap, prlimit and setpriv)
is named by its full path in the system's folders and runs with CLEAN_ENV,
never with the submission's environment: a built workspace's setup files put
its devel/bin first on PATH and its devel/lib on LD_LIBRARY_PATH, and its env
hooks can set LD_PRELOAD, any of which would run the submission's code as
root. That environment is handed over last, by env -i, once setpriv has made
the process the submission's.

Pure: builds command lines, no ROS.
"""
import os
import pwd
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field

from chase_tools.grading import limits as limits_module
from chase_tools.grading.disk import Disk
from chase_tools.grading.limits import Cgroups, Limits
from chase_tools.grading.scratch import write_new

SYSTEM_FOLDERS = ('/usr', '/bin', '/sbin', '/lib', '/lib32', '/lib64', '/libx32')
# What of /etc programs here need: the dynamic linker, the compilers' alternatives, name
# resolution of localhost, time zone, ROS's and Python's own settings. The sandbox gets
# its own passwd and group; nothing root-only (shadow, ssh keys, sudoers) is shown.
ETC_ENTRIES = ('alternatives', 'ld.so.cache', 'ld.so.conf', 'ld.so.conf.d', 'hosts', 'host.conf',
               'nsswitch.conf', 'gai.conf', 'localtime', 'timezone', 'os-release', 'lsb-release',
               'debian_version', 'ros', 'catkin', 'python3', 'python3.11', 'mime.types', 'protocols',
               'services', 'networks', 'fonts', 'terminfo', 'ssl/openssl.cnf', 'ssl/certs',
               'xml', 'sgml', 'bash.bashrc', 'inputrc')
SHOWN_SYS = ('/sys/devices/system/cpu',)      # core counts (os.cpu_count, make -j)
# Far above any account's uid, and far below (uid_t)-1; one per grading process.
UID_BASE = 1500000000
SANDBOX_USER = 'submission'


# Where the programs that run as root on the way into the sandbox are looked for: the
# system's folders only, never a PATH that the submission's setup files wrote.
SYSTEM_PATH = '/usr/sbin:/usr/bin:/sbin:/bin'
# The environment of those programs: nothing of the grader's or the submission's.
CLEAN_ENV = {'PATH': SYSTEM_PATH, 'LC_ALL': 'C'}
# What of an environment reaches the sandbox: ROS's own variables, the search paths a
# sourced workspace sets, the locale and the simulator's. Everything else (the teacher's
# SSH_AUTH_SOCK, AWS_* keys, tokens, the display) stays out; HOME, ROS_HOME, TMPDIR, USER
# and LOGNAME are the sandbox's own.
ALLOWED_VARIABLES = ('PATH', 'PYTHONPATH', 'LD_LIBRARY_PATH', 'CMAKE_PREFIX_PATH', 'PKG_CONFIG_PATH',
                     'VIRTUAL_ENV', 'CATKIN_SHELL', 'LANG', 'LANGUAGE', 'TZ',
                     'SETUPTOOLS_USE_DISTUTILS', 'PYTHONUNBUFFERED', 'PYTHONDONTWRITEBYTECODE',
                     'PYTHONIOENCODING')
ALLOWED_PREFIXES = ('ROS_', 'ROSCONSOLE_', 'ROSLAUNCH_', 'ROSLISP_', 'GAZEBO_', 'LC_')
VARIABLE_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*$')
# A larger value is left out: every variable is an argument of the sandbox's command line,
# which the kernel bounds.
VARIABLE_LIMIT = 64 << 10


class SandboxError(Exception):
    """The sandbox cannot be made on this machine."""


def system_program(name):
    """The full path of a program in the system's folders, or None."""
    return shutil.which(name, path=SYSTEM_PATH)


def bwrap_path():
    return system_program('bwrap')


def allowed_environment(env):
    """The variables of env that may reach the sandbox (ALLOWED_VARIABLES, ALLOWED_PREFIXES)."""
    return {name: value for name, value in env.items()
            if (name in ALLOWED_VARIABLES or name.startswith(ALLOWED_PREFIXES))
            and VARIABLE_NAME.match(name) and len(value) <= VARIABLE_LIMIT}


def sandbox_uid(pid=None):
    """A uid for the submission graded by process pid: unique among running graders, and no
    account's."""
    uid = UID_BASE + (os.getpid() if pid is None else pid)
    while True:
        try:
            pwd.getpwuid(uid)
        except KeyError:
            return uid
        uid += 1 << 22          # past the largest pid_max


@dataclass
class Confinement:
    """What every sandbox of one submission shares: who its code runs as, and its limits."""
    uid: int
    gid: int
    switch_user: bool             # the grader is root: setpriv to uid and gid inside bwrap
    limits: Limits = field(default_factory=Limits)
    cgroups: Cgroups = field(default_factory=Cgroups)
    passwd: str = ''              # shown as /etc/passwd and /etc/group
    group: str = ''
    disk: Disk = None             # the filesystem of its writable folders (disk.py)
    close_userns: bool = False    # a second bwrap closes user namespaces (USERNS_LAYER)
    # The grader's own: the group the submission's cgroups and the session's are made in.
    run_cgroups: Cgroups = None
    session_as_root: str = ''     # why the session could not get a uid of its own, if it could not

    @classmethod
    def of_this_process(cls, limits=None, cgroups=None):
        """A uid of the submission's own when the grader runs as root, else the grader's."""
        root = os.geteuid() == 0
        uid = sandbox_uid() if root else os.getuid()
        gid = uid if root else os.getgid()
        return cls(uid, gid, root, limits or Limits(), cgroups or Cgroups(why='not asked for'))

    @classmethod
    def create(cls, folder, limits=None, cgroups=None, disk=None):
        """of_this_process(), with passwd and group for the sandbox written to folder (a folder
        no sandbox can write)."""
        made = cls.of_this_process(limits, cgroups)
        made.disk = disk
        made.passwd = os.path.join(folder, 'passwd')
        made.group = os.path.join(folder, 'group')
        name = SANDBOX_USER if made.switch_user else _user_name(made.uid)
        write_new(made.passwd, 'root:x:0:0:root:/root:/usr/sbin/nologin\n'
                               '%s:x:%d:%d:the graded submission:/nonexistent:/bin/sh\n'
                               'nobody:x:65534:65534:nobody:/nonexistent:/usr/sbin/nologin\n'
                  % (name, made.uid, made.gid), mode=0o644)
        write_new(made.group, 'root:x:0:\n%s:x:%d:\nnogroup:x:65534:\n' % (name, made.gid), mode=0o644)
        return made

    @property
    def own_uid(self):
        """The sandbox's uid is the submission's alone (not the grader's)."""
        return self.switch_user

    def describe(self):
        """Who the code runs as and what bounds it, for the report."""
        who = ('as uid %d, a uid of its own (the grader runs as root), with no capabilities and '
               'no_new_privs' % self.uid if self.switch_user else
               'as the grader\'s own uid %d (the grader does not run as root), with no capabilities'
               % self.uid)
        limits = limits_module.describe(self.limits, self.cgroups, self.own_uid)
        if self.disk is not None:
            limits += '; %s' % self.disk.describe()
        limits += '; a /dev/shm of %s in each sandbox' % limits_module.size_text(
            limits_module.shm_size(self.limits))
        if self.close_userns:
            who += '; it cannot make user namespaces (bubblewrap\'s --disable-userns)'
        return '%s; limits %s' % (who, limits)

    def usage(self):
        """What the kernel refused the submission so far, and whether its folders are full."""
        usage = self.cgroups.usage()
        if self.disk is not None and self.disk.full():
            usage.disk_full = self.disk.used_text()
        return usage

    def as_json(self):
        return {'uid': self.uid, 'gid': self.gid, 'switch_user': self.switch_user,
                'limits': self.limits.as_json(), 'cgroups': self.cgroups.as_json(),
                'passwd': self.passwd, 'group': self.group,
                'disk': self.disk.as_json() if self.disk is not None else None,
                'close_userns': self.close_userns}

    @classmethod
    def from_json(cls, data):
        return cls(data['uid'], data['gid'], data['switch_user'], Limits.from_json(data['limits']),
                   Cgroups.from_json(data['cgroups']), data.get('passwd', ''), data.get('group', ''),
                   Disk.from_json(data['disk']) if data.get('disk') else None,
                   data.get('close_userns', False))


# Inside the sandbox, as the submission's uid: a user namespace that maps that uid alone and
# cannot make another (bubblewrap's --disable-userns needs one of its own, --unshare-user, and
# a namespace made by root would map the submission to root). Its processes are the command's:
# sandbox_processes.sandbox_children looks through it.
USERNS_LAYER = ('--unshare-user', '--disable-userns', '--dev-bind', '/', '/', '--die-with-parent',
                '--')


def userns_layer(bwrap):
    return [bwrap] + list(USERNS_LAYER)


_BWRAP_HELP = {}


def bwrap_has(option):
    """Whether the installed bubblewrap takes option (bwrap --help lists it)."""
    if 'text' not in _BWRAP_HELP:
        bwrap = bwrap_path()
        try:
            _BWRAP_HELP['text'] = subprocess.run(
                [bwrap, '--help'], env=dict(CLEAN_ENV), stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT, text=True, timeout=30, check=False).stdout if bwrap else ''
        except (OSError, subprocess.TimeoutExpired):
            _BWRAP_HELP['text'] = ''
    return re.search(r'^\s*%s\b' % re.escape(option), _BWRAP_HELP['text'], re.M) is not None


def close_userns_where_possible(confinement, scratch):
    """Set confinement.close_userns when the sandbox can close user namespaces here: bubblewrap
    has --disable-userns, and the submission's uid may make the one namespace that takes (where
    it may not, it can make none either). scratch: an empty folder for the trial sandbox."""
    confinement.close_userns = False
    if not bwrap_has('--disable-userns'):
        return
    confinement.close_userns = True
    box = Sandbox(scratch, own_network=True, confinement=confinement)
    box.prepare()
    try:
        cmd, env = box.wrap(['true'], {})
        done = subprocess.run(cmd, env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, timeout=30, check=False)
        confinement.close_userns = done.returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        confinement.close_userns = False


def _user_name(uid):
    try:
        return pwd.getpwuid(uid).pw_name
    except KeyError:
        return SANDBOX_USER


class Sandbox:
    """Command lines that run a program with only `scratch` writable.

    scratch: the writable folder; HOME is scratch/home and TMPDIR scratch/tmp
        (made beforehand, see prepare() and scratch.Scratch).
    visible: folders to show read-only (this workspace, the built submission).
    own_network: a network namespace of the command's own (loopback only);
        otherwise the caller's namespace is shared.
    stand_ins: (copy, path) pairs: a writable copy shown at path, for read-only
        folders that a program insists on writing to (see cache_stand_ins).
    overlays: {path: copy}: a file shown read-only at path in place of what is
        there (the grader's prepared launch files).
    """

    def __init__(self, scratch, visible=(), own_network=False, stand_ins=(), confinement=None):
        self.scratch = os.path.abspath(scratch)
        self.visible = [os.path.abspath(path) for path in visible]
        self.own_network = own_network
        self.stand_ins = list(stand_ins)
        self.overlays = {}
        self.confinement = confinement

    def prepare(self):
        """Make scratch/home and scratch/tmp for the sandbox's uid (for a scratch folder that no
        sandbox has used yet)."""
        confinement = self._confinement()
        for path in (self.scratch, self.home, self.tmp):
            os.makedirs(path, mode=0o700, exist_ok=path == self.scratch)
            if confinement.switch_user:
                os.chown(path, confinement.uid, confinement.gid, follow_symlinks=False)

    def _confinement(self):
        if self.confinement is None:
            self.confinement = Confinement.of_this_process()
        return self.confinement

    @property
    def home(self):
        return os.path.join(self.scratch, 'home')

    @property
    def tmp(self):
        return os.path.join(self.scratch, 'tmp')

    def wrap(self, cmd, env, cwd=None):
        """(command line, environment) to start cmd in the sandbox with what env() keeps of
        env: the command line is to run with the environment returned, CLEAN_ENV."""
        return self.command(cmd, cwd=cwd, env=env), dict(CLEAN_ENV)

    def command(self, cmd, cwd=None, env=None):
        """The command line that runs cmd in the sandbox, in cwd (default: the scratch), with
        what env() keeps of env; it is to be run with CLEAN_ENV (see wrap)."""
        bwrap = bwrap_path()
        tools = {name: system_program(name) for name in ('prlimit', 'setpriv', 'env')}
        if bwrap is None:
            raise SandboxError('bubblewrap (bwrap) is not installed; install the Debian package '
                               'bubblewrap, or pass --no-isolation inside a container that is '
                               'isolated itself')
        missing = sorted(name for name, path in tools.items() if path is None)
        if missing:
            raise SandboxError('%s not found in %s (Debian packages util-linux and coreutils)'
                               % (', '.join(missing), SYSTEM_PATH))
        confinement = self._confinement()
        tree = _Tree()
        for path in SYSTEM_FOLDERS:
            if os.path.islink(path):
                tree.args += ['--symlink', os.readlink(path), path]
            elif os.path.isdir(path):
                tree.bind(path)
        tree.folder('/etc')
        for entry in ETC_ENTRIES:
            if os.path.exists(os.path.join('/etc', entry)):
                tree.bind(os.path.join('/etc', entry))
        for name, source in (('passwd', confinement.passwd), ('group', confinement.group)):
            if source:
                tree.bind(source, os.path.join('/etc', name))
        for path in SHOWN_SYS:
            if os.path.isdir(path):
                tree.bind(path)
        tree.args += ['--dev', '/dev'] + self.shm_args() + [
            '--proc', '/proc', '--ro-bind', '/proc/sys', '/proc/sys']
        if confinement.close_userns:
            # The second bwrap sets its own user namespace's user.max_user_namespaces to 0 here;
            # the submission's uid can write none of the machine's (they are root's).
            tree.args += ['--bind', '/proc/sys/user', '/proc/sys/user']
        tree.mount('/tmp', ['--perms', '0755', '--tmpfs', '/tmp'], bound=False)
        for path in self.visible:
            tree.bind(path)
        tree.bind(self.scratch, writable=True)
        for copy, path in self.stand_ins:
            tree.bind(copy, path, writable=True)
        for path, copy in sorted(self.overlays.items()):
            # A file the sandbox does not show needs no stand-in, and bwrap could not put one
            # there: a program of the grader's workspace that only another environment names
            # (student mode's devel_platform) is out of the sandbox's reach as it is.
            # A path through a link to another stand-in's file has it already: bwrap cannot
            # bind over a link.
            real = os.path.realpath(path)
            if tree.shows(path) and (real == path or real not in self.overlays):
                tree.bind(copy, path)
        args = limits_module.join_command(confinement.cgroups.procs_files()) + [bwrap]
        args += tree.args + ['--remount-ro', '/tmp']
        args += ['--unshare-pid', '--unshare-ipc', '--unshare-uts', '--die-with-parent',
                 '--new-session', '--cap-drop', 'ALL', '--clearenv']
        for name, value in sorted(CLEAN_ENV.items()):
            args += ['--setenv', name, value]
        if self.own_network:
            args.append('--unshare-net')
        if confinement.switch_user:
            # Kept only for setpriv, which drops them with the switch to the submission's uid.
            args += ['--cap-add', 'CAP_SETUID', '--cap-add', 'CAP_SETGID', '--cap-add', 'CAP_SETPCAP']
        # bwrap keeps no capability to enter a folder of the sandbox's uid: the command does.
        args += ['--chdir', '/']
        args += limits_module.rlimit_command(confinement.limits, confinement.cgroups.active,
                                             confinement.own_uid, tools['prlimit'])
        if confinement.switch_user:
            args += [tools['setpriv'], '--reuid', str(confinement.uid), '--regid', str(confinement.gid),
                     '--clear-groups', '--inh-caps=-all', '--bounding-set=-all', '--no-new-privs',
                     '--']
        if confinement.close_userns:
            args += userns_layer(bwrap)
        # The submission's environment, from here on only: what runs now is the submission's.
        handed = ['%s=%s' % item for item in sorted(self.env(env or {}).items())]
        return args + [tools['env'], '-i', '--chdir=%s' % os.path.abspath(cwd or self.scratch),
                       '--'] + handed + list(cmd)

    def shm_args(self):
        """bwrap's arguments for /dev/shm: a tmpfs of limits.shm_size(); where bwrap cannot size a
        tmpfs, the sandbox's own TMPDIR, on the filesystem of the disk limit."""
        size = limits_module.shm_size(self._confinement().limits)
        if bwrap_has('--size'):
            return ['--perms', '1777', '--size', str(size), '--tmpfs', '/dev/shm']
        return ['--bind', self.tmp, '/dev/shm']

    def env(self, env):
        """What of env reaches the sandbox (allowed_environment), with HOME, ROS_HOME and TMPDIR
        inside the scratch and the sandbox's user."""
        env = allowed_environment(env)
        confinement = self._confinement()
        user = SANDBOX_USER if confinement.switch_user else _user_name(confinement.uid)
        env.update(HOME=self.home, ROS_HOME=os.path.join(self.home, '.ros'), TMPDIR=self.tmp,
                   USER=user, LOGNAME=user)
        return env


class _Tree:
    """bwrap arguments for a tree of read-only binds, with every folder above a bind made
    readable (bwrap would make it 0700, which the sandbox's uid could not enter)."""

    def __init__(self):
        self.args = []
        self.mounted = []
        self.made = set()

    def _inside_mount(self, path):
        return any(path == top or path.startswith(top.rstrip('/') + '/') for top in self.mounted)

    def shows(self, path):
        """Whether path is there in the sandbox: a file under a folder bound so far, reached
        through links that lead to such a folder too."""
        return (self._inside_mount(path) and os.path.exists(path)
                and self._inside_mount(os.path.realpath(path)))

    def folder(self, path):
        if path in self.made or self._inside_mount(path):
            return
        parent = os.path.dirname(path)
        if parent != path and parent != '/':
            self.folder(parent)
        self.args += ['--perms', '0755', '--dir', path]
        self.made.add(path)

    def mount(self, path, args, bound=True):
        """bound: a bind, whose folders exist already; a tmpfs is empty, and its folders are
        made here."""
        parent = os.path.dirname(path)
        if parent != '/':
            self.folder(parent)
        self.args += args
        if bound:
            self.mounted.append(path)
        else:
            self.made.add(path)

    def bind(self, source, dest=None, writable=False):
        dest = dest or source
        self.mount(dest, ['--bind' if writable else '--ro-bind', source, dest])


# The checkout that holds this code (catkin_ws/src/chase_tools/src/chase_tools/grading/).
CHECKOUT = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                         *[os.pardir] * 6))


def environment_paths(env, checkout=CHECKOUT):
    """Folders the environment names that the sandbox must show read-only: those inside this
    checkout (the devel space, the package path, env/) and the venv. A folder the environment
    names elsewhere (~/.local/bin on PATH, a teacher's own PYTHONPATH) stays hidden, and so
    does the folder that holds the checkout.

    A bin folder's scripts may load code kept beside it (env/bin/catkin_make
    loads env/catkin_make.py), so the folder above it is shown instead, unless
    that is the checkout itself.

    Each folder is shown where it really is and where the environment names
    it: a checkout reached through a link (/home/u/proj -> /tmp/x) is named
    by the link in the environment and in what was built through it (the
    devel space's setup files, the venv's scripts), and a link under a folder
    the sandbox hides leads nowhere there.
    """
    checkout = os.path.realpath(checkout)
    roots = [checkout]
    if env.get('VIRTUAL_ENV') and os.path.isdir(env['VIRTUAL_ENV']):
        roots.append(os.path.realpath(env['VIRTUAL_ENV']))
    named = []
    for name in ('VIRTUAL_ENV', 'CMAKE_PREFIX_PATH', 'ROS_PACKAGE_PATH', 'PYTHONPATH',
                 'LD_LIBRARY_PATH', 'PKG_CONFIG_PATH'):
        named += [path for path in env.get(name, '').split(os.pathsep) if path]
    for path in env.get('PATH', '').split(os.pathsep):
        path = os.path.abspath(path) if path else ''
        if path and os.path.basename(os.path.realpath(path)) == 'bin':
            path = os.path.dirname(path)
        if path and os.path.realpath(path) != checkout:
            named.append(path)
    paths = set()
    for path in named:
        real = os.path.realpath(path)
        if os.path.isdir(real) and any(_within(real, root) for root in roots):
            paths |= _spellings(path)
    paths = {path for path in paths if not any(_within(path, system) for system in SYSTEM_FOLDERS)}
    # A folder inside another needs no bind of its own.
    return sorted(p for p in paths if not any(p != q and _within(p, q) for q in paths))


def _spellings(path):
    """The folder as named (absolute) and as resolved."""
    named = os.path.normpath(os.path.abspath(path))
    return {named, os.path.realpath(named)}


def _within(path, top):
    return path == top or path.startswith(top.rstrip('/') + '/')


def cache_stand_ins(package_dir, caches):
    """Writable copies of a Python package's __pycache__ folders in `caches`, as Sandbox stand_ins.

    numba loads its compiled kernels from __pycache__ only if it can write
    there; seeing a read-only folder, it compiles them again, which costs the
    simulator seconds at every start. A copy in the scratch folder keeps the
    cache and leaves the original untouched. caches is a folder no sandbox has
    written to; the caller hands it to the sandbox's uid afterwards.
    """
    pairs = []
    for root, dirs, _files in os.walk(package_dir):
        if '__pycache__' in dirs:
            original = os.path.join(root, '__pycache__')
            copy = os.path.join(caches, os.path.relpath(original, os.path.dirname(package_dir)))
            shutil.copytree(original, copy, symlinks=True, dirs_exist_ok=True)
            pairs.append((copy, original))
        dirs[:] = [d for d in dirs if d != '__pycache__']
    return pairs


def flatsim_cache_stand_ins(caches):
    """cache_stand_ins of every folder of the flatsim package: catkin's devel space extends its
    __path__ to its sources."""
    import flatsim
    return [pair for path in flatsim.__path__ for pair in cache_stand_ins(path, caches)]


def network_namespace_command(cmd):
    """cmd in a network namespace of its own with loopback up, everything else as the caller's.

    The grading session runs in one: the master, the simulator and the
    submission's nodes talk over loopback, and nothing there reaches out.
    """
    bwrap = bwrap_path()
    if bwrap is None:
        raise SandboxError('bubblewrap (bwrap) is not installed')
    return [bwrap, '--dev-bind', '/', '/', '--unshare-net', '--die-with-parent'] + list(cmd)


def check():
    """None if sandboxes can be made here, else why not."""
    if bwrap_path() is None:
        return ('bubblewrap (bwrap) is not installed (Debian package bubblewrap; ./setup.sh '
                'installs it)')
    with tempfile.TemporaryDirectory(prefix='grade_probe_') as scratch:
        box = Sandbox(os.path.join(scratch, 'box'), own_network=True,
                      confinement=Confinement.create(scratch))
        box.prepare()
        try:
            cmd, env = box.wrap(['true'], {})
            proc = subprocess.run(cmd, env=env, stdin=subprocess.DEVNULL,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  timeout=30, check=False)
        except (OSError, subprocess.TimeoutExpired) as error:
            return 'bubblewrap could not run: %s' % error
    if proc.returncode != 0:
        return ('bubblewrap cannot make its namespaces here: %s. Run as root, or where '
                'unprivileged user namespaces are allowed; in a container, see docs/teaching.md '
                '(grading, one submission per container)' % proc.stdout.strip())
    return None
