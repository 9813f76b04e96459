"""catkin_ws/devel_platform: the devel space without the project's solutions, for students.

The project's catkin_ws holds the platform (flatsim, the stand-ins for gazebo_ros
and friends, turtlesim, chase_tools) and its own solutions to what the course has
students write: my_robot, ball_chaser and simple_arm. `source env.sh --student`
sources this view instead of catkin_ws/devel, so that a student's package is the
only one of its name, and a forgotten `source devel/setup.bash` ends in ROS's own
"not found" rather than in our solution running.

The view is what catkin chains through, file for file:
- .catkin lists the platform's source folders, package folder by package folder
  where a folder also holds a solution. catkin's ros_package_path hook builds
  ROS_PACKAGE_PATH from it, in this shell and in every workspace built on top;
- lib, share, include, bin, pkgconfig, Python's dist-packages: symbolic links to
  catkin_ws/devel's, leaving out every entry named after a solution (lib/ball_chaser,
  share/my_robot, lib/python3/dist-packages/simple_arm, lib/pkgconfig/my_robot.pc,
  share/common-lisp/ros/ball_chaser, ...). So catkin_find, rosrun, roslaunch,
  Python's imports and CMake's find_package find none of them;
- setup.bash and its kin: devel's, pointed at this folder.

Python's packages are folders of their own here, their files linked one by one,
and without devel's __pycache__: Python writes its caches beside the files it
finds, and the grader's sandbox mounts writable copies over them, which it cannot
do through a link.

chase_tools needs the solutions at run time: chase_demo and evaluate run the
project's robot and chaser, grade checks a submission's service against the course's
ball_chaser/DriveToTarget and drives in my_robot's chase_house.world. Its commands
here are small scripts that run devel's through with_reference, which puts the
solutions back behind whatever the environment finds first (a student's sourced
workspace still wins, as in the default environment).

    python3 env/platform_devel.py             (re)make catkin_ws/devel_platform from catkin_ws/devel
    python3 env/platform_devel.py --if-stale  only when devel's entries or this file changed since
"""
import hashlib
import os
import re
import shlex
import shutil
import sys
import tempfile

ENV_DIR = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.dirname(ENV_DIR)
WORKSPACE = os.path.join(TOP, 'catkin_ws')
VIEW_NAME = 'devel_platform'
# What the course has students write; the project's own are its reference solutions.
SOLUTIONS = ('ball_chaser', 'my_robot', 'simple_arm')
# Platform packages whose commands run the solutions on purpose.
SOLUTION_USERS = ('chase_tools',)
WITH_REFERENCE = 'with_reference'
SIGNATURE = '.made_from'
# catkin's devel-space relay to a Python script in a package's source folder.
_RELAY_TARGET = re.compile(r"^python_script = '([^']*)'$", re.M)
_LOCK = 'cmake.lock'
PYTHON_PACKAGES = os.path.join('lib', 'python3', 'dist-packages')


class ViewError(Exception):
    """The devel space cannot be viewed (not built, say); the message says what to do."""


def package_folders(src):
    """{package folder: package name} under src, not looking inside packages or CATKIN_IGNOREd folders."""
    found = {}
    for root, dirs, files in os.walk(src):
        dirs[:] = sorted(name for name in dirs if not name.startswith('.'))
        if 'CATKIN_IGNORE' in files:
            dirs[:] = []
        elif 'package.xml' in files:
            with open(os.path.join(root, 'package.xml'), errors='replace') as manifest:
                match = re.search(r'<name>\s*([^<\s]+)\s*</name>', manifest.read())
            if match:
                found[root] = match.group(1)
            dirs[:] = []
    return found


def platform_sources(src, solutions=SOLUTIONS):
    """The folders to list in .catkin: the top-level folders of src that hold no solution,
    and the other packages of those that do, each on its own."""
    packages = package_folders(src)
    solution_folders = [folder for folder, name in packages.items() if name in solutions]
    sources = []
    for entry in sorted(os.listdir(src)):
        top = os.path.join(src, entry)
        if not os.path.isdir(top) or entry.startswith('.'):
            continue
        inner = [folder for folder in solution_folders if folder == top or folder.startswith(top + os.sep)]
        if not inner:
            if any(folder == top or folder.startswith(top + os.sep) for folder in packages):
                sources.append(top)
            continue
        sources.extend(sorted(folder for folder in packages
                              if folder.startswith(top + os.sep) and folder not in solution_folders
                              and not any(folder.startswith(s + os.sep) for s in solution_folders)))
    return sources


def relay_target(path):
    """The script a catkin devel relay runs, or None when path is not such a relay."""
    try:
        with open(path, errors='replace') as relay:
            head = relay.read(2048)
    except (OSError, UnicodeDecodeError):
        return None
    match = _RELAY_TARGET.search(head)
    return match.group(1) if match else None


def plan(devel, src, solutions=SOLUTIONS, users=SOLUTION_USERS):
    """{path relative to devel: 'hide' | 'wrap'} for the entries the view does not just link."""
    hidden_names = set(solutions) | {name + '.pc' for name in solutions}
    user_folders = [os.path.join(src, name) for name in users]
    special = {}
    for root, dirs, files in os.walk(devel):
        rel_root = os.path.relpath(root, devel)
        for name in list(dirs) + files:
            rel = os.path.normpath(os.path.join(rel_root, name))
            if name in hidden_names:
                special[rel] = 'hide'
        dirs[:] = [name for name in dirs if name not in hidden_names]
        in_bin = rel_root == 'bin'
        in_user_lib = rel_root in [os.path.join('lib', name) for name in users]
        if in_bin or in_user_lib:
            for name in files:
                target = relay_target(os.path.join(root, name))
                if target and any(target.startswith(folder + os.sep) for folder in user_folders):
                    special[os.path.normpath(os.path.join(rel_root, name))] = 'wrap'
    return special


def with_reference_script(devel, solution_folders):
    """A shell script that runs its arguments with the solutions found again, last."""
    def append(var, value):
        return '%s="${%s:+$%s:}"%s\n' % (var, var, var, shlex.quote(value))
    return ('#!/bin/sh\n'
            '# Runs its arguments with the project\'s %s found again, behind whatever\n'
            '# this environment finds first. Written by env/platform_devel.py.\n'
            % ', '.join(SOLUTIONS)
            + append('ROS_PACKAGE_PATH', os.pathsep.join(solution_folders))
            + append('CMAKE_PREFIX_PATH', devel)
            + append('PYTHONPATH', os.path.join(devel, 'lib', 'python3', 'dist-packages'))
            + 'export ROS_PACKAGE_PATH CMAKE_PREFIX_PATH PYTHONPATH\n'
            'exec "$@"\n')


def wrapper_script(view, target):
    return ('#!/bin/sh\n'
            '# %s runs the project\'s solutions on purpose; see env/platform_devel.py.\n'
            'exec %s %s "$@"\n' % (os.path.basename(target), shlex.quote(os.path.join(view, WITH_REFERENCE)),
                                   shlex.quote(target)))


def signature(devel, src, solutions=SOLUTIONS):
    """What the view is made from: devel's entries, the source folders and this file."""
    digest = hashlib.sha256()
    with open(os.path.abspath(__file__), 'rb') as this:
        digest.update(this.read())
    for root, dirs, files in os.walk(devel):
        # Python's caches come and go as modules are imported, and the view holds none of
        # them: were they counted, every import would make the view again under a running grade.
        dirs[:] = sorted(d for d in dirs if d != '__pycache__')
        for name in sorted(files):
            digest.update(os.path.relpath(os.path.join(root, name), devel).encode(errors='surrogateescape') + b'\0')
    for folder in platform_sources(src, solutions):
        digest.update(folder.encode(errors='surrogateescape') + b'\0')
    return digest.hexdigest()


def is_current(workspace=WORKSPACE, solutions=SOLUTIONS):
    view = os.path.join(workspace, VIEW_NAME)
    try:
        with open(os.path.join(view, SIGNATURE)) as made_from:
            recorded = made_from.read().strip()
    except OSError:
        return False
    return recorded == signature(os.path.join(workspace, 'devel'), os.path.join(workspace, 'src'), solutions)


def _write(path, text, executable=False):
    with open(path, 'w') as out:
        out.write(text)
    if executable:
        os.chmod(path, 0o755)


def _mirror(devel, view, final_view, rel, special):
    source = os.path.join(devel, rel) if rel else devel
    for name in sorted(os.listdir(source)):
        entry_rel = os.path.join(rel, name) if rel else name
        entry = os.path.join(source, name)
        dest = os.path.join(view, entry_rel)
        action = special.get(entry_rel)
        in_python = _within(entry_rel, PYTHON_PACKAGES)
        if action == 'hide' or name == _LOCK or (in_python and name == '__pycache__'):
            continue
        if action == 'wrap':
            _write(dest, wrapper_script(final_view, entry), executable=True)
        elif os.path.isdir(entry) and (in_python or _within(PYTHON_PACKAGES, entry_rel)
                                       or any(other.startswith(entry_rel + os.sep) for other in special)):
            os.mkdir(dest)
            _mirror(devel, view, final_view, entry_rel, special)
        else:
            os.symlink(entry, dest)


def _within(path, folder):
    return path == folder or path.startswith(folder + os.sep)


def build(workspace=WORKSPACE, solutions=SOLUTIONS, users=SOLUTION_USERS):
    """Make workspace/devel_platform from workspace/devel; returns its path."""
    devel = os.path.join(workspace, 'devel')
    src = os.path.join(workspace, 'src')
    view = os.path.join(workspace, VIEW_NAME)
    if not os.path.isfile(os.path.join(devel, '.catkin')):
        raise ViewError('%s is not a built devel space; run setup.sh (or catkin_make in %s) first'
                        % (devel, workspace))
    special = plan(devel, src, solutions, users)
    solution_folders = sorted(folder for folder, name in package_folders(src).items() if name in solutions)
    staging = tempfile.mkdtemp(prefix='.%s.' % VIEW_NAME, dir=workspace)
    try:
        for name in sorted(os.listdir(devel)):
            entry = os.path.join(devel, name)
            if os.path.isdir(entry):
                if special.get(name) != 'hide':
                    os.mkdir(os.path.join(staging, name))
                    _mirror(devel, staging, view, name, special)
            elif name not in ('.catkin', _LOCK):
                # setup.bash and kin name the devel folder as their own; here they name the view.
                with open(entry, errors='surrogateescape') as original:
                    text = original.read().replace(devel, view)
                _write(os.path.join(staging, name), text)
                shutil.copymode(entry, os.path.join(staging, name))
        _write(os.path.join(staging, WITH_REFERENCE), with_reference_script(devel, solution_folders),
               executable=True)
        _write(os.path.join(staging, '.catkin'), ';'.join(platform_sources(src, solutions)))
        _write(os.path.join(staging, SIGNATURE), signature(devel, src, solutions) + '\n')
        os.chmod(staging, 0o755)
        _replace(staging, view)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return view


def _replace(staging, view):
    old = None
    if os.path.lexists(view):
        old = tempfile.mkdtemp(prefix='.%s.old.' % VIEW_NAME, dir=os.path.dirname(view))
        os.rename(view, os.path.join(old, VIEW_NAME))
    os.rename(staging, view)
    if old:
        shutil.rmtree(old, ignore_errors=True)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    if argv not in ([], ['--if-stale']):
        print('usage: python3 env/platform_devel.py [--if-stale]   (makes %s/%s)'
              % (WORKSPACE, VIEW_NAME), file=sys.stderr)
        return 2
    try:
        if argv and is_current():
            return 0
        view = build()
    except ViewError as error:
        print('platform_devel: %s' % error, file=sys.stderr)
        return 1
    except OSError as error:
        print('platform_devel: cannot make %s/%s (%s); run ./setup.sh as the owner of the checkout'
              % (WORKSPACE, VIEW_NAME, error), file=sys.stderr)
        return 1
    print('made %s: the devel space without %s' % (view, ', '.join(SOLUTIONS)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
