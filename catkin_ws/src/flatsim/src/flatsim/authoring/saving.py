"""Writing files from a request safely: only inside allowed folders, atomically, losing nothing.

A name from a request is relative to a folder the caller chose from its
allowed set. It may not be absolute, climb out with `..`, or reach outside
through a symlink (paths are compared after realpath). A file is written to
a temporary file beside it and renamed over the old one, so a failure part
way leaves the old file as it was. Every failure is an AuthoringError that
names the folder or file.
"""
import errno
import os
import shutil
import stat
import tempfile

from flatsim.errors import AuthoringError

WORLD_EXTENSION = '.world'
# A page may not pick these (or / itself, or /lib*) to save in: they belong to the system.
# /run is here because /var/run leads to it.
SYSTEM_FOLDERS = ('/etc', '/usr', '/bin', '/sbin', '/boot', '/proc', '/sys', '/dev', '/var',
                  '/root', '/run')


def _inside(path, folder):
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def _allowed_root(allowed_folders, folder):
    """The allowed folder (real path) that folder lies in, or AuthoringError."""
    if not folder or not os.path.isabs(folder):
        raise AuthoringError('the folder to save in must be an absolute path, got %r' % folder)
    real = os.path.realpath(folder)
    for allowed in allowed_folders:
        root = os.path.realpath(allowed)
        if _inside(real, root):
            return root
    raise AuthoringError('%s is not inside the folders flatsim may write to (%s)'
                         % (folder, ', '.join(allowed_folders) or 'none'))


def check_relative_name(name):
    """A relative file or folder name from a request: no absolute path, no `..`, no empty part."""
    if not isinstance(name, str) or not name.strip():
        raise AuthoringError('the name to save under is empty')
    if '\0' in name:
        raise AuthoringError('the name %r holds a NUL character' % name)
    if os.path.isabs(name) or name.startswith('~'):
        raise AuthoringError('the name %r must be relative to the chosen folder' % name)
    parts = name.split('/')
    if any(part in ('', '.', '..') for part in parts):
        raise AuthoringError("the name %r may not hold '..', '.' or empty parts" % name)
    return name


def _plain_name(name, what):
    """AuthoringError unless name is one plain file or folder name: no '/', no '..', no
    leading dot (a hidden file, or '.' and '..'), no control characters."""
    if not isinstance(name, str) or not name.strip():
        raise AuthoringError('the %s is empty' % what)
    if '/' in name or '\\' in name:
        raise AuthoringError("the %s %r may not hold '/' or '\\'; choose its folder with Browse"
                             % (what, name))
    if '..' in name:
        raise AuthoringError("the %s %r may not hold '..'" % (what, name))
    if name.startswith('.'):
        raise AuthoringError('the %s %r may not start with a dot (it would be hidden)' % (what, name))
    if any(ord(c) < 32 or ord(c) == 127 for c in name):
        raise AuthoringError('the %s %r holds a control character' % (what, name))
    return name


def check_folder_name(name, what='model folder name'):
    """A model's or building's folder: one plain folder name (see _plain_name)."""
    return _plain_name(name, what)


def check_world_file_name(name):
    """Save World As's file name: one plain file name that ends in .world, as Gazebo's are."""
    _plain_name(name, 'world file name')
    if not name.endswith(WORLD_EXTENSION) or name == WORLD_EXTENSION:
        raise AuthoringError('the world file name %r must end in %s, such as myworld%s'
                             % (name, WORLD_EXTENSION, WORLD_EXTENSION))
    return name


def _is_system_folder(real):
    """Whether real (a real absolute path) is / or lies in a folder of the system."""
    if real == '/':
        return True
    top = real.split('/')[1]
    return '/' + top in SYSTEM_FOLDERS or top.startswith('lib')


def check_pickable_folder(path, home):
    """The real path of a folder a page may pick to save in, or AuthoringError saying why not.

    Refused: / and the system's folders (SYSTEM_FOLDERS, /lib*), through symlinks too.
    home (HOME) and what lies in it are always fine, even where HOME is /root or under /var.
    """
    if not isinstance(path, str) or not os.path.isabs(path):
        raise AuthoringError('the folder to pick must be an absolute path, got %r' % (path,))
    real = os.path.realpath(path)
    if not os.path.isdir(real):
        raise AuthoringError('%s is not a folder' % path)
    home_real = os.path.realpath(home) if home else ''
    if home_real and home_real != '/' and _inside(real, home_real):
        return real
    if real == '/':
        raise AuthoringError('files may not be saved in the root folder /; pick a folder in your '
                             'home folder %s' % home)
    if _is_system_folder(real):
        shown = path if real == os.path.normpath(path) else '%s (%s)' % (path, real)
        raise AuthoringError('%s is a folder of the system; files may not be saved there. Pick a '
                             'folder in your home folder %s' % (shown, home))
    return real


def resolve_target(allowed_folders, folder, name):
    """The real path of name inside folder, where folder lies in one of allowed_folders.

    Raises AuthoringError for a folder outside them, a bad name, or a path
    that a symlink leads out of the allowed folder.
    """
    root = _allowed_root(allowed_folders, folder)
    check_relative_name(name)
    target = os.path.realpath(os.path.join(folder, name))
    if not _inside(target, root) or target == root:
        raise AuthoringError('%s leads outside %s (through a symlink?)' % (os.path.join(folder, name), root))
    return target


def _describe(error):
    return error.strerror or str(error)


def write_atomically(path, text):
    """Write text to path through a temporary file in the same folder, then rename it over path.

    On any failure the temporary file is removed and an existing file at
    path is left as it was. Raises AuthoringError naming the folder or file.
    """
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise AuthoringError('cannot save %s: the folder %s does not exist'
                             % (os.path.basename(path), folder))
    try:
        mode = stat.S_IMODE(os.stat(path).st_mode)
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        mode = 0o666 & ~umask
    except OSError as error:
        raise AuthoringError('cannot save %s: %s' % (path, _describe(error))) from None
    if os.path.isdir(path):
        raise AuthoringError('cannot save %s: a folder of that name is in the way' % path)
    try:
        descriptor, temporary = tempfile.mkstemp(dir=folder, prefix='.%s.' % os.path.basename(path),
                                                 suffix='.tmp')
    except OSError as error:
        raise AuthoringError('cannot write in the folder %s: %s' % (folder, _describe(error))) from None
    try:
        with os.fdopen(descriptor, 'w', encoding='utf-8') as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())
        os.chmod(temporary, mode)
        os.replace(temporary, path)
    except (OSError, UnicodeError) as error:
        try:
            os.unlink(temporary)
        except OSError:
            pass
        reason = _describe(error) if isinstance(error, OSError) else str(error)
        raise AuthoringError('cannot save %s: %s; the file there is unchanged' % (path, reason)) from None
    return path


def make_folder(path):
    """Make path (and its parents) as a folder; AuthoringError naming it when that fails."""
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as error:
        if error.errno == errno.EEXIST or error.errno == errno.ENOTDIR:
            raise AuthoringError('cannot make the folder %s: a file is in the way' % path) from None
        raise AuthoringError('cannot make the folder %s: %s' % (path, _describe(error))) from None
    return path


def save_text(allowed_folders, folder, name, text):
    """Write text as folder/name, where folder lies in one of allowed_folders; returns the real path.

    folder must exist; sub-folders in name are made.
    """
    target = resolve_target(allowed_folders, folder, name)
    if not os.path.isdir(folder):
        raise AuthoringError('cannot save %s: the folder %s does not exist' % (name, folder))
    make_folder(os.path.dirname(target))
    return write_atomically(target, text)


def _copy_entry(source, destination):
    if os.path.isdir(source) and not os.path.islink(source):
        shutil.copytree(source, destination, symlinks=True)
    else:
        shutil.copy2(source, destination, follow_symlinks=False)


def replace_folder(allowed_folders, folder, name, files):
    """Write the folder folder/name holding files ({relative name: text}) in one step; returns
    its real path.

    Everything is written to a temporary folder beside it first, with whatever else the old
    folder held (meshes, a thumbnail) copied in, and only then renamed into place: a failure
    on the way leaves the old folder as it was, with no file of it new and another old.
    """
    target = resolve_target(allowed_folders, folder, name)
    for relative in files:
        check_relative_name(relative)
    parent = os.path.dirname(target)
    if not os.path.isdir(parent):
        raise AuthoringError('cannot save in %s: the folder does not exist' % parent)
    if os.path.lexists(target) and not os.path.isdir(target):
        raise AuthoringError('cannot save %s: a file of that name is in the way' % target)
    base = os.path.basename(target)
    try:
        staging = tempfile.mkdtemp(dir=parent, prefix='.%s.' % base, suffix='.tmp')
    except OSError as error:
        raise AuthoringError('cannot write in the folder %s: %s' % (parent, _describe(error))) from None
    try:
        try:
            if os.path.isdir(target):
                os.chmod(staging, stat.S_IMODE(os.stat(target).st_mode))
                tops = {relative.split('/')[0] for relative in files}
                for entry in os.listdir(target):
                    if entry not in tops:
                        _copy_entry(os.path.join(target, entry), os.path.join(staging, entry))
            else:
                umask = os.umask(0)
                os.umask(umask)
                os.chmod(staging, 0o777 & ~umask)
        except (OSError, shutil.Error) as error:
            raise AuthoringError('cannot save %s: its old files cannot be kept (%s); the folder '
                                 'there is unchanged' % (target, error)) from None
        for relative, text in files.items():
            path = os.path.join(staging, relative)
            make_folder(os.path.dirname(path))
            try:
                write_atomically(path, text)
            except AuthoringError as error:
                raise AuthoringError('cannot save %s: %s; the folder there is unchanged'
                                     % (os.path.join(target, relative), error)) from None
        _swap_in(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return target


def _swap_in(staging, target):
    """Rename staging to target; an old target is moved aside first and removed after."""
    if not os.path.isdir(target):
        try:
            os.rename(staging, target)
        except OSError as error:
            raise AuthoringError('cannot save %s: %s' % (target, _describe(error))) from None
        return
    parent, base = os.path.split(target)
    try:
        aside = tempfile.mkdtemp(dir=parent, prefix='.%s.' % base, suffix='.old')
        os.rename(target, os.path.join(aside, base))
    except OSError as error:
        raise AuthoringError('cannot save %s: %s; the folder there is unchanged'
                             % (target, _describe(error))) from None
    try:
        os.rename(staging, target)
    except OSError as error:
        os.rename(os.path.join(aside, base), target)
        os.rmdir(aside)
        raise AuthoringError('cannot save %s: %s; the folder there is unchanged'
                             % (target, _describe(error))) from None
    shutil.rmtree(aside, ignore_errors=True)
