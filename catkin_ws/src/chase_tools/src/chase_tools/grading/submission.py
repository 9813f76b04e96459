"""What a submission holds, and the copy of it that the grader builds and launches.

A submission is a folder: a catkin workspace, its src folder, or a repository
with the robot package and ball_chaser somewhere inside. Pure: no ROS.
"""
import os
import shutil
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Dict, List, Optional

SKIPPED_DIRS = {'build', 'devel', 'install', 'logs', '.git', '.catkin_tools', '__pycache__'}
CHASER = 'ball_chaser'
ROBOT_LAUNCH = os.path.join('launch', 'world.launch')
COURSE_SERVICE = '/ball_chaser/command_robot'
# Where the grader serves its counting stand-in for the service (see session.py).
PROXY_SERVICE = '/grader/command_robot'
# Nodes that need a display; the grader runs headless, so they are left out.
GUI_PACKAGES = ('rviz', 'image_view', 'rqt_gui', 'rqt_image_view', 'rqt_graph', 'rqt_plot')
DEPEND_TAGS = ('depend', 'build_depend', 'exec_depend', 'run_depend', 'build_export_depend',
               'buildtool_depend', 'test_depend')


@dataclass
class Package:
    name: str
    path: str
    depends: List[str] = field(default_factory=list)


@dataclass
class Submission:
    path: str
    packages: Dict[str, Package]           # every catkin package found, by name
    robot: Optional[Package]               # the package with launch/world.launch
    chaser: Optional[Package]
    problems: List[str] = field(default_factory=list)

    @property
    def name(self):
        return os.path.basename(os.path.abspath(self.path).rstrip('/'))

    def needed(self):
        """The packages to build: robot and ball_chaser and what they depend on from the submission."""
        wanted = [p.name for p in (self.robot, self.chaser) if p is not None]
        needed = []
        while wanted:
            name = wanted.pop()
            if name in needed or name not in self.packages:
                continue
            needed.append(name)
            wanted.extend(self.packages[name].depends)
        return sorted(needed)


def package_dirs(top):
    """Folders under top that hold a package.xml (catkin's rules: CATKIN_IGNORE, no nesting)."""
    found = []
    for root, dirs, files in os.walk(top):
        if 'CATKIN_IGNORE' in files and root != top:
            dirs[:] = []
            continue
        if 'package.xml' in files:
            found.append(root)
            dirs[:] = []
            continue
        dirs[:] = sorted(d for d in dirs if d not in SKIPPED_DIRS and not d.startswith('.'))
    return found


def read_package(path):
    """A Package from path/package.xml; ValueError if it cannot be read."""
    try:
        root = ET.parse(os.path.join(path, 'package.xml')).getroot()
    except (ET.ParseError, OSError) as error:
        raise ValueError('%s/package.xml cannot be read: %s' % (path, error)) from error
    name = (root.findtext('name') or '').strip()
    if not name:
        raise ValueError('%s/package.xml has no <name>' % path)
    depends = sorted({(e.text or '').strip() for tag in DEPEND_TAGS for e in root.iter(tag)} - {''})
    return Package(name, path, depends)


def chaser_count(top):
    """How many ball_chaser packages lie under top."""
    count = 0
    for path in package_dirs(top):
        try:
            count += read_package(path).name == CHASER
        except ValueError:
            continue
    return count


def find(path):
    """The Submission in a folder; its problems say what is missing."""
    packages, problems = {}, []
    for package_dir in package_dirs(path):
        try:
            package = read_package(package_dir)
        except ValueError as error:
            problems.append(str(error))
            continue
        if package.name in packages:
            problems.append('two packages named %s: %s and %s; using the first'
                            % (package.name, packages[package.name].path, package_dir))
            continue
        packages[package.name] = package
    chaser = packages.get(CHASER)
    if chaser is None:
        problems.append('no package named %s in %s' % (CHASER, path))
    robots = [p for p in packages.values()
              if p.name != CHASER and os.path.isfile(os.path.join(p.path, ROBOT_LAUNCH))]
    robots.sort(key=lambda p: (p.name != 'my_robot', p.name))
    if not robots:
        problems.append('no package with %s in %s' % (ROBOT_LAUNCH, path))
    return Submission(path, packages, robots[0] if robots else None, chaser, problems)


def submissions_in(path):
    """[path] for one submission, or the subfolders of a folder of submissions."""
    if chaser_count(path) > 1:
        return [os.path.join(path, entry) for entry in sorted(os.listdir(path))
                if os.path.isdir(os.path.join(path, entry)) and not entry.startswith('.')]
    return [path]


def copy_packages(submission, src):
    """Copy the needed packages into the overlay's src folder; their new paths, by name."""
    copied = {}
    for name in submission.needed():
        target = os.path.join(src, name)
        shutil.copytree(submission.packages[name].path, target, symlinks=True,
                        ignore=shutil.ignore_patterns('.git', 'build', 'devel'))
        copied[name] = target
    return copied


# -- launch files, prepared for a headless run --------------------------------------------

@dataclass
class LaunchChanges:
    dropped: List[str] = field(default_factory=list)     # GUI nodes left out
    remapped: List[str] = field(default_factory=list)    # nodes whose service calls are counted


def _nodes(root):
    return [element for element in root.iter('node')]


def _node_label(node):
    return '%s (%s/%s)' % (node.get('name', '?'), node.get('pkg', '?'), node.get('type', '?'))


def drop_gui_nodes(root):
    """Remove nodes that need a display; their labels."""
    dropped = []
    for parent in list(root.iter()):
        for child in list(parent):
            if child.tag == 'node' and child.get('pkg', '') in GUI_PACKAGES:
                parent.remove(child)
                dropped.append(_node_label(child))
    return dropped


def looks_like_drive_node(node):
    """The course's server node is drive_bot; a guess the session checks on the master."""
    return 'drive' in (node.get('type', '') + node.get('name', '')).lower()


def remap_service_clients(root, keep=()):
    """Send every node's calls to the course service to the grader's stand-in, except servers.

    keep: node names known to serve the service. Nodes that look like drive_bot
    are kept too. Returns the labels of the nodes remapped.
    """
    remapped = []
    for node in _nodes(root):
        if looks_like_drive_node(node) or node.get('name') in keep:
            continue
        remap = ET.Element('remap', {'from': COURSE_SERVICE, 'to': PROXY_SERVICE})
        remap.tail = '\n'
        node.insert(0, remap)
        remapped.append(_node_label(node))
    return remapped


def prepare_launch_files(package_dir, remap=False, keep=()):
    """Rewrite a package's launch files in place (in the grader's copy) for a headless run."""
    changes = LaunchChanges()
    for root_dir, _dirs, files in os.walk(package_dir):
        for name in sorted(files):
            if not name.endswith('.launch') and not name.endswith('.launch.xml'):
                continue
            path = os.path.join(root_dir, name)
            original = path + '.orig'
            if os.path.exists(original):
                shutil.copyfile(original, path)
            try:
                tree = ET.parse(path)
            except ET.ParseError:
                continue                     # roslaunch will say what is wrong with it
            dropped = drop_gui_nodes(tree.getroot())
            remapped = remap_service_clients(tree.getroot(), keep) if remap else []
            if dropped or remapped:
                if not os.path.exists(original):
                    shutil.copyfile(path, original)
                tree.write(path)
                changes.dropped += dropped
                changes.remapped += remapped
    return changes
