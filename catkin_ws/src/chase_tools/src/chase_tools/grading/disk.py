"""A filesystem of its own for what one submission writes, of --disk-limit bytes.

Each file a submission writes is bounded (limits.Limits.file_size), but not
their number: a build or a node could fill the disk that holds the scratch
folder. So its writable folders (build/, run/ and caches/, with their HOME
and TMPDIR) lie on a filesystem of the limit's size, and a write past it
fails with ENOSPC (No space left on device), as does a file past its inode
count. The first of these that can be made is taken:

  ext4 image  a sparse file of the limit's size in the scratch folder, with
              an ext4 filesystem loop-mounted: it takes on the disk only what
              is written to it, never more than the limit (root, loop devices);
  tmpfs       a tmpfs of the limit's size: memory, not disk, charged to the
              submission's memory limit for what it writes (root and the right
              to mount, as in a container given CAP_SYS_ADMIN but no loop
              devices);
  none        the folders stay on the scratch folder's disk, not bounded (the
              grader is not root, or may not mount); the report's isolation
              line says why.

The mount is made in a mount namespace of the grading process's own (made
once, before anything of the submission runs), which the sandboxes and the
session inherit: nothing shows in the machine's mount table, and a grader
that is killed leaves no mount behind (the namespace, the mount and its loop
device go with its last process).

Pure but for the mount system calls and commands; no ROS.
"""
import ctypes
import ctypes.util
import os
import subprocess
from dataclasses import asdict, dataclass

from chase_tools.grading.limits import size_text

# sched.h and sys/mount.h: os.unshare and os.mount arrive only with Python 3.12.
CLONE_NEWNS = 0x00020000
MS_REC = 0x4000
MS_SLAVE = 1 << 19
IMAGE_NAME = 'disk.img'
# ext4's default for a small filesystem: one inode per 16 KiB. A tmpfs gets as many.
BYTES_PER_INODE = 16 << 10
# What is left when the filesystem counts as full, that is when a write of the submission's
# has failed: less than the last write that failed (a MiB, say) and ext4's own reserve (2%).
FULL_SPACE_SHARE = 0.02
FULL_SPACE_BYTES = 2 << 20
FULL_INODE_SHARE = 0.01
COMMAND_TIMEOUT_S = 60
_namespace = {}        # 'made': True, or 'why': why not; once per process


@dataclass
class Disk:
    """Where the submission's folders lie: folder, a filesystem of `limit` bytes of `kind`,
    or a plain folder (kind '') with `why` it is not bounded."""
    folder: str
    limit: int
    kind: str = ''
    why: str = ''

    @classmethod
    def create(cls, folder, limit):
        """Make folder (it must not exist) and mount a filesystem of limit bytes on it if this
        process may."""
        os.mkdir(folder, 0o755)
        disk = cls(folder, limit)
        if os.geteuid() != 0:
            disk.why = 'the grader is not root'
            return disk
        why = private_mount_namespace()
        if why:
            disk.why = why
            return disk
        tried = []
        for kind, mount in (('ext4 image', disk._mount_image), ('tmpfs', disk._mount_tmpfs)):
            problem = mount()
            if not problem:
                disk.kind = kind
                os.chmod(folder, 0o755)
                return disk
            tried.append('%s: %s' % (kind, problem))
        disk.why = 'no filesystem could be mounted (%s)' % '; '.join(tried)
        return disk

    @property
    def bounded(self):
        return bool(self.kind)

    @property
    def image(self):
        return os.path.join(os.path.dirname(self.folder), IMAGE_NAME)

    def _mount_image(self):
        try:
            with open(self.image, 'xb') as stream:
                stream.truncate(self.limit)
        except OSError as error:
            return 'cannot make %s (%s)' % (self.image, os.strerror(error.errno))
        # No journal and no reserved blocks: a throwaway filesystem, all of it the submission's.
        problem = _run(['mkfs.ext4', '-q', '-F', '-m', '0', '-O', '^has_journal',
                        '-E', 'nodiscard,lazy_itable_init=1', self.image])
        problem = problem or _run(['mount', '-t', 'ext4', '-o', 'loop,nosuid,nodev,noatime',
                                   self.image, self.folder])
        if problem:
            os.remove(self.image)
        return problem

    def _mount_tmpfs(self):
        return _run(['mount', '-t', 'tmpfs', '-o', 'size=%d,nr_inodes=%d,mode=0755,nosuid,nodev'
                     % (self.limit, max(1024, self.limit // BYTES_PER_INODE)),
                     'grade-disk', self.folder])

    def full(self):
        """True when what is left of the space or the inodes is too little to write on."""
        if not self.bounded:
            return False
        try:
            info = os.statvfs(self.folder)
        except OSError:
            return False
        space = max(FULL_SPACE_SHARE * info.f_blocks * info.f_frsize, FULL_SPACE_BYTES)
        return (info.f_bavail * info.f_frsize <= space
                or info.f_favail <= FULL_INODE_SHARE * info.f_files)

    def used_text(self):
        """'63 MiB in 1204 files'."""
        info = os.statvfs(self.folder)
        return '%s in %d files' % (size_text((info.f_blocks - info.f_bfree) * info.f_frsize),
                                   info.f_files - info.f_ffree)

    def unmount(self):
        """Unmount it (the submission's processes have ended); the image file stays."""
        if self.bounded:
            # Lazily: a process of the submission that is still being reaped holds it no longer.
            _run(['umount', '--lazy', self.folder])
            self.kind = ''
            self.why = 'unmounted'

    def remove_image(self):
        try:
            os.remove(self.image)
        except FileNotFoundError:
            pass

    def describe(self):
        """The disk limit in words, for the report's isolation line."""
        if self.kind == 'ext4 image':
            return ('%s of disk for its folders together (a filesystem of their own, an ext4 '
                    'image in the scratch folder)' % size_text(self.limit))
        if self.kind == 'tmpfs':
            return ('%s for its folders together (a tmpfs of their own, in memory)'
                    % size_text(self.limit))
        return 'disk space not bounded (%s)' % self.why

    def as_json(self):
        return asdict(self)

    @classmethod
    def from_json(cls, data):
        return cls(**data)


def private_mount_namespace():
    """Move this process into a mount namespace of its own whose mounts do not reach the
    machine's; '' once it is there, else why not. Called before any thread of the grader's
    starts: the namespace is the calling thread's, and what it starts from then on."""
    if 'made' not in _namespace:
        _namespace['why'] = _unshare_mounts()
        _namespace['made'] = not _namespace['why']
    return _namespace['why']


def _unshare_mounts():
    libc = ctypes.CDLL(ctypes.util.find_library('c'), use_errno=True)
    if libc.unshare(CLONE_NEWNS) != 0:
        return 'cannot make a mount namespace (%s)' % os.strerror(ctypes.get_errno())
    # Mounts made here stay here, and the machine's still show here.
    if libc.mount(None, b'/', None, MS_REC | MS_SLAVE, None) != 0:
        return 'cannot make the mounts private (%s)' % os.strerror(ctypes.get_errno())
    return ''


def _run(cmd):
    """'' when cmd succeeded, else what it said."""
    try:
        proc = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, timeout=COMMAND_TIMEOUT_S,
                              check=False)
    except (OSError, subprocess.TimeoutExpired) as error:
        return '%s: %s' % (cmd[0], getattr(error, 'strerror', None) or error)
    if proc.returncode != 0:
        return '%s: %s' % (cmd[0], ' '.join(proc.stdout.split()) or 'exit %d' % proc.returncode)
    return ''

