"""One line for when the project's own package runs in place of a student's.

The project ships its solutions to what the course has students write: my_robot,
ball_chaser and simple_arm. In the default environment (`source env.sh`) they
sit in the workspace underneath, so a student who forgets
`source devel/setup.bash` runs ours, and the robot chases the ball whatever
their own code does. The reference launch files and nodes call this at start-up.

It looks for a package of the same name in the student's catkin workspaces:
~/catkin_ws first, then every folder beside it in $HOME, at src/<name> and one
folder deeper (src/*/<name>). The search is bounded to those places, so it costs
a handful of directory listings. A workspace whose source folder is on
ROS_PACKAGE_PATH is sourced and left out.

No rospy: nodes call it before init_node, and launch files run it in a
<param command=...>, inside roslaunch's own start-up:

    <param name="overlay_check/my_robot"
           command="$(find overlay_check)/scripts/shadowed '$(find my_robot)'"/>

The parameter's value is the folder of the package that ran.
"""
import os
import re
import sys

# The project's catkin_ws/src: this file is catkin_ws/src/overlay_check/src/overlay_check/shadowed.py.
PROJECT_SRC = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
STUDENT_WORKSPACE = 'catkin_ws'
# roslaunch passes every node it starts a __log:= argument; rosrun does not.
ROSLAUNCH_ARG = '__log:='
_NAME = re.compile(r'<name>\s*([^<\s]+)\s*</name>')


def package_name(folder):
    """The name a package.xml in folder declares, or None when there is none."""
    try:
        with open(os.path.join(folder, 'package.xml'), errors='replace') as manifest:
            match = _NAME.search(manifest.read(65536))
    except OSError:
        return None
    return match.group(1) if match else None


def package_folder(path):
    """The package folder that path lies in (the nearest one holding a package.xml), or None."""
    folder = os.path.abspath(path)
    if not os.path.isdir(folder):
        folder = os.path.dirname(folder)
    while True:
        if os.path.isfile(os.path.join(folder, 'package.xml')):
            return folder
        parent = os.path.dirname(folder)
        if parent == folder:
            return None
        folder = parent


def _subfolders(folder):
    try:
        names = sorted(os.listdir(folder))
    except OSError:
        return []
    return [os.path.join(folder, name) for name in names
            if not name.startswith('.') and os.path.isdir(os.path.join(folder, name))]


def student_workspaces(home):
    """~/catkin_ws, then the other folders in home, each one a possible catkin workspace."""
    first = os.path.join(home, STUDENT_WORKSPACE)
    return [first] + [folder for folder in _subfolders(home) if folder != first]


def student_copies(name, home):
    """[(workspace, package folder)] of packages called name in the student's workspaces."""
    found = []
    for workspace in student_workspaces(home):
        src = os.path.join(workspace, 'src')
        if not os.path.isdir(src):
            continue
        for folder in [os.path.join(src, name)] + [os.path.join(inner, name) for inner in _subfolders(src)]:
            if package_name(folder) == name:
                found.append((workspace, folder))
    return found


def _inside(path, folder):
    return path == folder or path.startswith(folder.rstrip(os.sep) + os.sep)


def is_sourced(workspace, ros_package_path):
    """True when workspace's packages are on ROS_PACKAGE_PATH (its devel/setup.bash is sourced)."""
    real = os.path.realpath(workspace)
    return any(entry and (_inside(os.path.realpath(entry), real) or _inside(real, os.path.realpath(entry)))
               for entry in ros_package_path.split(os.pathsep))


def fix_line(workspace):
    """The command that makes workspace's packages the ones that run."""
    if os.path.isfile(os.path.join(workspace, 'devel', 'setup.bash')):
        return 'source %s' % os.path.join(workspace, 'devel', 'setup.bash')
    return 'cd %s && catkin_make && source devel/setup.bash' % workspace


def shadow_warning(running, home, ros_package_path, project_src=PROJECT_SRC):
    """The one line to print when running, a package folder of the project, hides a student's
    package of the same name in a workspace that is not sourced; None when there is nothing to say."""
    running = os.path.realpath(running)
    project_src = os.path.realpath(project_src)
    if os.path.dirname(running) != project_src:
        return None     # a copy of ours elsewhere (a grader's build, a test's) or the student's own
    name = package_name(running)
    if name is None or not home:
        return None
    project_workspace = os.path.dirname(project_src)
    hidden = [(workspace, folder) for workspace, folder in student_copies(name, home)
              if os.path.realpath(folder) != running
              and not _inside(os.path.realpath(workspace), project_workspace)
              and not is_sourced(workspace, ros_package_path)]
    if not hidden:
        return None
    workspace, folder = hidden[0]
    more = ''
    if len(hidden) > 1:
        more = ' (another in %s)' % ', '.join(other for _ws, other in hidden[1:])
    return ('%s: this is the project\'s %s (%s), not yours (%s)%s: your workspace is not sourced; '
            'to run yours: %s' % (name, name, running, folder, more, fix_line(workspace)))


def warning_for(path, environ=None):
    """shadow_warning for the package that path (a node's file or a package folder) lies in."""
    environ = os.environ if environ is None else environ
    running = package_folder(path)
    if running is None:
        return None
    return shadow_warning(running, environ.get('HOME', ''), environ.get('ROS_PACKAGE_PATH', ''))


def warn_if_shadowed(node_file, argv=None, stream=None):
    """For a reference node: print the warning, unless roslaunch started the node (the launch
    file has said it once already, for all its nodes)."""
    argv = sys.argv if argv is None else argv
    if any(arg.startswith(ROSLAUNCH_ARG) for arg in argv):
        return None
    line = warning_for(node_file)
    if line:
        print(line, file=stream or sys.stderr, flush=True)
    return line


def main(argv=None):
    """shadowed PACKAGE_FOLDER: warn on stderr, print the folder on stdout (the parameter's value)."""
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1 or not os.path.isdir(argv[0]):
        print('usage: shadowed PACKAGE_FOLDER (got %s)' % (' '.join(argv) or 'nothing'), file=sys.stderr)
        return 2
    line = warning_for(argv[0])
    if line:
        print(line, file=sys.stderr, flush=True)
    print(os.path.realpath(argv[0]), end='')
    return 0
