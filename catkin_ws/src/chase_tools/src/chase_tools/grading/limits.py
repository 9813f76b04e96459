"""What one submission may use, and the cgroups that hold it to that.

Memory and processes are bounded for the submission as a whole: every
sandboxed command of it (build steps, launches) joins one cgroup in the
memory and the pids hierarchies (cgroup v1), made inside the grader's own
cgroups, so a cluster job's or a container's limits still hold above it. It
is made in a group of the grader's (create_group), beside the session's: the
session, a uid of its own, moves its sandboxes into it (hand_to). The
kernel counts what it refused there (oom_kill, pids.events), which is how the
report can say that a limit was hit.

Where the machine has no cgroup v1 memory hierarchy (Debian 12 boots with the
unified hierarchy only), the same cgroup is made in cgroup v2, beside the
grader's own: memory.max, memory.swap.max and pids.max, counted in
memory.events and pids.events. cgroup v2 lets a cgroup hand controllers to
its children only while it holds no process itself, so the grader first moves
itself into a leaf of its own; that works where the grader's cgroup holds
nothing else, as a scope started for it does (systemd-run --scope -p
Delegate=yes grade ...), and otherwise the fallback below holds and the
report says why.

Where no cgroup can be made (not root, or no writable hierarchy), memory
falls back to a limit per process (address space: address_space()), and
processes to RLIMIT_NPROC, which counts every process of one uid: per
submission, since each gets a uid of its own when the grader runs as root.
Address space is not memory: a process reserves far more than it uses
(a stack for each thread, glibc's malloc arenas of 64 MiB per thread, the
numba compiler's), so the limit is the memory limit and AS_RESERVE more,
or the simulator itself, which runs in the submission's sandbox, could not
start its threads under a memory limit of 1 GiB.

Open files, file size and core dumps are bounded per process (rlimits), the
space it writes by a filesystem of its own (disk.py).

Pure but for the cgroup files under /sys/fs/cgroup; no ROS.
"""
import errno
import math
import os
import re
import signal
import time
from dataclasses import asdict, dataclass, field

CGROUP_ROOT = '/sys/fs/cgroup'
SIZE = re.compile(r'^\s*(\d+(?:\.\d+)?)\s*([KMGT]?)i?B?\s*$', re.IGNORECASE)
UNITS = {'': 1, 'K': 1 << 10, 'M': 1 << 20, 'G': 1 << 30, 'T': 1 << 40}
# The largest limits the kernel takes: a resource limit or a cgroup's byte count is a signed
# 64-bit number, and pids.max stops at PID_MAX_LIMIT.
MAX_LIMIT = (1 << 63) - 1
MAX_PROCESSES = 1 << 22
NR_OPEN = '/proc/sys/fs/nr_open'


def max_open_files():
    """The most open files one process may be allowed (fs.nr_open; Linux's default elsewhere)."""
    try:
        with open(NR_OPEN) as limit:
            return int(limit.read())
    except (OSError, ValueError):
        return 1 << 20


def parse_size(text):
    """Bytes in '4G', '512M', '1.5GiB', '65536'; ValueError otherwise."""
    match = SIZE.match(str(text))
    if not match:
        raise ValueError('%r is not a size (say 4G, 512M or a number of bytes)' % text)
    value = float(match.group(1)) * UNITS[match.group(2).upper()]
    if not math.isfinite(value) or value < 1:
        raise ValueError('%r is not a size of at least one byte' % text)
    return int(value)


def size_text(count):
    """1073741824 -> '1 GiB', 1536 -> '1.5 KiB'."""
    for unit, factor in (('GiB', 1 << 30), ('MiB', 1 << 20), ('KiB', 1 << 10)):
        if count >= factor:
            return ('%.1f %s' % (count / factor, unit)).replace('.0 ', ' ')
    return '%d bytes' % count


@dataclass
class Limits:
    memory: int = 4 << 30          # bytes, the submission's processes together
    processes: int = 1024          # tasks (threads count), the submission's processes together
    open_files: int = 1024         # per process
    file_size: int = 1 << 30       # bytes, per file
    disk: int = 2 << 30            # bytes, what the submission writes together (see disk.py)
    log: int = 2 << 20             # bytes kept of each log: the first half and the last half

    def as_json(self):
        return asdict(self)

    @classmethod
    def from_json(cls, data):
        return cls(**data)


@dataclass
class Usage:
    """What the kernel refused the submission so far."""
    oom_kills: int = 0             # processes killed at the memory limit
    refused_forks: int = 0         # forks and threads refused at the process limit
    disk_full: str = ''            # what fills the submission's filesystem, when it is full

    def since(self, before):
        return Usage(self.oom_kills - before.oom_kills, self.refused_forks - before.refused_forks,
                     self.disk_full if not before.disk_full else '')


# Cgroups.folders' key of a cgroup v2 folder, which holds every controller.
UNIFIED = 'unified'


def unified_mount(mountinfo='/proc/self/mountinfo'):
    """Where the cgroup v2 hierarchy is mounted, or None."""
    try:
        with open(mountinfo) as stream:
            for line in stream:
                fields = line.split()
                after = fields.index('-')
                if fields[after + 1] == 'cgroup2':
                    return fields[4]
    except (OSError, ValueError, IndexError):
        pass
    return None


def own_unified_cgroup(proc_cgroup='/proc/self/cgroup'):
    """This process's cgroup v2 path ('/' at the top), or None."""
    try:
        with open(proc_cgroup) as stream:
            for line in stream:
                if line.startswith('0::'):
                    return line.rstrip('\n')[3:]
    except OSError:
        pass
    return None


def own_cgroup(controller, proc_cgroup='/proc/self/cgroup'):
    """This process's cgroup path in a v1 hierarchy ('/' at the top), or None."""
    try:
        with open(proc_cgroup) as stream:
            for line in stream:
                _id, controllers, path = line.rstrip('\n').split(':', 2)
                if controller in controllers.split(','):
                    return path
    except (OSError, ValueError):
        pass
    return None


@dataclass
class Cgroups:
    """One submission's cgroups: {controller: folder}. Empty when none could be made (see why)."""
    folders: dict = field(default_factory=dict)
    why: str = ''

    @classmethod
    def create(cls, name, limits, root=CGROUP_ROOT, within=None):
        """Make `name` in the memory and pids hierarchies below this process's own cgroups
        (cgroup v1), else beside this process in cgroup v2 (create_unified); inside the
        cgroups `within` (a group: create_group) when given. limits None: no limit of its own."""
        if within is not None:
            return cls.create_inside(within, name, limits)
        if own_cgroup('memory') is None or not os.path.isdir(os.path.join(root, 'memory')):
            return cls.create_unified(name, limits)
        made = cls()
        for controller in ('memory', 'pids'):
            parent = own_cgroup(controller)
            if parent is None or not os.path.isdir(os.path.join(root, controller)):
                made.remove()
                return cls(why='no cgroup v1 %s hierarchy here' % controller)
            folder = os.path.join(root, controller, parent.lstrip('/'), name)
            try:
                os.mkdir(folder, 0o755)
            except OSError as error:
                made.remove()
                return cls(why='cannot make a cgroup in %s (%s)' % (os.path.dirname(folder),
                                                                   os.strerror(error.errno)))
            made.folders[controller] = folder
        return made.limited(limits)

    @classmethod
    def create_group(cls, name):
        """Cgroups without limits of their own, to make others in (create(within=)): cgroups
        that a uid other than root may move processes between (hand_to) are made in one."""
        made = cls.create(name, None)
        if UNIFIED in made.folders:
            try:
                _write(os.path.join(made.folders[UNIFIED], 'cgroup.subtree_control'), '+memory +pids')
            except OSError as error:
                made.remove()
                return cls(why='cannot hand memory and pids to the cgroups in %s (%s)'
                           % (made.folders[UNIFIED], os.strerror(error.errno)))
        return made

    @classmethod
    def create_inside(cls, group, name, limits):
        if not group.active:
            return cls(why=group.why)
        made = cls()
        for controller, parent in group.folders.items():
            folder = os.path.join(parent, name)
            try:
                os.mkdir(folder, 0o755)
            except OSError as error:
                made.remove()
                return cls(why='cannot make a cgroup in %s (%s)' % (parent, os.strerror(error.errno)))
            made.folders[controller] = folder
        return made.limited(limits)

    def limited(self, limits):
        """These cgroups with limits written (None: none); inactive, and why, if they cannot be."""
        if limits is None:
            return self
        try:
            if UNIFIED in self.folders:
                folder = self.folders[UNIFIED]
                _write(os.path.join(folder, 'memory.max'), limits.memory)
                if os.path.exists(os.path.join(folder, 'memory.swap.max')):
                    # Swap would let the submission go past the limit, only slower.
                    _write(os.path.join(folder, 'memory.swap.max'), 0)
                _write(os.path.join(folder, 'pids.max'), limits.processes)
            else:
                memory = self.folders['memory']
                _write(os.path.join(memory, 'memory.limit_in_bytes'), limits.memory)
                if os.path.exists(os.path.join(memory, 'memory.memsw.limit_in_bytes')):
                    # Swap would let the submission go past the limit, only slower.
                    _write(os.path.join(memory, 'memory.memsw.limit_in_bytes'), limits.memory)
                _write(os.path.join(self.folders['pids'], 'pids.max'), limits.processes)
        except OSError as error:
            self.remove()
            return type(self)(why='cannot set the cgroup limits (%s)' % os.strerror(error.errno))
        return self

    def hand_ancestor_to(self, uid, gid):
        """Let uid move processes between the cgroups made in this group (create(within=)).
        cgroup v2 asks for write access to the cgroup.procs of the common ancestor; the group
        holds no process itself there (its controllers are its children's). cgroup v1 asks
        for none, and there it would let uid move processes into the group, which has no limit."""
        if UNIFIED in self.folders:
            os.chown(os.path.join(self.folders[UNIFIED], 'cgroup.procs'), uid, gid,
                     follow_symlinks=False)

    def hand_to(self, uid, gid, own=False):
        """Let uid move its processes into these cgroups (their cgroup.procs); own: also make
        cgroups inside them and hand them controllers (the folders themselves), as roscore's
        are made inside the session's. Limits stay root's."""
        names = ('cgroup.procs', 'tasks') + (('cgroup.subtree_control',) if own else ())
        for folder in self.folders.values():
            if own:
                os.chown(folder, uid, gid, follow_symlinks=False)
            for name in names:
                path = os.path.join(folder, name)
                if os.path.exists(path):
                    os.chown(path, uid, gid, follow_symlinks=False)

    @classmethod
    def create_unified(cls, name, limits, mount=None, proc_cgroup='/proc/self/cgroup'):
        """Make `name` in cgroup v2, beside this process: in the cgroup it is in, which hands
        memory and pids to its children once this process has moved into a leaf of its own."""
        mount = mount or unified_mount()
        own = own_unified_cgroup(proc_cgroup)
        if mount is None or own is None:
            return cls(why='no cgroup v1 memory hierarchy, and no cgroup v2 one here')
        parent = os.path.join(mount, own.lstrip('/'))
        wanted = ('memory', 'pids')
        offered = _words(os.path.join(parent, 'cgroup.controllers'))
        missing = [controller for controller in wanted if controller not in offered]
        if missing:
            return cls(why='cgroup v2 does not give the grader\'s cgroup %s the %s controller%s '
                           '(delegate %s, as systemd-run --scope -p Delegate=yes does)'
                       % (own, ' and '.join(missing), '' if len(missing) == 1 else 's',
                          'it' if len(missing) == 1 else 'them'))
        control = os.path.join(parent, 'cgroup.subtree_control')
        if not all(controller in _words(control) for controller in wanted):
            try:
                _write(control, ' '.join('+' + controller for controller in wanted))
            except OSError as error:
                if error.errno != errno.EBUSY:
                    return cls(why='cannot hand memory and pids to the cgroups in %s (%s)'
                               % (parent, os.strerror(error.errno)))
                # A cgroup that holds processes hands no controller down: this one leaves first.
                try:
                    leaf = os.path.join(parent, 'grader_%d' % os.getpid())
                    os.makedirs(leaf, 0o755, exist_ok=True)
                    _write(os.path.join(leaf, 'cgroup.procs'), os.getpid())
                    _write(control, ' '.join('+' + controller for controller in wanted))
                except OSError as error:
                    return cls(why='cgroup v2: the grader\'s cgroup %s holds other processes, so it '
                                   'hands no controller down (%s); start the grader in a scope of '
                                   'its own: systemd-run --scope -p Delegate=yes grade ...'
                               % (own, os.strerror(error.errno)))
        folder = os.path.join(parent, name)
        try:
            os.mkdir(folder, 0o755)
        except OSError as error:
            return cls(why='cannot make a cgroup in %s (%s)' % (parent, os.strerror(error.errno)))
        return cls({UNIFIED: folder}).limited(limits)

    @property
    def active(self):
        return bool(self.folders)

    def procs_files(self):
        """The cgroup.procs files a command writes its pid to, to join."""
        return [os.path.join(folder, 'cgroup.procs') for folder in self.folders.values()]

    def tree(self):
        """Every folder of these cgroups and of the cgroups made inside them (a session's holds
        roscore's, and in cgroup v2 the leaf it moved into), deepest first."""
        found = []
        for folder in self.folders.values():
            for root, _dirs, _files in os.walk(folder, topdown=False):
                found.append(root)
        return found

    def usage(self):
        usage = Usage()
        if not self.active:
            return usage
        if UNIFIED in self.folders:
            folder = self.folders[UNIFIED]
            usage.oom_kills = _field(os.path.join(folder, 'memory.events'), 'oom_kill')
            usage.refused_forks = _field(os.path.join(folder, 'pids.events'), 'max')
            return usage
        usage.oom_kills = _field(os.path.join(self.folders['memory'], 'memory.oom_control'), 'oom_kill')
        usage.refused_forks = _field(os.path.join(self.folders['pids'], 'pids.events'), 'max')
        return usage

    def pids(self):
        found = set()
        for path in [os.path.join(folder, 'cgroup.procs') for folder in self.tree()]:
            try:
                with open(path) as stream:
                    found |= {int(line) for line in stream if line.strip()}
            except OSError:
                continue
        return found

    def kill_all(self, wall_timeout=10.0):
        """SIGKILL every process in the cgroups until none is left; True when none is."""
        deadline = time.monotonic() + wall_timeout
        while time.monotonic() < deadline:
            pids = self.pids()
            if not pids:
                return True
            for pid in pids:
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            time.sleep(0.05)
        return not self.pids()

    def remove(self):
        for folder in self.tree():
            for _attempt in range(50):
                try:
                    os.rmdir(folder)
                    break
                except FileNotFoundError:
                    break
                except OSError as error:
                    if error.errno != errno.EBUSY:
                        break
                    # The last killed processes are still being reaped.
                    time.sleep(0.1)
        self.folders.clear()

    def as_json(self):
        return {'folders': dict(self.folders), 'why': self.why}

    @classmethod
    def from_json(cls, data):
        return cls(dict(data.get('folders', {})), data.get('why', ''))


# Address space a process of the sandbox may reserve beyond the memory limit without a cgroup:
# the simulator reserves about 1 GiB before it has loaded a robot (its threads, each with a
# stack and a malloc arena, numba's compiler, numpy's BLAS), of which it uses about 200 MiB;
# under 768 MiB of address space it never serves its services.
AS_RESERVE = 2 << 30


def address_space(limits):
    """RLIMIT_AS of each of the submission's processes where no cgroup bounds its memory."""
    return min(MAX_LIMIT, limits.memory + AS_RESERVE)


# The most a sandbox's /dev/shm holds: POSIX shared memory and semaphores (Python's
# multiprocessing) take a few KiB; a tmpfs left unsized takes half the machine's memory.
SHM_MAX = 64 << 20


def shm_size(limits):
    """Bytes of each sandbox's /dev/shm: SHM_MAX, or an eighth of the memory limit if less."""
    return max(1 << 20, min(SHM_MAX, limits.memory // 8))


def join_command(procs_files):
    """A prefix that moves the command into the cgroups before it starts: what it forks stays there."""
    if not procs_files:
        return []
    script = 'for f in "$@"; do [ "$f" = -- ] && break; echo $$ > "$f" || exit 125; done; ' \
             'while [ "$1" != -- ]; do shift; done; shift; exec "$@"'
    return ['/bin/sh', '-c', script, 'join-cgroup'] + list(procs_files) + ['--']


def rlimit_command(limits, cgroups_active, per_uid, prlimit='/usr/bin/prlimit'):
    """prlimit arguments for the limits a cgroup does not hold.

    per_uid: the sandbox has a uid of its own, so RLIMIT_NPROC bounds the
    submission's processes without touching anyone else's.
    """
    args = [prlimit, '--nofile=%d' % limits.open_files, '--fsize=%d' % limits.file_size,
            '--core=0']
    if not cgroups_active:
        args.append('--as=%d' % address_space(limits))
    if per_uid:
        args.append('--nproc=%d' % limits.processes)
    return args + ['--']


def describe(limits, cgroups, per_uid):
    """The limits in words, for the report's isolation line."""
    if cgroups.active:
        whole = 'for the submission as a whole (cgroup): %s of memory and %d processes' % (
            size_text(limits.memory), limits.processes)
    else:
        whole = ('without a cgroup (%s): %s of address space per process (the memory limit of %s '
                 'and %s that processes reserve but do not use), and %s' % (
            cgroups.why, size_text(address_space(limits)), size_text(limits.memory),
            size_text(AS_RESERVE),
            '%d processes for its uid' % limits.processes if per_uid else 'processes not bounded'))
    return ('%s; per process: %d open files, %s per file, no core dumps; the first and last %s of '
            'each log kept' % (whole, limits.open_files, size_text(limits.file_size),
                               size_text(limits.log // 2)))


def hit_text(usage, limits, where):
    """'the build hit the memory limit of 4 GiB (the kernel killed 1 process)', or ''."""
    parts = []
    if usage.oom_kills:
        parts.append('the memory limit of %s (the kernel killed %d process%s)' % (
            size_text(limits.memory), usage.oom_kills, '' if usage.oom_kills == 1 else 'es'))
    if usage.refused_forks:
        parts.append('the process limit of %d (%d fork%s refused)' % (
            limits.processes, usage.refused_forks, '' if usage.refused_forks == 1 else 's'))
    if usage.disk_full:
        parts.append('the disk limit of %s (its folders are full: %s)' % (
            size_text(limits.disk), usage.disk_full))
    return '%s hit %s' % (where, ' and '.join(parts)) if parts else ''


def _write(path, value):
    with open(path, 'w') as stream:
        stream.write(str(value))


def _words(path):
    try:
        with open(path) as stream:
            return stream.read().split()
    except OSError:
        return []


def _field(path, name):
    try:
        with open(path) as stream:
            for line in stream:
                key, _sep, value = line.strip().partition(' ')
                if key == name:
                    return int(value)
    except (OSError, ValueError):
        pass
    return 0
