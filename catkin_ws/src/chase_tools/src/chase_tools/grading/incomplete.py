"""What a submission that the grader cannot build is: ROS 2 packages, ball_chaser without a
robot package, a robot package without ball_chaser, other ROS packages, or nothing of ROS.

The grader builds a ROS 1 (catkin) workspace: a robot package (the one with
world.launch) beside ball_chaser (grading/submission.py). A folder that does
not hold both, or holds them as ROS 2 (ament) packages, is named by what it
holds, in the words of the `builds` item. A folder of ROS 2 packages is not
judged (the grader cannot run it; that says nothing of the student's work);
the others fail the build, for what is missing was seen. Pure: no ROS.
"""
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass

from chase_tools.grading import submission
from chase_tools.grading.rubric import NOT_JUDGED
from chase_tools.grading.scratch import read_beneath

# ROS 2's build tools: a package.xml's <buildtool_depend> or <export><build_type>.
AMENT_TOOLS = ('ament_cmake', 'ament_python', 'ament_cmake_python', 'ament_cmake_auto')
# The files of an ament_python package that name ament (its data_files install the package's
# marker into share/ament_index).
PYTHON_SETUP_FILES = ('setup.py', 'setup.cfg')
SETUP_READ_LIMIT = 1 << 20
SHOWN = 4
ROS2 = ('ROS 2 packages (ament): this grader runs ROS 1 (catkin) submissions')
NO_ROBOT = ('%s but no robot package (no package with %s/%s)'
            % (submission.CHASER, submission.COURSE_LAUNCH_FOLDER, submission.ROBOT_LAUNCH))
NO_CHASER = 'a robot package but no %s' % submission.CHASER
NEITHER = ('ROS packages, but neither %s nor a robot package (no package with %s/%s)'
           % (submission.CHASER, submission.COURSE_LAUNCH_FOLDER, submission.ROBOT_LAUNCH))
NOTHING = 'nothing of ROS: no package (no package.xml) in the folder'


@dataclass
class Unbuildable:
    """Why a submission is not built: the builds item's evidence, and whether that is a verdict
    (False: not judged)."""
    evidence: str
    judged: bool


def is_ament(package_path):
    """True when the package is a ROS 2 one: its package.xml builds with ament, or its
    setup.py or setup.cfg names ament. Read as data: no link followed, the size bounded."""
    real = os.path.realpath(package_path)
    root = submission.read_launch(real, os.path.join(real, 'package.xml'),
                                  limit=submission.PACKAGE_READ_LIMIT)
    if isinstance(root, ET.Element):
        tools = [(element.text or '').strip() for element in root.iter('buildtool_depend')]
        tools += [(element.text or '').strip() for element in root.iter('build_type')]
        if any(tool in AMENT_TOOLS for tool in tools):
            return True
    for name in PYTHON_SETUP_FILES:
        try:
            text = read_beneath(real, name, SETUP_READ_LIMIT)
        except OSError:
            continue
        if b'ament' in text:
            return True
    return False


def _names(packages):
    names = sorted(package.name for package in packages)
    shown = ', '.join(names[:SHOWN])
    return shown + (' and %d more' % (len(names) - SHOWN) if len(names) > SHOWN else '')


def what_it_is(found):
    """Unbuildable, naming what the Submission found holds, or None when the grader can build
    it (a catkin robot package beside ball_chaser)."""
    every, read_problems = submission.read_packages(found.path)
    if found.robot is not None and found.chaser is not None:
        ament = [package for package in (found.robot, found.chaser) if is_ament(package.path)]
        if not ament:
            return None
        return Unbuildable('%s%s (%s)' % (NOT_JUDGED, ROS2, _names(ament)), False)
    ament = [package for package in every if is_ament(package.path)]
    problems = ''.join('; %s' % problem for problem in read_problems)
    if ament:
        return Unbuildable('%s%s (%s)%s' % (NOT_JUDGED, ROS2, _names(ament), problems), False)
    if found.chaser is not None:
        return Unbuildable('not built: %s%s' % (NO_ROBOT, problems), True)
    if found.robot is not None:
        return Unbuildable('not built: %s (%s)%s' % (NO_CHASER, found.robot.name, problems), True)
    if every:
        return Unbuildable('not built: %s (%s)%s' % (NEITHER, _names(every), problems), True)
    if read_problems:
        return Unbuildable('not built: no package could be read: %s' % '; '.join(read_problems),
                           True)
    return Unbuildable('not built: %s' % NOTHING, True)
