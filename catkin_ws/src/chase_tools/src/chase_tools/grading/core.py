"""The session's ROS master and rosout (roscore), in a sandbox of their own.

Every node of the submission talks to the master, and every node's log
messages go to rosout: both take what the submission sends, as much as it
sends. So roscore runs like the submission's own code (sandbox.py), but
apart from it:

  - as a uid of its own (CORE_UID_OFFSET above the sandbox's uid of the
    session's process: no account's, and not the submission's), with no
    capabilities and no_new_privs, when the grader runs as root;
  - in cgroups of its own (memory and processes: CORE_MEMORY, CORE_PROCESSES),
    or, where none can be made, under the same per-process fallback limits as
    the submission's sandbox (limits.py);
  - writing only its own folder (the grader's core/, which no sandbox of the
    submission sees), each file at most CORE_FILE_SIZE: SIGXFSZ is ignored
    there, so a write past it fails and rosout lives on;
  - its output (roslaunch's, where XML-RPC log() calls end) through a capped
    log (logcap.py), its Python logs rotated at the log limit
    (logging_config), and at the end, each of its log files copied into the
    report folder the way a capped log is kept: the first and last half of
    the limit (copy_logs).

  - its master bounded in what it takes (master_limit.py): no XML-RPC call
    larger than 16 MiB, no more than 64 MiB of parameters; each refusal is
    named in the report (master_notes).

A master past its memory limit all the same is killed by the kernel: the run
ends then, and the report says so (node.GraderNode.core_trouble).

Pure: builds command lines and copies files, no ROS.
"""
import os
import shlex
import shutil
import stat
import sys

from chase_tools.grading import master_limit
from chase_tools.grading.limits import Cgroups, Limits, size_text
from chase_tools.grading.logcap import LogCap
from chase_tools.grading.sandbox import Confinement, Sandbox, sandbox_uid
from chase_tools.grading.scratch import open_beneath, read_beneath, write_new

# Past the sandboxes' uids (UID_BASE + a pid, plus multiples of 2**22 on a clash).
CORE_UID_OFFSET = 1 << 27
CORE_USER = 'roscore'
# What the master, rosout and roslaunch hold together. The course's graph costs the master a
# few MiB of registrations and parameters (a URDF is the largest); the rest is headroom.
CORE_MEMORY = 512 << 20
# Without a cgroup, address space per process: Python reserves much more than it touches.
CORE_ADDRESS_SPACE = 1 << 30
CORE_PROCESSES = 256
CORE_OPEN_FILES = 4096          # a socket per node connection, for many nodes
CORE_FILE_SIZE = 64 << 20       # any one file roscore writes (rosout.log, its Python logs)
CORE_LOG_FILES = 32             # files of roscore's copied into the report, at most
READ_CHUNK = 1 << 20
# The master roslaunch finds first on roscore's PATH: Debian's, bounded (master_limit.py).
MASTER_SCRIPT = '''#!/bin/sh
exec %(python)s -m chase_tools.grading.master_limit %(record)s %(master)s "$@"
'''
MASTER_RECORD = 'refused_calls.json'
# roslaunch, rosmaster and every Python node read this for their file logs (rosgraph.roslogging):
# rotated at half the log limit, one backup, as Debian's own but for the sizes.
LOGGING_CONFIG = '''[loggers]
keys=root, rosout

[handlers]
keys=fileHandler,streamHandler

[formatters]
keys=defaultFormatter

[logger_root]
level=INFO
handlers=fileHandler

[logger_rosout]
level=INFO
handlers=streamHandler
propagate=1
qualname=rosout

[handler_fileHandler]
class=handlers.RotatingFileHandler
level=DEBUG
formatter=defaultFormatter
args=(os.environ['ROS_LOG_FILENAME'], 'a', %d, 1)

[handler_streamHandler]
class=rosgraph.roslogging.RosStreamHandler
level=DEBUG
formatter=defaultFormatter
args=(True,)

[formatter_defaultFormatter]
format=[%%(name)s][%%(levelname)s] %%(asctime)s: %%(message)s
'''


def logging_config(path, log_limit):
    """Write the Python logging configuration that keeps each node's log file to log_limit."""
    write_new(path, LOGGING_CONFIG % max(1, log_limit // 2), mode=0o644)
    return path


def core_uid(pid=None):
    return sandbox_uid(pid) + CORE_UID_OFFSET


class Core:
    """roscore's sandbox for the session of process pid: folder is the grader's (made here);
    uid, when the grader chose it (session_user.py)."""

    def __init__(self, folder, log_limit, switch_user=None, pid=None, uid=None):
        self.folder = os.path.abspath(folder)
        self.log_limit = log_limit
        os.makedirs(self.folder, mode=0o700)
        root = os.geteuid() == 0 if switch_user is None else switch_user
        self.limits = Limits(memory=CORE_MEMORY, processes=CORE_PROCESSES,
                             open_files=CORE_OPEN_FILES, file_size=CORE_FILE_SIZE,
                             disk=CORE_FILE_SIZE, log=log_limit)
        self.cgroups = (Cgroups.create('grade_core_%d' % (pid or os.getpid()), self.limits)
                        if root else Cgroups(why='the grader does not run as root'))
        if not self.cgroups.active:
            self.limits.memory = CORE_ADDRESS_SPACE
        if uid is None:
            uid = core_uid(pid) if root else os.getuid()
        gid = uid if root else os.getgid()
        self.confinement = Confinement(uid, gid, root, self.limits, self.cgroups)
        self.home = os.path.join(self.folder, 'run')
        config = os.path.join(self.folder, 'config')
        os.mkdir(config, 0o755)
        if root:
            self.confinement.passwd = os.path.join(config, 'passwd')
            self.confinement.group = os.path.join(config, 'group')
            write_new(self.confinement.passwd,
                      'root:x:0:0:root:/root:/usr/sbin/nologin\n'
                      '%s:x:%d:%d:the grade\'s ROS master:/nonexistent:/bin/sh\n' % (CORE_USER, uid, gid),
                      mode=0o644)
            write_new(self.confinement.group, 'root:x:0:\n%s:x:%d:\n' % (CORE_USER, gid), mode=0o644)
        self.logging = logging_config(os.path.join(config, 'python_logging.conf'), log_limit)
        self.sandbox = None

    def command(self, port, env, visible):
        """(command line, environment) of roscore on port, in its sandbox."""
        self.sandbox = Sandbox(self.home, visible=list(visible) + [os.path.dirname(self.logging)],
                               confinement=self.confinement)
        if not os.path.isdir(self.home):
            self.sandbox.prepare()
        env = dict(env, ROS_PYTHON_LOG_CONFIG_FILE=self.logging)
        # roslaunch starts the master as `rosmaster` from PATH: first there, the bounded one.
        master = shutil.which('rosmaster', path=env.get('PATH', os.defpath))
        if master is not None:
            folder = os.path.join(os.path.dirname(self.logging), 'bin')
            os.makedirs(folder, 0o755, exist_ok=True)
            if not os.path.exists(os.path.join(folder, 'rosmaster')):
                write_new(os.path.join(folder, 'rosmaster'), MASTER_SCRIPT % {
                    'python': shlex.quote(sys.executable), 'master': shlex.quote(master),
                    'record': shlex.quote(self.master_record)}, mode=0o755)
            env['PATH'] = folder + os.pathsep + env.get('PATH', os.defpath)
        # A write past the file size limit then fails (EFBIG) instead of killing the writer.
        cmd = ['/bin/sh', '-c', 'trap "" XFSZ; exec "$@"', 'roscore', 'roscore', '-p', str(port)]
        return self.sandbox.wrap(cmd, env)

    @property
    def master_record(self):
        """What the master refused (master_limit.py), written by roscore's uid."""
        return os.path.join(self.home, MASTER_RECORD)

    def master_notes(self):
        """The report's notes on the calls the master refused; none if it refused none."""
        try:
            record = read_beneath(self.home, MASTER_RECORD, master_limit.RECORD_LIMIT)
        except OSError:
            return []
        return master_limit.master_notes(record.decode(errors='replace'))

    @property
    def log_dir(self):
        """Where roscore's ROS_HOME keeps its logs (Sandbox.env)."""
        return os.path.join(self.home, 'home', '.ros', 'log')

    def describe(self):
        who = ('as uid %d, a uid of its own' % self.confinement.uid if self.confinement.switch_user
               else 'as the grader\'s own uid %d' % self.confinement.uid)
        if self.cgroups.active:
            bound = 'a cgroup of its own: %s of memory, %d processes' % (size_text(CORE_MEMORY),
                                                                        CORE_PROCESSES)
        else:
            bound = 'without a cgroup (%s): %s of address space per process' % (
                self.cgroups.why, size_text(CORE_ADDRESS_SPACE))
        return ('%s, %s; each file it writes at most %s, its logs kept to the first and last %s'
                % (who, bound, size_text(CORE_FILE_SIZE), size_text(self.log_limit // 2)))

    def hit(self):
        """What the kernel refused roscore (limits.Usage)."""
        return self.cgroups.usage()

    def end(self):
        """Kill whatever of roscore is left, and remove its cgroups."""
        if self.cgroups.active:
            self.cgroups.kill_all()
        if self.confinement.switch_user:
            from chase_tools.grading.sandbox_processes import kill_processes_of
            kill_processes_of(self.confinement.uid)
        self.cgroups.remove()

    def copy_logs(self, destination):
        """Copy roscore's log files into destination, each kept to the log limit as a capped log
        is; [(report-relative name, LogCap)] of those that were cut. roscore's uid wrote them:
        no link is followed, only regular files are read, at most CORE_LOG_FILES of them."""
        cut, copied = [], 0
        if not os.path.isdir(self.log_dir):
            return cut
        for root, dirs, files in os.walk(self.log_dir):
            dirs.sort()
            for name in sorted(files):
                if copied >= CORE_LOG_FILES:
                    return cut
                relative = os.path.relpath(os.path.join(root, name), self.log_dir)
                cap = _capped_copy(self.log_dir, relative, os.path.join(destination, relative),
                                   self.log_limit)
                if cap is not None:
                    copied += 1
                    if cap.cut:
                        cut.append((relative, cap))
        return cut


def _capped_copy(top, relative, target, keep):
    """Copy top/relative (a regular file, no link followed) to target, kept like a capped log."""
    try:
        # Non-blocking: a fifo in its place must not hold the grader.
        fd = open_beneath(top, relative, os.O_RDONLY | os.O_NONBLOCK)
    except OSError:
        return None
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return None
        cap = LogCap(keep)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        with open(target, 'wb') as out:
            while True:
                data = os.read(fd, READ_CHUNK)
                if not data:
                    break
                out.write(cap.feed(data))
            out.write(cap.rest())
        return cap
    except OSError:
        return None
    finally:
        os.close(fd)
