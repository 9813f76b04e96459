"""catkin_make as the course uses it, made to work for students' packages here.

env.sh puts env/bin first on PATH, so a student's terminal, ./setup.sh and the
tests all build through this. It runs Debian's catkin_make with the same
arguments, and:

- every compiled target of a package depends on the package's own generated
  message headers and on those of the catkin packages it found
  (env/cmake/generated_messages_first.cmake, through CMAKE_PROJECT_INCLUDE).
  Packages that forget `add_dependencies(node ${catkin_EXPORTED_TARGETS}
  <pkg>_generate_messages_cpp)` otherwise fail on a parallel build with
  "fatal error: <pkg>/<Srv>.h: No such file or directory";
- a package that builds a Gazebo plugin (find_package of gazebo,
  gazebo_plugins or gazebo_dev) is left out with a message that names it:
  Gazebo is not installed, and flatsim does not load plugin libraries;
- when the workspaces underneath differ from those the build was configured
  on (built before `source env.sh`, say), CMake runs again, so that
  devel/setup.bash chains to the environment you have now.
"""
import os
import re
import sys

from catkin.builder import extract_cmake_and_make_arguments
from catkin_pkg.packages import find_packages

DEBIAN_CATKIN_MAKE = '/usr/bin/catkin_make'
ENV_DIR = os.path.dirname(os.path.abspath(__file__))
PROJECT_INCLUDE = os.path.join(ENV_DIR, 'cmake', 'generated_messages_first.cmake')
GAZEBO_PACKAGES = ('gazebo', 'gazebo_plugins', 'gazebo_dev')
BLACKLIST_ARG = '-DCATKIN_BLACKLIST_PACKAGES='

_COMMENT = re.compile(r'#\[(=*)\[.*?\]\1\]|#[^\n]*', re.S)
_FIND_PACKAGE = re.compile(r'\bfind_package\s*\(([^)]*)\)', re.I)


def workspace_paths(argv, cwd):
    """(source, devel) folders that catkin_make will use for these arguments."""
    args, cmake_args, _make_args = extract_cmake_and_make_arguments(list(argv))
    base = _option(args, ('-C', '--directory')) or cwd
    base = os.path.abspath(os.path.join(cwd, base))
    source = _option(args, ('--source',))
    source = os.path.abspath(os.path.join(cwd, source)) if source else os.path.join(base, 'src')
    devel = _last_define(cmake_args, 'CATKIN_DEVEL_PREFIX')
    devel = os.path.abspath(os.path.join(cwd, devel)) if devel else os.path.join(base, 'devel')
    return source, devel


def _option(args, names):
    value = None
    for i, arg in enumerate(args):
        for name in names:
            if arg == name and i + 1 < len(args):
                value = args[i + 1]
            elif name.startswith('--') and arg.startswith(name + '='):
                value = arg[len(name) + 1:]
            elif not name.startswith('--') and arg.startswith(name) and len(arg) > len(name):
                value = arg[len(name):]
    return value


def _last_define(cmake_args, name):
    prefix = '-D%s=' % name
    values = [arg[len(prefix):] for arg in cmake_args if arg.startswith(prefix)]
    return values[-1] if values else None


def gazebo_dependencies(cmake_text):
    """The Gazebo packages that a CMakeLists.txt find_package()s, in order of mention."""
    found = []
    for call in _FIND_PACKAGE.finditer(_COMMENT.sub('', cmake_text)):
        for word in call.group(1).split():
            if word in GAZEBO_PACKAGES and word not in found:
                found.append(word)
    return found


def gazebo_plugin_packages(source_dir):
    """[(package name, path relative to source_dir, [gazebo packages])] to leave out."""
    plugins = []
    for path, package in sorted(find_packages(source_dir, exclude_subspaces=True).items()):
        try:
            with open(os.path.join(source_dir, path, 'CMakeLists.txt'), errors='replace') as cmake:
                needs = gazebo_dependencies(cmake.read())
        except FileNotFoundError:
            continue
        if needs:
            plugins.append((package.name, path, needs))
    return plugins


def recorded_underlays(devel_dir):
    """The workspaces a devel space chains to, as catkin wrote them, or None if not built."""
    try:
        with open(os.path.join(devel_dir, '_setup_util.py')) as setup_util:
            text = setup_util.read()
    except FileNotFoundError:
        return None
    match = re.search(r"^\s*CMAKE_PREFIX_PATH = r'([^']*)'\.split\(';'\)", text, re.M)
    if match is None:
        return None
    return _catkin_workspaces(match.group(1).split(';'), devel_dir)


def current_underlays(devel_dir, environ):
    """The workspaces catkin would chain this devel space to in this environment."""
    return _catkin_workspaces(environ.get('CMAKE_PREFIX_PATH', '').split(os.pathsep), devel_dir)


def _catkin_workspaces(prefixes, devel_dir):
    # As catkin's all.cmake picks them: the prefixes holding a .catkin marker, but not this one.
    own = os.path.realpath(devel_dir)
    found = []
    for prefix in prefixes:
        real = os.path.realpath(prefix) if prefix else None
        if real and real != own and real not in found and os.path.isfile(os.path.join(real, '.catkin')):
            found.append(real)
    return found


def command(argv, cwd, environ, say):
    """The Debian catkin_make command line for argv; say(line) reports what it changes."""
    source, devel = workspace_paths(argv, cwd)
    _args, cmake_args, _make_args = extract_cmake_and_make_arguments(list(argv))
    blacklist = [name for arg in cmake_args if arg.startswith(BLACKLIST_ARG)
                 for name in arg[len(BLACKLIST_ARG):].split(';') if name]
    passed_on = [arg for arg in argv if not arg.startswith(BLACKLIST_ARG)]
    for name, path, needs in gazebo_plugin_packages(source) if os.path.isdir(source) else []:
        say('skipping package %s (%s): it builds a Gazebo plugin (find_package %s), and Gazebo '
            'is not installed here; flatsim runs the gazebo_ros plugins itself and loads no '
            'plugin libraries' % (name, os.path.join(os.path.basename(source), path), ', '.join(needs)))
        if name not in blacklist:
            blacklist.append(name)
    extra = ['-DCMAKE_PROJECT_INCLUDE=%s' % PROJECT_INCLUDE, BLACKLIST_ARG + ';'.join(blacklist)]
    recorded = recorded_underlays(devel)
    wanted = current_underlays(devel, environ)
    if recorded is not None and recorded != wanted:
        say('the workspaces underneath changed (built on: %s; now: %s): running CMake again so '
            'devel/setup.bash chains to them' % (':'.join(recorded) or 'none', ':'.join(wanted) or 'none'))
        extra.append('--force-cmake')
        # catkin copies the new file into devel with CMake's file(COPY), which skips a
        # destination whose time matches the new one's to the second: a build a moment
        # earlier would keep the old chain. An old time makes the copy happen, and the old
        # file still works if CMake fails.
        os.utime(os.path.join(devel, '_setup_util.py'), (0, 0))
    return [DEBIAN_CATKIN_MAKE] + extra + passed_on


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    # Debian's catkin_make takes the current folder from PWD, so that symlinked paths stay as typed.
    cwd = os.environ.get('PWD') or os.getcwd()
    cmd = command(argv, cwd, os.environ, lambda line: print('catkin_make: ' + line, flush=True))
    os.execv(cmd[0], cmd)
