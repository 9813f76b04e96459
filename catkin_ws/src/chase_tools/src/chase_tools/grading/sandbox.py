"""Running untrusted code: a submission's build, its launch files (xacro runs Python) and its nodes.

Each command runs under bubblewrap (bwrap):
  - the root file system is mounted read-only;
  - /home, /root, /tmp, /var/tmp, /run, /mnt, /media and /srv are replaced by
    empty read-only folders, so nothing private there can be read and no
    socket there (a Docker or D-Bus socket) can be reached;
  - the only writable folder is the submission's scratch folder;
  - the workspace underneath (this repository) is visible read-only;
  - the command has a process namespace of its own (it sees and can signal
    only its own processes), no capabilities (it cannot mount, remount or
    make namespaces), and per-process limits on memory, file size and core dumps;
  - the network: a build gets a network namespace of its own (loopback only);
    launched nodes share the namespace of the grading session, which holds
    nothing but a loopback interface, the ROS master and the simulator.

Pure: builds command lines, no ROS.
"""
import os
import shutil
import subprocess
import tempfile

HIDDEN = ('/home', '/root', '/tmp', '/var/tmp', '/run', '/mnt', '/media', '/srv')
# Per process. Address space, not resident memory: numba's LLVM and a C++
# compiler both stay far below it.
ADDRESS_SPACE_BYTES = 4 << 30
FILE_SIZE_BYTES = 1 << 30


class SandboxError(Exception):
    """The sandbox cannot be made on this machine."""


def bwrap_path():
    return shutil.which('bwrap')


class Sandbox:
    """Command lines that run a program with only `scratch` writable.

    visible: folders outside the hidden ones to show read-only (the workspace top).
    own_network: a network namespace of the command's own (loopback only);
        otherwise the caller's namespace is shared.
    stand_ins: (copy, path) pairs: a writable copy inside the scratch folder
        shown at path, for read-only folders that a program insists on
        writing to (see cache_stand_ins).
    """

    def __init__(self, scratch, visible=(), own_network=False, stand_ins=()):
        self.scratch = os.path.abspath(scratch)
        self.visible = [os.path.abspath(path) for path in visible]
        self.own_network = own_network
        self.stand_ins = list(stand_ins)

    def command(self, cmd, cwd=None):
        bwrap = bwrap_path()
        if bwrap is None:
            raise SandboxError('bubblewrap (bwrap) is not installed; install the Debian package '
                               'bubblewrap, or pass --no-isolation inside a container that is '
                               'isolated itself')
        args = [bwrap, '--ro-bind', '/', '/', '--dev', '/dev', '--proc', '/proc']
        hidden = [path for path in HIDDEN if os.path.isdir(path) and not os.path.islink(path)]
        for path in hidden:
            args += ['--tmpfs', path]
        for path in self.visible:
            args += ['--ro-bind', path, path]
        args += ['--bind', self.scratch, self.scratch]
        for copy, path in self.stand_ins:
            args += ['--bind', copy, path]
        for path in hidden:
            args += ['--remount-ro', path]
        args += ['--unshare-pid', '--unshare-ipc', '--unshare-uts', '--cap-drop', 'ALL',
                 '--die-with-parent']
        if self.own_network:
            args.append('--unshare-net')
        args += ['--chdir', os.path.abspath(cwd or self.scratch)]
        return args + limits() + list(cmd)

    def env(self, env):
        """env with HOME, ROS_HOME and TMPDIR inside the scratch, and no display."""
        env = dict(env)
        for name in ('DISPLAY', 'WAYLAND_DISPLAY', 'XAUTHORITY', 'DBUS_SESSION_BUS_ADDRESS',
                     'SSH_AUTH_SOCK'):
            env.pop(name, None)
        home = os.path.join(self.scratch, 'home')
        env.update(HOME=home, ROS_HOME=os.path.join(home, '.ros'),
                   TMPDIR=os.path.join(self.scratch, 'tmp'))
        for path in (home, env['TMPDIR']):
            os.makedirs(path, exist_ok=True)
        return env


def environment_paths(env):
    """Folders the environment names (venv, devel spaces, package and Python paths) that the
    hidden folders would otherwise hide: this workspace, wherever it is cloned."""
    paths = set()
    for name in ('VIRTUAL_ENV', 'CMAKE_PREFIX_PATH', 'ROS_PACKAGE_PATH', 'PYTHONPATH',
                 'LD_LIBRARY_PATH', 'PKG_CONFIG_PATH', 'PATH'):
        for path in env.get(name, '').split(os.pathsep):
            path = os.path.realpath(path) if path else ''
            # A bin folder's scripts may load code kept beside it (env/bin/catkin_make
            # loads env/catkin_make.py), so the folder above it is shown instead.
            if name == 'PATH' and os.path.basename(path) == 'bin':
                path = os.path.dirname(path)
            if (os.path.isdir(path)
                    and any(path == hidden or path.startswith(hidden + '/') for hidden in HIDDEN)):
                paths.add(path)
    # A folder inside another needs no bind of its own.
    return sorted(p for p in paths if not any(p != q and p.startswith(q + '/') for q in paths))


def cache_stand_ins(package_dir, scratch):
    """Writable copies of a Python package's __pycache__ folders, as Sandbox stand_ins.

    numba loads its compiled kernels from __pycache__ only if it can write
    there; seeing a read-only folder, it compiles them again, which costs the
    simulator seconds at every start. A copy in the scratch folder keeps the
    cache and leaves the original untouched.
    """
    pairs = []
    for root, dirs, _files in os.walk(package_dir):
        if '__pycache__' in dirs:
            original = os.path.join(root, '__pycache__')
            copy = os.path.join(scratch, 'caches', os.path.relpath(original, os.path.dirname(package_dir)))
            shutil.copytree(original, copy, dirs_exist_ok=True)
            pairs.append((copy, original))
        dirs[:] = [d for d in dirs if d != '__pycache__']
    return pairs


def limits():
    """prlimit arguments that bound every process the command starts."""
    return ['prlimit', '--as=%d' % ADDRESS_SPACE_BYTES, '--fsize=%d' % FILE_SIZE_BYTES,
            '--core=0', '--']


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
        try:
            proc = subprocess.run(Sandbox(scratch, own_network=True).command(['true']),
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  timeout=30, check=False)
        except (OSError, subprocess.TimeoutExpired) as error:
            return 'bubblewrap could not run: %s' % error
    if proc.returncode != 0:
        return ('bubblewrap cannot make its namespaces here: %s. Run as root, or where '
                'unprivileged user namespaces are allowed; in a container, see the README '
                '(grading, one submission per container)' % proc.stdout.strip())
    return None
