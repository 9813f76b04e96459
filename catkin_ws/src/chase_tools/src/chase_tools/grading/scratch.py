"""One submission's scratch folder, and how the grader touches what a submission wrote.

Every folder is made before anything of the submission runs, so that no
path the grader writes to, reads from or binds into a sandbox can have been
planted by the submission:

    TOP/          the grader's (mode 0700); no sandbox sees it
      grader/     the grader's own files: session.json, result.json, passwd and group for the
                  sandbox, prepared launch files (bound read-only, file by file)
      disk.img    the filesystem mounted on disk/, when it is an ext4 image (see disk.py)
      disk/       what the submission may write, on a filesystem of --disk-limit when the
                  grader can make one (disk.py), else a plain folder:
        build/    the build sandbox's only writable folder: ws/ (the overlay workspace),
                  home/ and tmp/; owned by the sandbox's uid
        run/      the run sandbox's writable folder: home/ and tmp/; owned by the sandbox's
                  uid, and never visible to the build
        caches/   writable copies of the simulator's numba caches, filled before any node starts

After the build, build/ is data: the grader reads it only through
read_beneath (no link followed, regular files only) and binds build/ws only
after checking that it is still a folder of its own.

Pure: no ROS.
"""
import errno
import os
import shutil
import stat
import tempfile

from chase_tools.grading.disk import Disk

READ_LIMIT = 16 << 20


class Scratch:
    def __init__(self, top):
        self.top = os.path.abspath(top)
        self.owner = None                # (uid, gid) of the sandbox, when it is not the grader's
        self.grader = os.path.join(self.top, 'grader')
        self.disk = None                 # disk.Disk, when a disk limit was asked for
        written = os.path.join(self.top, 'disk')
        self.build = os.path.join(written, 'build')
        self.workspace = os.path.join(self.build, 'ws')
        self.run = os.path.join(written, 'run')
        self.caches = os.path.join(written, 'caches')

    @classmethod
    def create(cls, parent, prefix, disk_limit=None):
        """A new scratch folder in parent; with disk_limit (bytes), what the submission writes
        lies on a filesystem of that size when this process may mount one (disk.Disk)."""
        scratch = cls(tempfile.mkdtemp(prefix=prefix, dir=parent))
        os.mkdir(scratch.grader, 0o700)
        written = os.path.dirname(scratch.build)
        if disk_limit:
            scratch.disk = Disk.create(written, disk_limit)
        else:
            os.mkdir(written, 0o755)
        os.mkdir(scratch.caches, 0o700)
        for top in (scratch.build, scratch.run):
            for folder in (top, os.path.join(top, 'home'), os.path.join(top, 'tmp')):
                os.mkdir(folder, 0o700)
        os.mkdir(scratch.workspace, 0o755)
        return scratch

    def hand_over(self, path):
        """Give a folder the grader made (and nothing else has touched) to the sandbox's uid."""
        if self.owner is not None:
            hand_over(path, *self.owner)

    def linked(self, folders):
        """Those of folders (paths in the scratch) that are no longer folders of their own: a
        build may have put links in their place."""
        found = []
        for folder in folders:
            try:
                if not stat.S_ISDIR(lstat_beneath(self.top, os.path.relpath(folder, self.top)).st_mode):
                    found.append(folder)
            except OSError:
                found.append(folder)
        return found

    def close(self, keep=False):
        """Unmount the submission's filesystem (its processes have ended), and remove the
        scratch folder unless keep."""
        if self.disk is not None:
            self.disk.unmount()
        if not keep:
            # rmtree removes links, never what they point at.
            shutil.rmtree(self.top, ignore_errors=True)


def hand_over(path, uid, gid):
    """chown path and everything under it, links included as links."""
    os.chown(path, uid, gid, follow_symlinks=False)
    for root, dirs, files in os.walk(path):
        for name in dirs + files:
            os.chown(os.path.join(root, name), uid, gid, follow_symlinks=False)


def _components(relative):
    parts = [part for part in relative.split('/') if part not in ('', '.')]
    if '..' in parts:
        raise OSError(errno.EXDEV, 'leaves the folder', relative)
    return parts


def open_beneath(top, relative, flags=os.O_RDONLY):
    """An fd for top/relative, opened without following any link on the way (ELOOP, ENOTDIR)."""
    parts = _components(relative)
    fd = os.open(top, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW)
    try:
        for part in parts[:-1]:
            next_fd = os.open(part, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW, dir_fd=fd)
            os.close(fd)
            fd = next_fd
        if not parts:
            return os.dup(fd)
        return os.open(parts[-1], flags | os.O_NOFOLLOW | os.O_NONBLOCK, dir_fd=fd)
    finally:
        os.close(fd)


def lstat_beneath(top, relative):
    parts = _components(relative)
    if not parts:
        return os.lstat(top)
    fd = open_beneath(top, os.path.dirname('/'.join(parts)) or '.', os.O_RDONLY | os.O_DIRECTORY)
    try:
        return os.stat(parts[-1], dir_fd=fd, follow_symlinks=False)
    finally:
        os.close(fd)


def read_beneath(top, relative, limit=READ_LIMIT):
    """The bytes of the regular file top/relative, read as data: no link followed, no fifo or
    device opened, at most limit bytes. OSError otherwise."""
    fd = open_beneath(top, relative)
    try:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            raise OSError(errno.EINVAL, 'not a regular file', os.path.join(top, relative))
        chunks, left = [], limit
        while left > 0:
            data = os.read(fd, min(left, 1 << 20))
            if not data:
                break
            chunks.append(data)
            left -= len(data)
        return b''.join(chunks)
    finally:
        os.close(fd)


def write_new(path, data, mode=0o600):
    """Write a file that must not exist yet (no link followed, none replaced)."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, mode)
    with os.fdopen(fd, 'wb') as stream:
        stream.write(data.encode() if isinstance(data, str) else data)
