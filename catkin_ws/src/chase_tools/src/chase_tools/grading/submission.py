"""What a submission holds, and the copy of it that the grader builds and launches.

A submission is a folder: a catkin workspace, its src folder, or a repository
with the robot package (the one with launch/world.launch) and ball_chaser
somewhere inside, often beside stray copies of them. The grader grades one
folder of it: the one where a robot package and ball_chaser sit together
(find). A folder is a class, one submission per subfolder, only when asked or
when every subfolder that holds a package holds a whole submission
(submissions_in). Pure: no ROS.
"""
import os
import re
import shutil
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import Dict, List, Optional

from defusedxml import ElementTree as defused_ET
from defusedxml.common import DefusedXmlException

from chase_tools.grading.scratch import read_beneath
from flatsim.authoring.sdf_text import element_depth

SKIPPED_DIRS = {'build', 'devel', 'install', 'logs', '.git', '.catkin_tools', '__pycache__'}
# Left out of the grader's copy of a package, at any depth.
NOT_COPIED = {'.git', 'build', 'devel'}
CHASER = 'ball_chaser'
# The launch files the course names, each found as `roslaunch PKG FILE` finds it: anywhere in
# its package (find_launch), launch/ being only where the course keeps it.
ROBOT_LAUNCH = 'world.launch'
CHASER_LAUNCH = 'ball_chaser.launch'
COURSE_LAUNCH_FOLDER = 'launch'
PREFERRED_ROBOT = 'my_robot'
COURSE_SERVICE = '/ball_chaser/command_robot'
# Where the grader serves its counting stand-in for the service (listeners.CallCounter).
PROXY_SERVICE = '/grader/command_robot'
LAUNCH_READ_LIMIT = 4 << 20
# Deeper launch files are not read: none a student writes nests so deep, and reading or
# writing them a Python call per level, as roslaunch and ElementTree do, nears Python's
# recursion limit (where a garbage collection could not free pymunk's bodies safely).
LAUNCH_MAX_DEPTH = 100
PACKAGE_READ_LIMIT = 1 << 20
# This workspace's own packages (catkin_ws/src): the simulator, its Gazebo stand-ins, the
# grader. A submission's package of one of their names, built over them, would take its
# place; only the packages the course has students write may.
OUR_SRC = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), *[os.pardir] * 4))
COURSE_PACKAGES = (CHASER, PREFERRED_ROBOT)
DEPEND_TAGS = ('depend', 'build_depend', 'exec_depend', 'run_depend', 'build_export_depend',
               'buildtool_depend', 'test_depend')
# REP 144's rule for a package's name. The grader, as root, makes a folder of each name it
# builds, so a name outside the rule ('..', '/') would aim root's copy anywhere.
PACKAGE_NAME = re.compile(r'[a-z][a-z0-9_]*')


def is_package_name(name):
    return PACKAGE_NAME.fullmatch(name) is not None


@dataclass
class Package:
    name: str
    path: str
    depends: List[str] = field(default_factory=list)


@dataclass
class Submission:
    path: str
    packages: Dict[str, Package]           # the packages of the graded folder, by name
    robot: Optional[Package]               # the package with launch/world.launch
    chaser: Optional[Package]
    problems: List[str] = field(default_factory=list)
    folder: str = '.'                      # the graded folder, relative to path
    ignored: List[str] = field(default_factory=list)   # package folders not graded, relative to path
    choices: List[str] = field(default_factory=list)   # how the folder was chosen, when it was a choice

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
    """A Package from path/package.xml; ValueError if it cannot be read.

    It is the submission's, read as data: a link is not followed, the size is bounded, and
    a file that declares XML entities is not read (see read_launch).
    """
    root = read_launch(os.path.realpath(path), os.path.join(os.path.realpath(path), 'package.xml'),
                       limit=PACKAGE_READ_LIMIT, errors=True)
    if not isinstance(root, ET.Element):
        raise ValueError('%s/package.xml cannot be read: %s' % (path, root))
    name = (root.findtext('name') or '').strip()
    if not name:
        raise ValueError('%s/package.xml has no <name>' % path)
    if not is_package_name(name):
        raise ValueError('%s/package.xml: the package is refused: its <name> %r is not a ROS '
                         'package name (REP 144: a lower-case letter, then lower-case letters, '
                         'digits and underscores)' % (path, name[:80]))
    # A dependency is a rosdep key (python3-numpy) or a package's name; only a package's name
    # can be one of the submission's packages, which are followed and copied.
    depends = sorted({(e.text or '').strip() for tag in DEPEND_TAGS for e in root.iter(tag)}
                     - {''})
    return Package(name, path, [depend for depend in depends if is_package_name(depend)])


def read_packages(top):
    """([Package] under top, [problems reading the others])."""
    packages, problems = [], []
    for path in package_dirs(top):
        try:
            packages.append(read_package(path))
        except ValueError as error:
            problems.append(str(error))
    return packages, problems


def find_launch(package_path, file_name):
    """The files named file_name in a package, relative to it and sorted, found as roslaunch's
    `roslaunch PKG FILE` finds them (roslib's find_resource): in any folder of the package but
    those whose names start with a dot. Read as data: no link is followed, and the folders the
    grader leaves out of its copy (NOT_COPIED) are not searched."""
    found = []
    for root, dirs, files in os.walk(package_path):
        dirs[:] = sorted(d for d in dirs if not d.startswith('.') and d not in NOT_COPIED)
        if file_name in files and not os.path.islink(os.path.join(root, file_name)):
            found.append(os.path.relpath(os.path.join(root, file_name), package_path))
    return sorted(found)


def launch_path(package_path, file_name):
    """package_path/the file roslaunch would run for file_name; the course's place, launch/,
    when the package holds none (roslaunch then says it cannot find it) or several (roslaunch
    refuses to choose)."""
    found = find_launch(package_path, file_name)
    relative = found[0] if len(found) == 1 else os.path.join(COURSE_LAUNCH_FOLDER, file_name)
    return os.path.join(package_path, relative)


def is_robot(package):
    return package.name != CHASER and bool(find_launch(package.path, ROBOT_LAUNCH))


def launch_places(found):
    """Notes on the course's launch files that lie outside launch/ (roslaunch finds them
    there all the same) or of which a package holds several (roslaunch refuses to run them)."""
    notes = []
    for package, file_name in ((found.robot, ROBOT_LAUNCH), (found.chaser, CHASER_LAUNCH)):
        if package is None:
            continue
        places = find_launch(package.path, file_name)
        if len(places) > 1:
            notes.append('%s holds %d files named %s (%s): `roslaunch %s %s` refuses to choose '
                         'between them' % (package.name, len(places), file_name, ', '.join(places),
                                           package.name, file_name))
        elif places and places[0] != os.path.join(COURSE_LAUNCH_FOLDER, file_name):
            notes.append('%s/%s lies outside launch/, where the course keeps it; roslaunch finds '
                         'it there all the same' % (package.name, places[0]))
    return notes


def _depth(path, top):
    relative = os.path.relpath(path, top)
    return 0 if relative == '.' else len(relative.split(os.sep))


def _inside(path, top):
    return os.path.commonpath([path, top]) == top


def _pairs(packages, top):
    """Every (robot, ball_chaser) pair, best first: the two nearest each other (fewest folders
    between each and their common folder), the robot named my_robot, the common folder nearest
    top, then by path, so that the choice never depends on the order of the file system."""
    pairs = []
    for robot in (p for p in packages if is_robot(p)):
        for chaser in (p for p in packages if p.name == CHASER):
            common = os.path.commonpath([robot.path, chaser.path])
            apart = _depth(robot.path, common) + _depth(chaser.path, common)
            pairs.append(((apart, robot.name != PREFERRED_ROBOT, _depth(common, top), common,
                           robot.path, chaser.path), robot, chaser, common))
    return sorted(pairs, key=lambda pair: pair[0])


def find(path):
    """The Submission in a folder: the folder in it that holds a robot package and ball_chaser
    together; problems say what is missing, choices how the folder was chosen."""
    every, problems = read_packages(path)
    pairs = _pairs(every, path)
    if not pairs:
        robot = min((p for p in every if is_robot(p)), default=None,
                    key=lambda p: (p.name != PREFERRED_ROBOT, p.name, p.path))
        chaser = next((p for p in every if p.name == CHASER), None)
        if chaser is None:
            problems.append('no package named %s in %s' % (CHASER, path))
        if robot is None:
            problems.append('no package with a %s in %s' % (ROBOT_LAUNCH, path))
        return Submission(path, _by_name(every, path, (), problems), robot, chaser, problems)
    (key, robot, chaser, common), others = pairs[0], pairs[1:]
    choices = []
    rivals = sorted({other[3] for other in others if other[0][:2] == key[:2] and other[3] != common})
    if rivals:
        choices.append('graded %s; %s also hold%s a robot package beside a %s; the grader takes '
                       'the folder nearest the top, then the first by name'
                       % (_relative(common, path), ', '.join(_relative(r, path) for r in rivals),
                          's' if len(rivals) == 1 else '', CHASER))
    inside = [p for p in every if _inside(p.path, common)]
    packages = _by_name(inside, common, (robot, chaser), problems)
    elsewhere = _by_name([p for p in every if not _inside(p.path, common)], common, (), [])
    found = Submission(path, packages, robot, chaser, problems, _relative(common, path),
                       choices=choices)
    # A dependency that only lies outside the graded folder is still the submission's.
    for name in _missing_dependencies(found, elsewhere):
        packages[name] = elsewhere[name]
        choices.append('%s taken from %s, outside %s' % (name, _relative(elsewhere[name].path, path),
                                                         found.folder))
    choices.extend(launch_places(found))
    graded = {id(p) for p in packages.values()}
    found.ignored = sorted(_relative(p.path, path) for p in every if id(p) not in graded)
    return found


def _by_name(packages, top, preferred, problems):
    """One package per name: the preferred ones, then the one nearest top, then by path."""
    chosen = {}
    ranked = sorted(packages, key=lambda p: (all(p is not q for q in preferred),
                                             _depth(p.path, top), p.path))
    for package in ranked:
        if package.name in chosen:
            problems.append('two packages named %s: %s and %s; using the first'
                            % (package.name, chosen[package.name].path, package.path))
            continue
        chosen[package.name] = package
    return chosen


def _missing_dependencies(found, elsewhere):
    missing, seen = [], set()
    wanted = list(found.needed())
    while wanted:
        name = wanted.pop()
        if name in seen:
            continue
        seen.add(name)
        package = found.packages.get(name) or elsewhere.get(name)
        if package is None:
            continue
        if name not in found.packages:
            missing.append(name)
        wanted.extend(package.depends)
    return sorted(missing)


def _relative(path, top):
    return os.path.relpath(path, top)


def is_complete(folder):
    """True when folder holds a robot package and a ball_chaser."""
    packages, _problems = read_packages(folder)
    return bool(_pairs(packages, folder))


def subfolders(path):
    return [os.path.join(path, entry) for entry in sorted(os.listdir(path))
            if os.path.isdir(os.path.join(path, entry)) and not entry.startswith('.')
            and entry not in SKIPPED_DIRS]


def submissions_in(path, whole_class=False):
    """The submissions in path: [path], or its subfolders when it is a class.

    It is a class when whole_class is set (`grade --class`), or when at least two
    subfolders hold a package and each of those holds a whole submission.
    A repository holds stray packages in subfolders beside the real submission;
    a class whose every student's folder is complete is told from it. A class
    is every subfolder, those without a package too (a student who pushed none).
    """
    folders = subfolders(path)
    if whole_class:
        return folders
    holding = [folder for folder in folders if package_dirs(folder)]
    if len(holding) >= 2 and all(is_complete(folder) for folder in holding):
        return folders
    return [path]


def complete_subfolders(path):
    """The subfolders of path that hold a whole submission (for a hint to pass --class)."""
    return [folder for folder in subfolders(path) if is_complete(folder)]


# -- the grader's copy --------------------------------------------------------------------

def our_package_names(src=OUR_SRC):
    """The names a submission's packages may not have: this workspace's own, but for the
    course's (COURSE_PACKAGES)."""
    names = set()
    for path in package_dirs(src):
        try:
            names.add(read_package(path).name)
        except ValueError:
            continue
    return names - set(COURSE_PACKAGES)


def named_like_ours(submission, ours=None):
    """The packages the grader would build (needed()) that have one of our_package_names(),
    each as 'name (its folder in the submission)'."""
    ours = our_package_names() if ours is None else ours
    return ['%s (%s)' % (name, _relative(submission.packages[name].path, submission.path))
            for name in submission.needed() if name in ours]


def copy_packages(submission, src):
    """Copy the needed packages into the overlay's src folder.

    Returns ({name: new path}, [links left out, each 'link -> target (why)']).
    The copy holds no links: one whose target lies inside the submission is
    copied as what it points to, and one that points outside it (roslaunch
    would crawl its target), nowhere, or back to a folder above it is left out.
    """
    copied, left_out = {}, []
    top = os.path.realpath(submission.path)
    for name in submission.needed():
        source = submission.packages[name].path
        target = copy_target(src, name)
        _copy_tree(source, target, _TreeCopy(top, submission.path, left_out))
        copied[name] = target
    return copied, left_out


def copy_target(src, name):
    """src/name, for a package's copy; ValueError unless name is a package's name and the
    folder lies directly in src, whatever src's links."""
    if not is_package_name(name):
        raise ValueError('%r is not a ROS package name; nothing is copied for it' % name[:80])
    real_src = os.path.realpath(src)
    target = os.path.join(real_src, name)
    if os.path.dirname(os.path.realpath(target)) != real_src:
        raise ValueError('the copy of %s would not lie in %s' % (name, src))
    return target


@dataclass
class _TreeCopy:
    top: str                  # the submission, resolved
    shown_top: str            # the submission as given, for the names in left_out
    left_out: List[str]


def _copy_tree(source, target, copy, ancestors=()):
    """Copy a folder; ancestors: the resolved folders being copied around it (a link to one
    of them is a loop)."""
    ancestors = ancestors + (os.path.realpath(source),)
    os.makedirs(target, exist_ok=True)
    for entry in sorted(os.scandir(source), key=lambda e: e.name):
        if entry.name in NOT_COPIED:
            continue
        destination = os.path.join(target, entry.name)
        if entry.is_symlink():
            _copy_link(entry.path, destination, copy, ancestors)
        elif entry.is_dir(follow_symlinks=False):
            _copy_tree(entry.path, destination, copy, ancestors)
        elif entry.is_file(follow_symlinks=False):
            shutil.copy2(entry.path, destination)


def _copy_link(link, destination, copy, ancestors):
    real = os.path.realpath(link)
    shown = '%s -> %s' % (_relative(link, copy.shown_top), os.readlink(link))
    if not _inside(real, copy.top):
        copy.left_out.append('%s (points outside the submission)' % shown)
    elif not os.path.exists(real):
        copy.left_out.append('%s (points nowhere)' % shown)
    elif os.path.isdir(real):
        if any(_inside(folder, real) for folder in ancestors):
            copy.left_out.append('%s (loops back to a folder above it)' % shown)
        else:
            _copy_tree(real, destination, copy, ancestors)
    elif os.path.isfile(real):
        shutil.copy2(real, destination)
    else:
        copy.left_out.append('%s (not a file)' % shown)


# -- what ball_chaser.launch starts -------------------------------------------------------

SUBSTITUTION = re.compile(r'\$\((\w+)((?:\s[^)]*)?)\)')
MAX_INCLUDE_DEPTH = 10
# Launch files read in all while following includes: a file that includes many others, each
# including many, would be read without end within the depth alone.
MAX_INCLUDE_READS = 64


class _Unresolved(Exception):
    """A value that cannot be known without running roslaunch (an environment variable, a
    Python expression, a package from elsewhere)."""


def include_chain(top, launch_file, target, packages):
    """[launch_file, ..., target] when launch_file includes target, directly or through other
    includes; [] when it does not, or when that cannot be told without running anything.

    Includes are followed as roslaunch follows them, as far as a reading of the
    files can: $(find PKG) of packages ({name: folder}), $(dirname), $(arg
    NAME) with the defaults and values the files give, and if/unless that come
    to true, false, 1 or 0. An include that needs more is not followed.

    The files are the submission's, read as data: only those inside top (the
    grader's copy), without following a link, each of at most
    LAUNCH_READ_LIMIT bytes, MAX_INCLUDE_READS in all; a file that declares
    XML entities (which could expand without bound) is not read.
    """
    reads = [MAX_INCLUDE_READS]
    return _include_chain(top, os.path.normpath(launch_file), os.path.normpath(target), packages,
                          {}, (), reads)


def read_launch(top, path, reads=None, limit=LAUNCH_READ_LIMIT, errors=False):
    """The root element of the XML file top/path (path inside top), read as data; None when
    it cannot be read so (see include_chain), or with errors, why not."""
    relative = os.path.relpath(path, top)
    if relative == '..' or relative.startswith('../') or (reads is not None and reads[0] <= 0):
        return 'outside the folder read, or past the files read' if errors else None
    if reads is not None:
        reads[0] -= 1
    try:
        text = read_beneath(top, relative, limit + 1)
        if len(text) > limit:
            raise ValueError('larger than %d bytes' % limit)
        root = defused_ET.fromstring(text, forbid_dtd=False, forbid_entities=True,
                                     forbid_external=True)
        if element_depth(root) > LAUNCH_MAX_DEPTH:
            raise ValueError('its elements are nested deeper than %d levels' % LAUNCH_MAX_DEPTH)
        return root
    except OSError as error:
        why = error.strerror or error
    except (ValueError, ET.ParseError, DefusedXmlException) as error:
        why = error
    return str(why) if errors else None


def _include_chain(top, path, target, packages, args, seen, reads):
    if path == target:
        return [path]
    if path in seen or len(seen) >= MAX_INCLUDE_DEPTH:
        return []
    root = read_launch(top, path, reads)
    if root is None:
        return []
    scope = _LaunchScope(args, packages, os.path.dirname(path))
    for include in scope.includes(root):
        try:
            included = os.path.normpath(scope.resolve(include.get('file', '')))
        except _Unresolved:
            continue
        passed = dict(scope.args) if include.get('pass_all_args', '').lower() in ('true', '1') else {}
        for arg in include:
            if arg.tag == 'arg' and arg.get('name') and scope.active(arg):
                passed[arg.get('name')] = scope.resolve_or_none(arg.get('value', arg.get('default')))
        chain = _include_chain(top, included, target, packages, passed, seen + (path,), reads)
        if chain:
            return [path] + chain
    return []


class _LaunchScope:
    """The args of one launch file, as roslaunch reads them in document order."""

    def __init__(self, args, packages, folder):
        self.args = dict(args)          # name -> value; None when it cannot be known
        self.packages = packages
        self.folder = folder

    def resolve(self, text):
        def substitute(match):
            kind, rest = match.group(1), match.group(2).strip()
            if kind == 'find' and rest in self.packages:
                return self.packages[rest]
            if kind == 'dirname':
                return self.folder
            if kind == 'arg' and self.args.get(rest) is not None:
                return self.args[rest]
            raise _Unresolved(match.group(0))
        if text is None:
            raise _Unresolved('no value')
        return SUBSTITUTION.sub(substitute, text)

    def resolve_or_none(self, text):
        try:
            return self.resolve(text)
        except _Unresolved:
            return None

    def active(self, element):
        """False for an element whose if/unless is false, or cannot be known."""
        for attribute, wanted in (('if', True), ('unless', False)):
            if element.get(attribute) is None:
                continue
            value = (self.resolve_or_none(element.get(attribute)) or '').strip().lower()
            if value not in ('true', '1', 'false', '0') or (value in ('true', '1')) != wanted:
                return False
        return True

    def includes(self, element):
        """The <include>s that roslaunch would follow, declaring <arg>s on the way."""
        for child in element:
            if not self.active(child):
                continue
            if child.tag == 'arg' and child.get('name'):
                name = child.get('name')
                if 'value' in child.attrib:
                    self.args[name] = self.resolve_or_none(child.get('value'))
                elif name not in self.args:
                    self.args[name] = self.resolve_or_none(child.get('default'))
            elif child.tag == 'group':
                yield from self.includes(child)
            elif child.tag == 'include':
                yield child


def chaser_launch_includes_world(submission, src):
    """The include chain from ball_chaser.launch to the robot's world.launch, as paths relative
    to the submission; [] when ball_chaser.launch does not start the world itself.

    src: the grader's copy of the submission's packages (copy_packages), one folder per
    package; what is read is that copy, as data (include_chain), never the submission itself.
    """
    if submission.robot is None or submission.chaser is None:
        return []
    copies = {name: os.path.join(src, name) for name in submission.needed()}
    chain = include_chain(src, launch_path(copies[submission.chaser.name], CHASER_LAUNCH),
                          launch_path(copies[submission.robot.name], ROBOT_LAUNCH), copies)
    return [_in_submission(path, submission, copies) for path in chain]


def _in_submission(path, submission, copies):
    """The path in the submission of a file of the grader's copy."""
    for name, copy in copies.items():
        if _inside(path, copy):
            return os.path.normpath(os.path.join(_relative(submission.packages[name].path, submission.path),
                                                 _relative(path, copy)))
    return path
