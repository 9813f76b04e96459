"""The grading session as a user of its own, not root.

The session (session.py) is the part of the grader that the submission
reaches: its node /grade_probe takes the nodes' XML-RPC calls and TCPROS
messages, it serves their calls to the stand-in service, and it reads what
their sandboxes wrote. When the grader runs as root, the session runs as a
uid of its own (SessionUser.uid: no account's, nor the submission's), root
only inside a user namespace that maps nothing but the uids it starts
sandboxes as: the submission's, and each world's roscore's and simulator's.
There it does to those alone what it did as root: start a sandbox as one of
them (bwrap, setpriv), hand it folders (chown) and signal its processes. Any
other file or process of the machine is to it what it is to any user: it
cannot read root's files, write outside the folders made for it, or signal
the grader.

What the grader hands it beforehand (SessionUser.create, hand_cgroups):
  - a folder of its own in the scratch: its grader_dir, and `report`, where it
    writes what goes into the report folder. The grader copies that into the
    report folder once the session has ended: regular files only, no link
    followed, within a bound (copy_report);
  - the numba caches' folder, which it fills and hands to the sandboxes;
  - the cgroup files it writes: its own cgroups, in which it makes roscore's,
    and the cgroup.procs of the submission's, which its sandboxes join;
  - a view of the machine in which the folders it needs (the checkout, the
    venv, its parts of the scratch) are reachable past folders its uid cannot
    enter, such as a home of mode 0700 (reach_args).

It is started as
  bwrap --dev-bind / / [reach_args] --unshare-net --die-with-parent --
      python -m chase_tools.grading.session_user UID MAPPED -- CMD...
Here a process that stays root writes the namespace's map and waits; its
child makes the namespace, becomes the session's uid there (root of the
namespace, with no_new_privs: no setuid program of the machine gives it
more) and runs CMD. A SIGINT to the root process is passed on to the session.
"""
import ctypes
import os
import pwd
import re
import signal
import stat
import subprocess
import sys
from dataclasses import dataclass

from chase_tools.grading.sandbox import sandbox_uid
from chase_tools.grading.scratch import hand_over, open_beneath

# Past the sandboxes' uids and roscore's (core.CORE_UID_OFFSET, 1 << 27, and its worlds').
SESSION_UID_OFFSET = 1 << 28
# Past the largest pid_max: each world's roscore and simulator get a uid of their own.
WORLD_UID_STRIDE = 1 << 22
# What of the session's report folder the grader copies into the real one, at most.
REPORT_FILES = 4096
REPORT_PICTURE = re.compile(r'^(trial_\d+|world)\.png$')
CLONE_NEWUSER = 0x10000000
PR_SET_PDEATHSIG = 1
PR_SET_NO_NEW_PRIVS = 38
# The exit status of a session that could not be made a user of its own.
EXIT_SETUP = 125


def free_uid(uid):
    """uid, or the next one WORLD_UID_STRIDE apart that no account has."""
    while True:
        try:
            pwd.getpwuid(uid)
        except KeyError:
            return uid
        uid += WORLD_UID_STRIDE


@dataclass
class SessionUser:
    """The uids of one grade's session (of grading process pid) and the folder it owns."""
    uid: int
    cores: list                    # roscore's uid in world 1, 2, ...
    simulators: list               # the simulator's uid in world 1, 2, ...
    folder: str = ''

    @classmethod
    def uids_for(cls, worlds, pid=None):
        from chase_tools.grading.core import core_uid
        from chase_tools.grading.simulator import simulator_uid
        base_core, base_simulator = core_uid(pid), simulator_uid(pid)
        return cls(free_uid(sandbox_uid(pid) + SESSION_UID_OFFSET),
                   [free_uid(base_core + n * WORLD_UID_STRIDE) for n in range(worlds)],
                   [free_uid(base_simulator - n * (WORLD_UID_STRIDE << 2)) for n in range(worlds)])

    @classmethod
    def create(cls, top, worlds, pid=None):
        """The session's uids, and its folder `top` (new, with `report` in it), its own."""
        made = cls.uids_for(worlds, pid)
        made.folder = os.path.abspath(top)
        os.mkdir(made.folder, 0o700)
        os.mkdir(made.report, 0o755)
        for path in (made.folder, made.report):
            made.hand(path)
        return made

    @property
    def report(self):
        return os.path.join(self.folder, 'report')

    def hand(self, path):
        """Give path (made by the grader, nothing else has touched it) to the session's uid."""
        os.chown(path, self.uid, self.uid, follow_symlinks=False)

    def uids_json(self):
        return {'session': self.uid, 'core': list(self.cores), 'simulator': list(self.simulators)}

    def mapped(self, submission_uid):
        """The uids the session may act as, besides its own."""
        return sorted({submission_uid, *self.cores, *self.simulators})

    def command(self, cmd, submission_uid, needed):
        """cmd as the session's uid in its user namespace, in a network namespace of its own
        with loopback up, with the folders needed reachable (reach_args) and numba's caches
        writable (cache_args)."""
        from chase_tools.grading.sandbox import SandboxError, bwrap_path
        bwrap = bwrap_path()
        if bwrap is None:
            raise SandboxError('bubblewrap (bwrap) is not installed')
        return ([bwrap, '--dev-bind', '/', '/'] + reach_args(needed, self.uid, self.uid)
                + self.cache_args() + ['--unshare-net', '--die-with-parent', '--',
                   sys.executable, '-m', 'chase_tools.grading.session_user', str(self.uid),
                   ','.join(str(uid) for uid in self.mapped(submission_uid)), '--'] + list(cmd))

    def cache_args(self):
        """Writable copies of flatsim's __pycache__ folders shown in their place: numba loads
        the compiled kernels that the session's placement uses only from a folder it may write
        (sandbox.cache_stand_ins)."""
        from chase_tools.grading.sandbox import flatsim_cache_stand_ins
        caches = os.path.join(self.folder, 'caches')
        os.mkdir(caches, 0o700)
        pairs = flatsim_cache_stand_ins(caches)
        hand_over(caches, self.uid, self.uid)
        return [arg for copy, original in pairs for arg in ('--bind', copy, original)]

    def refused(self):
        """None if this machine lets the session become its uid here, else why not (a kernel or
        a container that makes no user namespaces): the session then runs as root, as the
        grader does, and the grade says so."""
        try:
            done = subprocess.run([sys.executable, '-m', 'chase_tools.grading.session_user',
                                   str(self.uid), '', '--', 'true'], stdin=subprocess.DEVNULL,
                                  stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                  timeout=30, check=False)
        except (OSError, subprocess.TimeoutExpired) as error:
            return str(error)
        return None if done.returncode == 0 else (done.stdout.strip().splitlines() or ['?'])[-1]

    def end(self):
        """Kill whatever still runs as the session's uid; the names of what did."""
        from chase_tools.grading.sandbox_processes import kill_processes_of
        return kill_processes_of(self.uid)

    def copy_report(self, out_dir, limit):
        """Copy what the session wrote for the report folder into out_dir: regular files only,
        no link followed, none already there replaced, at most `limit` bytes and REPORT_FILES
        files in all; the notes on what was left out."""
        return copy_tree_beneath(self.report, out_dir, limit, REPORT_FILES, report_name)


def report_name(name, is_folder):
    """Whether the session writes name at the top of the report folder: its logs and the
    pictures, never the grader's report.md or grade.json."""
    return name == 'logs' if is_folder else REPORT_PICTURE.match(name) is not None


def copy_tree_beneath(top, destination, limit, most_files, wanted=lambda _name, _is_folder: True):
    """Copy the regular files under top (a folder another uid writes) to destination, as
    data: no link followed, no fifo or device opened, nothing replaced in destination, at most
    limit bytes and most_files files in all, at its top only what wanted(name, is_folder)
    allows. Notes on what was left out."""
    left, files = limit, 0
    skipped = {'links or special files': 0, 'files past the bound': 0, 'files already there': 0,
               'names the session does not write': 0}
    stack = ['']
    while stack:
        relative = stack.pop()
        try:
            fd = open_beneath(top, relative or '.', os.O_RDONLY | os.O_DIRECTORY)
        except OSError:
            skipped['links or special files'] += 1
            continue
        try:
            names = sorted(os.listdir(fd))
            kinds = {}
            for name in names:
                try:
                    kinds[name] = os.stat(name, dir_fd=fd, follow_symlinks=False).st_mode
                except OSError:
                    continue
        finally:
            os.close(fd)
        try:
            os.makedirs(os.path.join(destination, relative), mode=0o755, exist_ok=True)
        except OSError:
            # A file of the grader's is there already.
            skipped['files already there'] += 1
            continue
        for name in names:
            mode, path = kinds.get(name), os.path.join(relative, name)
            if not relative and not wanted(name, mode is not None and stat.S_ISDIR(mode)):
                skipped['names the session does not write'] += 1
                continue
            if mode is not None and stat.S_ISDIR(mode):
                stack.append(path)
                continue
            if mode is None or not stat.S_ISREG(mode):
                skipped['links or special files'] += 1
                continue
            if files >= most_files:
                skipped['files past the bound'] += 1
                continue
            copied = _copy_file_beneath(top, path, os.path.join(destination, path), left)
            if copied in (LINK, EXISTS, TOO_LARGE):
                skipped[{LINK: 'links or special files', EXISTS: 'files already there',
                         TOO_LARGE: 'files past the bound'}[copied]] += 1
                continue
            files += 1
            left -= copied
    return ['%s: %d' % (what, count) for what, count in skipped.items() if count]


LINK, EXISTS, TOO_LARGE = -1, -2, -3


def _copy_file_beneath(top, relative, target, most):
    """Bytes copied, or LINK (not a regular file), EXISTS (target is there) or TOO_LARGE (more
    than `most` bytes: nothing is copied, never a part)."""
    try:
        source = open_beneath(top, relative)
    except OSError:
        return LINK
    try:
        info = os.fstat(source)
        if not stat.S_ISREG(info.st_mode):
            return LINK
        if info.st_size > most:
            return TOO_LARGE
        try:
            out = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644)
        except OSError:
            return EXISTS
        copied = 0
        with os.fdopen(out, 'wb') as stream:
            while copied < info.st_size:
                data = os.read(source, min(info.st_size - copied, 1 << 20))
                if not data:
                    break
                stream.write(data)
                copied += len(data)
        return copied
    finally:
        os.close(source)


def searchable(path, uid, gid):
    """Whether a process of uid and gid (no other group, no capability) may enter folder path."""
    try:
        info = os.stat(path)
    except OSError:
        return True                 # nothing there to reach past
    if info.st_uid == uid:
        return bool(info.st_mode & stat.S_IXUSR)
    if info.st_gid == gid:
        return bool(info.st_mode & stat.S_IXGRP)
    return bool(info.st_mode & stat.S_IXOTH)


def _parts(path):
    return tuple(part for part in path.split('/') if part)


def reach_args(needed, uid, gid):
    """bwrap arguments that make each of the needed paths reachable by uid: each folder on the
    way that uid cannot enter is replaced by an empty tmpfs (mode 0755), and what is needed
    under it is bound back in place. What uid may read in those paths themselves is still
    up to their own modes."""
    paths = sorted({os.path.normpath(os.path.abspath(path)) for path in needed},
                   key=_parts)
    blocked = set()
    for path in paths:
        parts = _parts(path)
        for depth in range(1, len(parts)):
            folder = '/' + '/'.join(parts[:depth])
            if not searchable(folder, uid, gid):
                blocked.add(folder)
    candidates = sorted([(_parts(folder), 0, folder) for folder in blocked]
                        + [(_parts(path), 1, path) for path in paths])
    mounts, args, made = [], [], set()
    for parts, kind, path in candidates:
        covering = [(len(m_parts), m_kind) for m_parts, m_kind in mounts
                    if parts[:len(m_parts)] == m_parts and len(m_parts) < len(parts)]
        hidden = bool(covering) and max(covering)[1] == 0
        if kind == 0 and not hidden:
            args += ['--perms', '0755', '--tmpfs', path]
            mounts.append((parts, 0))
        elif kind == 1 and hidden and os.path.exists(path):
            # bwrap would make the folders on the way in the tmpfs 0700, root's.
            for depth in range(max(covering)[0] + 1, len(parts)):
                folder = '/' + '/'.join(parts[:depth])
                if folder not in made:
                    args += ['--perms', '0755', '--dir', folder]
                    made.add(folder)
            args += ['--bind', path, path]
            mounts.append((parts, 1))
    return args


def id_map(own, mapped):
    """The text of a uid_map or gid_map: root of the namespace is `own`; each of mapped is
    itself."""
    return ''.join(['0 %d 1\n' % own] + ['%d %d 1\n' % (uid, uid) for uid in sorted(set(mapped))
                                          if uid != own])


def _become_session(libc, own_parent, ready, go):
    """In the child: make the user namespace, wait for its map, become its root."""
    if libc.unshare(CLONE_NEWUSER) != 0:
        raise OSError(ctypes.get_errno(), 'cannot make a user namespace')
    os.write(ready, b'1')
    os.close(ready)
    if os.read(go, 1) != b'1':
        raise OSError('the user namespace was given no map')
    os.close(go)
    os.setgroups([])
    os.setresgid(0, 0, 0)
    os.setresuid(0, 0, 0)
    # Changing uid cleared the parent-death signal: set it now, and check the parent is there.
    libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0)
    if os.getppid() != own_parent:
        raise OSError('the grader\'s process ended')
    if libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), 'cannot set no_new_privs')


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    try:
        if len(argv) < 4 or argv[2] != '--':
            raise ValueError('no command')
        own = int(argv[0])
        mapped = [int(uid) for uid in argv[1].split(',') if uid]
    except ValueError:
        print('usage: python -m chase_tools.grading.session_user UID MAPPED,... -- CMD...',
              file=sys.stderr)
        return 2
    cmd = argv[3:]
    libc = ctypes.CDLL(None, use_errno=True)
    ready_read, ready_write = os.pipe()
    go_read, go_write = os.pipe()
    parent = os.getpid()
    child = os.fork()
    if child == 0:
        try:
            os.close(ready_read)
            os.close(go_write)
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            _become_session(libc, parent, ready_write, go_read)
            os.execvp(cmd[0], cmd)
        except BaseException as error:  # noqa: BLE001 - the child must never return into main
            print('the grading session could not start as uid %d: %s' % (own, error),
                  file=sys.stderr, flush=True)
        os._exit(EXIT_SETUP)
    os.close(ready_write)
    os.close(go_read)

    def pass_on(signum, _frame):
        try:
            os.kill(child, signum)
        except ProcessLookupError:
            pass
    for signum in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(signum, pass_on)
    if os.read(ready_read, 1) == b'1':
        try:
            for name in ('uid_map', 'gid_map'):
                with open('/proc/%d/%s' % (child, name), 'w') as stream:
                    stream.write(id_map(own, mapped))
            os.write(go_write, b'1')
        except OSError as error:
            print('the grading session\'s user namespace could not be mapped: %s' % error,
                  file=sys.stderr, flush=True)
    os.close(go_write)
    _pid, status = os.waitpid(child, 0)
    if os.WIFSIGNALED(status):
        signal.signal(os.WTERMSIG(status), signal.SIG_DFL)
        os.kill(os.getpid(), os.WTERMSIG(status))
    return os.waitstatus_to_exitcode(status)


if __name__ == '__main__':
    sys.exit(main())
