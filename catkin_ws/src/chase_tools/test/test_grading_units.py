"""The grader's pure parts: finding a submission's packages, preparing its launch files,
reading build logs, the report and its JSON, and the sandbox's command line. No master."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
import time
import xml.etree.ElementTree as ET

import pytest

from chase_tools.grading import (headless_launch, incomplete, overlay, rubric, sandbox, submission,
                                 worldcopy, worlds)
from flatsim.loading.sdf_world import load_world

HERE = os.path.dirname(os.path.abspath(__file__))
TOP = os.path.realpath(os.path.join(HERE, '..', '..', '..', '..'))     # this workspace's checkout
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import variants  # noqa: E402


# -- build logs ----------------------------------------------------------------------------

GCC_NO_NOTE = """\
/ws/src/ball_chaser/src/process_image.cpp: In function 'void process_image_callback(sensor_msgs::Image)':
/ws/src/ball_chaser/src/process_image.cpp:31:24: error: 'accumulate' is not a member of 'std'
   31 |     long column = std::accumulate(columns.begin(), columns.end(), 0L);
make[2]: *** [ball_chaser/CMakeFiles/process_image.dir/build.make:76: process_image.cpp.o] Error 1
"""
GCC_WITH_NOTE = """\
a.cpp:3:8: error: 'string' in namespace 'std' does not name a type
a.cpp:1:1: note: 'std::string' is defined in header '<string>'; did you forget to '#include <string>'?
b.cpp:9:5: error: 'numeric_limits' was not declared in this scope
"""


def test_missing_headers_come_from_the_compilers_notes_and_the_known_names():
    assert overlay.missing_headers(GCC_NO_NOTE) == {'numeric': ['accumulate']}
    assert overlay.missing_headers(GCC_WITH_NOTE) == {'limits': ['numeric_limits'],
                                                      'string': ['string']}


def test_an_unknown_name_is_not_taken_for_a_missing_header():
    assert overlay.missing_headers("x.cpp:1:1: error: 'drive_robt' was not declared in this scope") == {}


MESSAGES_FAILED = """\
make[3]: *** [ball_chaser/CMakeFiles/boom.dir/build.make:70: ball_chaser/CMakeFiles/boom] Error 1
make[2]: *** [CMakeFiles/Makefile2:716: ball_chaser/CMakeFiles/boom.dir/all] Error 2
make[1]: *** [CMakeFiles/Makefile2:511: ball_chaser/CMakeFiles/ball_chaser_generate_messages.dir/rule] Error 2
make: *** [Makefile:361: ball_chaser_generate_messages] Error 2
"""


def test_the_goal_that_failed_is_the_top_level_makes():
    assert overlay.failed_goal(MESSAGES_FAILED) == 'ball_chaser_generate_messages'
    assert overlay.failed_goal(GCC_NO_NOTE) is None


def test_error_lines_keep_the_first_of_each():
    lines = overlay.error_lines(GCC_NO_NOTE + GCC_NO_NOTE)
    assert lines[0].endswith("error: 'accumulate' is not a member of 'std'")
    assert len(lines) == 2


# -- finding the packages ------------------------------------------------------------------

def test_a_workspace_a_src_folder_and_a_repository_give_the_same_packages(tmp_path):
    variants.compose('py_correct', tmp_path / 'repo' / 'src')
    (tmp_path / 'repo' / 'src' / 'build').mkdir()
    (tmp_path / 'repo' / 'src' / 'build' / 'package.xml').write_text('<package/>')
    for top in (tmp_path / 'repo', tmp_path / 'repo' / 'src', tmp_path / 'repo' / 'src' / 'py_correct'):
        found = submission.find(str(top))
        assert found.robot.name == 'my_robot' and found.chaser.name == 'ball_chaser', top
        assert found.needed() == ['ball_chaser', 'my_robot']
        assert found.problems == []


def test_a_robot_package_of_another_name_is_found_by_its_world_launch(tmp_path):
    path = variants.compose('py_correct', tmp_path)
    os.rename(os.path.join(path, 'my_robot'), os.path.join(path, 'robot'))
    xml = os.path.join(path, 'robot', 'package.xml')
    with open(xml) as stream:
        text = stream.read().replace('<name>my_robot</name>', '<name>myrobot</name>')
    with open(xml, 'w') as stream:
        stream.write(text)
    assert submission.find(path).robot.name == 'myrobot'


def test_a_package_xml_that_links_out_of_the_submission_is_not_read(tmp_path):
    """The grader (root) would otherwise read what the link names: here a package.xml of a
    name no package of the submission has."""
    outside = tmp_path / 'outside.xml'
    outside.write_text('<package format="3"><name>read_through_a_link</name></package>')
    path = variants.compose('py_correct', tmp_path / 'submission')
    os.remove(os.path.join(path, 'my_robot', 'package.xml'))
    os.symlink(str(outside), os.path.join(path, 'my_robot', 'package.xml'))
    found = submission.find(path)
    assert sorted(found.packages) == ['ball_chaser']
    assert '%s/package.xml cannot be read: Too many levels of symbolic links' % os.path.join(
        path, 'my_robot') in found.problems, found.problems


def test_a_missing_ball_chaser_is_a_problem_not_an_error(tmp_path):
    path = variants.compose('py_correct', tmp_path)
    (tmp_path / 'py_correct' / 'ball_chaser' / 'CATKIN_IGNORE').write_text('')
    found = submission.find(path)
    assert found.chaser is None
    assert any('no package named ball_chaser' in problem for problem in found.problems)


def test_a_folder_of_ros2_packages_is_named_so_and_not_judged(tmp_path):
    found = submission.find(variants.compose('ros2_packages', tmp_path))
    unbuildable = incomplete.what_it_is(found)
    assert unbuildable.evidence == ('not judged: ROS 2 packages (ament): this grader runs ROS 1 '
                                    '(catkin) submissions (ball_chaser, my_robot)')
    assert not unbuildable.judged


def test_ros2_packages_with_the_courses_launch_files_are_ros2_all_the_same(tmp_path):
    """ROS 2 reads XML launch files too: a world.launch does not make an ament package catkin's."""
    path = variants.compose('ros2_packages', tmp_path)
    with open(os.path.join(path, 'my_robot', 'launch', 'world.launch'), 'w') as stream:
        stream.write('<launch/>\n')
    found = submission.find(path)
    assert (found.robot.name, found.chaser.name) == ('my_robot', 'ball_chaser')
    assert incomplete.what_it_is(found).evidence.startswith('not judged: ROS 2 packages (ament)')


def test_an_ament_python_package_is_told_by_its_setup_py_alone(tmp_path):
    package = tmp_path / 'ball_chaser'
    package.mkdir()
    (package / 'package.xml').write_text('<package format="3"><name>ball_chaser</name></package>')
    assert not incomplete.is_ament(str(package))
    (package / 'setup.py').write_text("data_files=[('share/ament_index/resource_index/packages', [])]")
    assert incomplete.is_ament(str(package))


def test_ball_chaser_without_a_robot_package_is_named_so(tmp_path):
    found = submission.find(variants.compose('py_chaser_only', tmp_path))
    unbuildable = incomplete.what_it_is(found)
    assert unbuildable.evidence == ('not built: ball_chaser but no robot package (no package with '
                                    'launch/world.launch)')
    assert unbuildable.judged


def test_a_robot_package_without_ball_chaser_is_named_so(tmp_path):
    path = variants.compose('py_correct', tmp_path)
    shutil.rmtree(os.path.join(path, 'ball_chaser'))
    unbuildable = incomplete.what_it_is(submission.find(path))
    assert unbuildable.evidence == 'not built: a robot package but no ball_chaser (my_robot)'
    assert unbuildable.judged


def test_a_folder_with_nothing_of_ros_is_named_so(tmp_path):
    (tmp_path / 'README.md').write_text('# Go Chase It\n')
    (tmp_path / 'scripts').mkdir()
    (tmp_path / 'scripts' / 'chase.py').write_text('print("chase")\n')
    unbuildable = incomplete.what_it_is(submission.find(str(tmp_path)))
    assert unbuildable.evidence == 'not built: nothing of ROS: no package (no package.xml) in the folder'
    # Other packages, but neither of the course's.
    shutil.copytree(os.path.join(variants.BASE, 'ball_chaser_py'), str(tmp_path / 'teleop'))
    xml = tmp_path / 'teleop' / 'package.xml'
    xml.write_text(xml.read_text().replace('<name>ball_chaser</name>', '<name>teleop</name>'))
    assert incomplete.what_it_is(submission.find(str(tmp_path))).evidence == (
        'not built: ROS packages, but neither ball_chaser nor a robot package (no package with '
        'launch/world.launch) (teleop)')


def test_a_whole_catkin_submission_is_built(tmp_path):
    assert incomplete.what_it_is(submission.find(variants.compose('py_correct', tmp_path))) is None


def test_a_folder_of_submissions_is_told_from_one_submission(tmp_path):
    for name in ('py_correct', 'cpp_correct'):
        variants.compose(name, tmp_path)
    # A folder without packages does not make it less of a class, and is graded (and fails).
    (tmp_path / 'nothing_pushed').mkdir()
    assert submission.submissions_in(str(tmp_path)) == [
        str(tmp_path / name) for name in ('cpp_correct', 'nothing_pushed', 'py_correct')]
    assert submission.submissions_in(str(tmp_path / 'py_correct')) == [str(tmp_path / 'py_correct')]


def test_a_folder_with_an_incomplete_subfolder_is_a_class_only_when_asked(tmp_path):
    for name in ('py_correct', 'cpp_correct'):
        variants.compose(name, tmp_path)
    shutil.rmtree(tmp_path / 'cpp_correct' / 'ball_chaser')
    assert submission.submissions_in(str(tmp_path)) == [str(tmp_path)]
    assert submission.complete_subfolders(str(tmp_path)) == [str(tmp_path / 'py_correct')]
    assert submission.submissions_in(str(tmp_path), whole_class=True) == [
        str(tmp_path / 'cpp_correct'), str(tmp_path / 'py_correct')]


def test_a_repository_with_stray_copies_is_one_submission_graded_in_its_subfolder(tmp_path):
    repo = variants.compose('py_repository', tmp_path)
    assert submission.submissions_in(repo) == [repo]
    found = submission.find(repo)
    assert found.folder == 'Project 2'
    assert found.robot.path == os.path.join(repo, 'Project 2', 'my_robot')
    assert found.chaser.path == os.path.join(repo, 'Project 2', 'ball_chaser')
    assert found.ignored == [os.path.join('Project 1', 'my_robot'), os.path.join('backup', 'ball_chaser')]
    assert found.needed() == ['ball_chaser', 'my_robot']
    assert found.problems == [] and found.choices == []
    # Beside the others, it is a whole submission, so a folder of them is still a class.
    variants.compose('py_correct', tmp_path)
    assert submission.submissions_in(str(tmp_path)) == [str(tmp_path / 'py_correct'), repo]


def _package(path, name, depends=(), world=False):
    os.makedirs(os.path.join(path, 'launch'))
    with open(os.path.join(path, 'package.xml'), 'w') as stream:
        stream.write('<package><name>%s</name>%s</package>'
                     % (name, ''.join('<depend>%s</depend>' % d for d in depends)))
    if world:
        with open(os.path.join(path, 'launch', 'world.launch'), 'w') as stream:
            stream.write('<launch/>')


def test_the_robot_package_and_ball_chaser_nearest_each_other_are_graded(tmp_path):
    _package(str(tmp_path / 'ws' / 'src' / 'robot'), 'robot', world=True)
    _package(str(tmp_path / 'ws' / 'src' / 'ball_chaser'), 'ball_chaser', depends=['robot_msgs'])
    _package(str(tmp_path / 'ws' / 'src' / 'old' / 'ball_chaser'), 'ball_chaser')
    _package(str(tmp_path / 'a_copy' / 'src' / 'my_robot'), 'my_robot', world=True)
    _package(str(tmp_path / 'msgs' / 'robot_msgs'), 'robot_msgs')
    found = submission.find(str(tmp_path))
    assert (found.folder, found.robot.name) == (os.path.join('ws', 'src'), 'robot')
    assert found.chaser.path == str(tmp_path / 'ws' / 'src' / 'ball_chaser')
    # A package it depends on comes from wherever it is; the rest outside is left.
    assert found.needed() == ['ball_chaser', 'robot', 'robot_msgs']
    assert found.choices == ['robot_msgs taken from %s, outside %s'
                             % (os.path.join('msgs', 'robot_msgs'), os.path.join('ws', 'src'))]
    assert found.ignored == [os.path.join('a_copy', 'src', 'my_robot'),
                             os.path.join('ws', 'src', 'old', 'ball_chaser')]
    assert found.problems == ['two packages named ball_chaser: %s and %s; using the first'
                              % (tmp_path / 'ws' / 'src' / 'ball_chaser',
                                 tmp_path / 'ws' / 'src' / 'old' / 'ball_chaser')]


def test_two_whole_submissions_in_one_repository_are_a_choice_that_is_reported(tmp_path):
    for folder in ('b_final', 'a_draft'):
        _package(str(tmp_path / folder / 'my_robot'), 'my_robot', world=True)
        _package(str(tmp_path / folder / 'ball_chaser'), 'ball_chaser')
    _package(str(tmp_path / 'deep' / 'src' / 'my_robot'), 'my_robot', world=True)
    _package(str(tmp_path / 'deep' / 'src' / 'x' / 'ball_chaser'), 'ball_chaser')
    for _attempt in range(2):                  # the same choice every time
        found = submission.find(str(tmp_path))
        assert found.folder == 'a_draft'
        assert found.choices == ['graded a_draft; b_final also holds a robot package beside a '
                                 'ball_chaser; the grader takes the folder nearest the top, then '
                                 'the first by name']
        assert found.ignored == [os.path.join('b_final', 'ball_chaser'), os.path.join('b_final', 'my_robot'),
                                 os.path.join('deep', 'src', 'my_robot'),
                                 os.path.join('deep', 'src', 'x', 'ball_chaser')]


def test_only_the_needed_packages_are_copied(tmp_path):
    path = variants.compose('py_correct', tmp_path / 'sub')
    extra = tmp_path / 'sub' / 'py_correct' / 'teleop_gui'
    extra.mkdir()
    (extra / 'package.xml').write_text('<package><name>teleop_gui</name></package>')
    copied, left_out = submission.copy_packages(submission.find(path), str(tmp_path / 'ws'))
    assert sorted(copied) == ['ball_chaser', 'my_robot'] and left_out == []
    assert os.access(tmp_path / 'ws' / 'ball_chaser' / 'scripts' / 'drive_bot.py', os.X_OK)


def test_launch_files_are_found_anywhere_in_their_package_as_roslaunch_finds_them(tmp_path):
    path = variants.compose('py_world_launch_in_worlds', tmp_path)
    found = submission.find(path)
    assert found.robot is not None and found.robot.name == 'my_robot'
    assert submission.find_launch(found.robot.path, 'world.launch') == ['worlds/world.launch']
    assert submission.launch_path(found.robot.path, 'world.launch') == \
        os.path.join(found.robot.path, 'worlds', 'world.launch')
    assert found.choices == ['my_robot/worlds/world.launch lies outside launch/, where the course '
                             'keeps it; roslaunch finds it there all the same']
    # A dot folder is not searched, as roslaunch prunes them.
    os.makedirs(os.path.join(found.chaser.path, '.old'))
    os.rename(os.path.join(found.chaser.path, 'launch', 'ball_chaser.launch'),
              os.path.join(found.chaser.path, '.old', 'ball_chaser.launch'))
    assert submission.find_launch(found.chaser.path, 'ball_chaser.launch') == []


def test_two_files_of_one_launch_name_in_a_package_are_named_as_roslaunch_refuses_them(tmp_path):
    path = variants.compose('py_correct', tmp_path)
    robot = os.path.join(path, 'my_robot')
    shutil.copy(os.path.join(robot, 'launch', 'world.launch'), os.path.join(robot, 'worlds'))
    assert submission.find(path).choices == [
        'my_robot holds 2 files named world.launch (launch/world.launch, worlds/world.launch): '
        '`roslaunch my_robot world.launch` refuses to choose between them']


@pytest.mark.parametrize('name', ['../../etc/cron.d', '/etc/cron.d', '..', 'a/b', 'My_Robot',
                                  '1robot', 'my-robot', 'my robot', '_robot'])
def test_a_package_name_outside_rep_144_refuses_the_package(tmp_path, name):
    _package(str(tmp_path / 'p'), name)
    folder = str(tmp_path / 'p')
    with pytest.raises(ValueError, match=r'the package is refused: its <name> .* is not a ROS package '
                                         r'name \(REP 144'):
        submission.read_package(folder)


def test_a_dependency_outside_rep_144_is_a_rosdep_key_never_a_package_to_follow(tmp_path):
    _package(str(tmp_path / 'p'), 'my_robot', ['python3-numpy', '../../../etc/cron.d', 'rospy'])
    folder = str(tmp_path / 'p')
    assert submission.read_package(folder).depends == ['rospy']


def test_a_refused_package_is_named_among_the_problems_and_left_out(tmp_path):
    path = variants.compose('py_correct', tmp_path / 'sub')
    _package(os.path.join(path, 'helper'), '../' * 30 + str(tmp_path / 'escaped'))
    found = submission.find(path)
    assert any('the package is refused' in problem for problem in found.problems), found.problems
    assert sorted(found.packages) == ['ball_chaser', 'my_robot']


@pytest.mark.parametrize('name', ['../escaped', '/tmp/escaped', 'a/b', '..', ''])
def test_a_copy_target_outside_the_workspace_is_refused(tmp_path, name):
    with pytest.raises(ValueError):
        submission.copy_target(str(tmp_path / 'src'), name)


def test_a_copy_target_through_a_link_in_src_is_refused(tmp_path):
    (tmp_path / 'src').mkdir()
    (tmp_path / 'elsewhere').mkdir()
    os.symlink(str(tmp_path / 'elsewhere'), str(tmp_path / 'src' / 'my_robot'))
    with pytest.raises(ValueError, match='would not lie in'):
        submission.copy_target(str(tmp_path / 'src'), 'my_robot')
    assert submission.copy_target(str(tmp_path / 'src'), 'ball_chaser') == \
        os.path.join(os.path.realpath(str(tmp_path / 'src')), 'ball_chaser')


def test_copy_packages_never_writes_outside_src_whatever_the_name(tmp_path):
    path = variants.compose('py_correct', tmp_path / 'sub')
    found = submission.find(path)
    found.packages['my_robot'].name = '../escaped'
    found.packages['../escaped'] = found.packages.pop('my_robot')
    found.robot = found.packages['../escaped']
    with pytest.raises(ValueError):
        submission.copy_packages(found, str(tmp_path / 'ws' / 'src'))
    assert not os.path.exists(tmp_path / 'ws' / 'escaped')


def test_links_out_of_the_submission_are_left_out_of_the_copy_and_named(tmp_path):
    path = variants.compose('py_stray_link', tmp_path / 'sub')
    robot = tmp_path / 'sub' / 'py_stray_link' / 'my_robot'
    (tmp_path / 'sub' / 'py_stray_link' / 'shared.world').write_text('<sdf/>')
    os.symlink('office.world', robot / 'worlds' / 'same.world')                   # within the package
    os.symlink('../../shared.world', robot / 'worlds' / 'shared.world')           # elsewhere inside
    os.symlink('../ball_chaser/launch', robot / 'chaser_launch')                  # a folder inside
    os.symlink('../..', robot / 'worlds' / 'up')                                   # a loop
    os.symlink('no_such.world', robot / 'gone')
    copied, left_out = submission.copy_packages(submission.find(path), str(tmp_path / 'ws'))
    assert left_out == [
        'my_robot/gone -> no_such.world (points nowhere)',
        'my_robot/upstream -> %s (points outside the submission)' % variants.OUTSIDE_ROBOT,
        'my_robot/worlds/up -> ../.. (loops back to a folder above it)']
    copy = tmp_path / 'ws' / 'my_robot'
    assert not os.path.lexists(copy / 'upstream') and not os.path.lexists(copy / 'gone')
    assert (copy / 'worlds' / 'same.world').read_text() == (robot / 'worlds' / 'office.world').read_text()
    assert (copy / 'worlds' / 'shared.world').read_text() == '<sdf/>'
    assert (copy / 'chaser_launch' / 'ball_chaser.launch').is_file()
    # Links inside are copied as what they point to: the copy holds none.
    for root, dirs, files in os.walk(copied['my_robot']):
        assert not any(os.path.islink(os.path.join(root, name)) for name in dirs + files)


# -- what ball_chaser.launch starts ---------------------------------------------------------------

def _launch(path, body):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w') as stream:
        stream.write('<launch>\n%s\n</launch>\n' % body)


INCLUDED_THROUGH_ANOTHER_FILE = """
  <arg name="world" default="true"/>
  <arg name="robot_pkg" default="$(find my_robot)"/>
  <group if="$(arg world)">
    <include file="$(dirname)/all.launch" pass_all_args="true"/>
  </group>"""
ALL_LAUNCH = """
  <arg name="robot_pkg"/>
  <include file="$(arg robot_pkg)/launch/world.launch"/>"""


def _includes_world(found, tmp_path):
    """chaser_launch_includes_world on a fresh copy of the submission, as the grader builds it."""
    src = tempfile.mkdtemp(dir=str(tmp_path), prefix='src_')
    submission.copy_packages(found, src)
    return submission.chaser_launch_includes_world(found, src)


def test_a_ball_chaser_launch_that_includes_world_launch_is_seen_through_other_files(tmp_path):
    path = variants.compose('py_chaser_includes_world', tmp_path)
    found = submission.find(path)
    assert _includes_world(found, tmp_path) == [
        os.path.join('ball_chaser', 'launch', 'ball_chaser.launch'),
        os.path.join('my_robot', 'launch', 'world.launch')]
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'),
            INCLUDED_THROUGH_ANOTHER_FILE)
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'all.launch'), ALL_LAUNCH)
    assert _includes_world(found, tmp_path) == [
        os.path.join('ball_chaser', 'launch', 'ball_chaser.launch'),
        os.path.join('ball_chaser', 'launch', 'all.launch'),
        os.path.join('my_robot', 'launch', 'world.launch')]


def test_the_include_chain_is_named_by_its_place_in_a_repository(tmp_path):
    path = variants.compose('py_repository', tmp_path)
    _launch(os.path.join(path, 'Project 2', 'ball_chaser', 'launch', 'ball_chaser.launch'),
            '<include file="$(find my_robot)/launch/world.launch"/>')
    assert _includes_world(submission.find(path), tmp_path) == [
        os.path.join('Project 2', 'ball_chaser', 'launch', 'ball_chaser.launch'),
        os.path.join('Project 2', 'my_robot', 'launch', 'world.launch')]


WORLD_INCLUDE = '<include file="$(find my_robot)/launch/world.launch"/>'
BOMB = ('<?xml version="1.0"?>\n<!DOCTYPE launch [\n<!ENTITY a "aaaaaaaaaa">\n'
        + ''.join('<!ENTITY %s "&%s;&%s;&%s;&%s;&%s;&%s;&%s;&%s;&%s;&%s;">\n'
                  % ((chr(ord('a') + level),) + (chr(ord('a') + level - 1),) * 10)
                  for level in range(1, 9))
        + ']>\n<launch>%s<arg name="x" default="&i;"/></launch>\n' % WORLD_INCLUDE)


def test_the_includes_are_read_from_the_graders_copy_never_from_the_submission(tmp_path):
    """The grader (root) reads the copy it built from, without links; a change to the
    submission after the copy, such as a launch file that now includes world.launch, is unseen."""
    path = variants.compose('py_correct', tmp_path)
    found = submission.find(path)
    src = str(tmp_path / 'src')
    submission.copy_packages(found, src)
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'), WORLD_INCLUDE)
    assert submission.chaser_launch_includes_world(found, src) == []
    _launch(os.path.join(src, 'ball_chaser', 'launch', 'ball_chaser.launch'), WORLD_INCLUDE)
    assert len(submission.chaser_launch_includes_world(found, src)) == 2
    # A link in the copy (the build may make one) is not followed.
    target = os.path.join(src, 'ball_chaser', 'launch', 'ball_chaser.launch')
    os.rename(target, str(tmp_path / 'elsewhere.launch'))
    os.symlink(str(tmp_path / 'elsewhere.launch'), target)
    assert submission.chaser_launch_includes_world(found, src) == []


@pytest.mark.parametrize('text', [
    '<!DOCTYPE launch [<!ENTITY world \'%s\'>]><launch>&world;</launch>' % WORLD_INCLUDE,
    BOMB,
    '<launch>%s<!-- %s --></launch>' % (WORLD_INCLUDE, 'x' * submission.LAUNCH_READ_LIMIT),
], ids=['entity', 'billion_laughs', 'too_large'])
def test_a_launch_file_too_large_or_with_entities_is_not_read(tmp_path, text):
    """Each would be followed to world.launch if it were read: an entity that expands to the
    include, a billion laughs (eight levels of ten entities), a file larger than the grader
    reads."""
    path = variants.compose('py_correct', tmp_path)
    with open(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'), 'w') as stream:
        stream.write(text)
    assert _includes_world(submission.find(path), tmp_path) == []


def test_includes_are_read_a_bounded_number_of_times(tmp_path, monkeypatch):
    """Five files, each including the next four times: 1365 reads without a bound on the total
    (and 10 files of 10 within the depth limit would be 10**10)."""
    path = variants.compose('py_correct', tmp_path)
    launch = os.path.join(path, 'ball_chaser', 'launch')
    for level in range(5):
        _launch(os.path.join(launch, 'level%d.launch' % level),
                '<include file="$(dirname)/level%d.launch"/>' % (level + 1) * 4)
    _launch(os.path.join(launch, 'ball_chaser.launch'), '<include file="$(dirname)/level0.launch"/>')
    found = submission.find(path)
    reads = []
    original = submission.read_beneath
    monkeypatch.setattr(submission, 'read_beneath', lambda *args: reads.append(args) or original(*args))
    assert _includes_world(found, tmp_path) == []
    assert len(reads) == submission.MAX_INCLUDE_READS


@pytest.mark.parametrize('body', [
    '',
    '<include file="$(find my_robot)/launch/robot_description.launch"/>',
    '<include if="false" file="$(find my_robot)/launch/world.launch"/>',
    '<arg name="sim" default="false"/><include if="$(arg sim)" file="$(find my_robot)/launch/world.launch"/>',
    '<include unless="$(optenv NO_WORLD 0)" file="$(find my_robot)/launch/world.launch"/>',
    '<include file="$(eval find(\'my_robot\') + \'/launch/world.launch\')"/>',
    '<include file="$(find gazebo_ros)/launch/empty_world.launch"/>',
    '<include file="$(dirname)/ball_chaser.launch"/>',
])
def test_a_ball_chaser_launch_that_does_not_surely_start_the_world_is_launched_after_it(tmp_path, body):
    path = variants.compose('py_correct', tmp_path)
    _launch(os.path.join(path, 'ball_chaser', 'launch', 'ball_chaser.launch'), body)
    assert _includes_world(submission.find(path), tmp_path) == []


# -- launch files ----------------------------------------------------------------------------

LAUNCH = """<launch>
  <node name="drive_bot" type="drive_bot" pkg="ball_chaser" output="screen"/>
  <group if="true">
    <node name="process_image" type="process_image.py" pkg="ball_chaser"/>
  </group>
  <node name="rviz" pkg="rviz" type="rviz" required="true"/>
</launch>
"""


def _prepared(tmp_path, copies='copies', **kwargs):
    launch = tmp_path / 'pkg' / 'launch' / 'ball_chaser.launch'
    if not launch.exists():
        launch.parent.mkdir(parents=True)
        launch.write_text(LAUNCH)
    changes = headless_launch.prepare_launch_files(str(tmp_path / 'pkg'), str(tmp_path / copies), **kwargs)
    assert launch.read_text() == LAUNCH                   # the package itself is never written
    copy = changes.copies.get(str(launch))
    return changes, ET.parse(copy).getroot() if copy else None


def test_gui_nodes_are_left_out_and_process_image_is_remapped(tmp_path):
    changes, root = _prepared(tmp_path, remap=True)
    assert list(changes.copies.values()) == [str(tmp_path / 'copies' / 'launch' / 'ball_chaser.launch')]
    assert changes.dropped == ['rviz (rviz/rviz)']
    assert changes.remapped == ['process_image (ball_chaser/process_image.py)']
    nodes = {node.get('name'): node for node in root.iter('node')}
    assert set(nodes) == {'drive_bot', 'process_image'}
    assert nodes['drive_bot'].find('remap') is None
    remap = nodes['process_image'].find('remap')
    assert (remap.get('from'), remap.get('to')) == (submission.COURSE_SERVICE, submission.PROXY_SERVICE)


def test_preparing_again_starts_from_the_original(tmp_path):
    _prepared(tmp_path, remap=True)
    changes, root = _prepared(tmp_path, copies='again', remap=True, keep=['process_image'])
    assert changes.remapped == []
    assert not list(root.iter('remap'))


def test_a_launch_file_that_links_elsewhere_is_neither_read_nor_written(tmp_path):
    host = tmp_path / 'host.launch'
    host.write_text(LAUNCH)
    (tmp_path / 'pkg' / 'launch').mkdir(parents=True)
    os.symlink(str(host), str(tmp_path / 'pkg' / 'launch' / 'extra.launch'))
    os.symlink(str(tmp_path), str(tmp_path / 'pkg' / 'linked_folder'))
    changes = headless_launch.prepare_launch_files(str(tmp_path / 'pkg'), str(tmp_path / 'copies'))
    assert changes.copies == {} and changes.dropped == []
    assert host.read_text() == LAUNCH


# -- the report ----------------------------------------------------------------------------------

def test_the_json_names_every_item_in_order_even_when_the_run_stopped_early(tmp_path):
    grade = rubric.Grade('/sub', seed=3)
    grade.set('builds', False, 'catkin_make failed', ['  a.cpp:1: error: x'])
    grade.not_run('the build failed')
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    data = json.loads((tmp_path / 'g.json').read_text())
    assert [item['name'] for item in data['items']] == list(rubric.ITEM_NAMES)
    assert set(data['items'][0]) == {'name', 'passed', 'evidence', 'judged'}
    assert data['items'][0]['evidence'] == 'catkin_make failed\n  a.cpp:1: error: x'
    assert data['items'][3]['evidence'] == 'not run: the build failed'
    assert data['success_rate'] == 0.0 and data['trials'] == []
    assert {'builds', 'world_launches', 'sensors', 'drive_bot_service', 'process_image_calls',
            'stops_without_ball', 'chase'} <= {item['name'] for item in data['items']}


def test_the_markdown_has_one_line_per_item_and_the_log_lines_below():
    grade = rubric.Grade('/subs/alice', seed=1, reach=0.15)
    for name in rubric.ITEM_NAMES:
        grade.set(name, name != 'chase', 'evidence of %s' % name)
    grade.set('chase', False, '1 of 2 placements reached', ['  trial 1: sim time stalled'])
    grade.trials = [rubric.Trial(0, [0.0, 0.0, 0.5], [1.0, 1.0], True, 3.2, 0.12, 'trial_00.png',
                                 reason='came within 15 cm of the ball\'s surface'),
                    rubric.Trial(1, [1.0, 0.0, 0.0], [2.0, 0.0], False, None, 1.46, 'trial_01.png',
                                 reason='turned away: the ball left the camera\'s view at 2.1 s')]
    text = rubric.markdown(grade)
    rows = [line for line in text.splitlines() if line.startswith('| `')]
    assert len(rows) == len(rubric.ITEM_NAMES)
    assert '| **FAIL** | 1 of 2 placements reached |' in rows[-1]
    assert 'within 0.15 m of the ball\'s surface' in text
    assert ('| reached in 3.2 s (came within 15 cm of the ball\'s surface) | 0.12 m |' in text)
    assert ('| not reached: turned away: the ball left the camera\'s view at 2.1 s | 1.46 m |' in text)
    assert '![trial 1](trial_01.png)' in text
    assert '```\n  trial 1: sim time stalled\n```' in text
    assert 'Chase success rate: 50% (1 of 2 trials, seed 1)' in text


def test_an_item_that_was_not_observed_is_not_judged_in_the_report_and_the_json(tmp_path):
    grade = rubric.Grade('/subs/alice', seed=1)
    grade.set('builds', True, 'packages ball_chaser, my_robot: catkin_make')
    grade.set('world_launches', False, 'world.launch did not parse')
    grade.not_judged('sensors', 'the simulator was impersonated')
    grade.not_run('an earlier step failed')
    verdicts = {item.name: item.verdict for item in grade.items}
    assert verdicts == {'builds': 'pass', 'world_launches': 'fail', 'sensors': 'not judged',
                        'drive_bot_service': 'not judged', 'process_image_calls': 'not judged',
                        'stops_without_ball': 'not judged', 'chase': 'not judged'}
    text = rubric.markdown(grade)
    assert 'Rubric items (7): 1 passed, 1 failed, 5 not judged.' in text
    rows = {line.split(' | ')[0][3:-1]: line for line in text.splitlines() if line.startswith('| `')}
    assert rows['world_launches'].endswith('| **FAIL** | world.launch did not parse |')
    assert rows['sensors'].endswith('| *NOT JUDGED* | not judged: the simulator was impersonated |')
    assert rows['chase'].endswith('| *NOT JUDGED* | not run: an earlier step failed |')
    assert rubric.NOT_JUDGED_MEANS in text.splitlines()
    # The JSON: passed stays a bool, false when not judged, and judged says which.
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    items = {item['name']: item for item in json.loads((tmp_path / 'g.json').read_text())['items']}
    assert (items['sensors']['passed'], items['sensors']['judged']) == (False, False)
    assert (items['world_launches']['passed'], items['world_launches']['judged']) == (False, True)
    assert (items['builds']['passed'], items['builds']['judged']) == (True, True)


def test_a_world_with_no_placement_shows_its_picture_in_the_report_and_the_json(tmp_path):
    grade = rubric.Grade('/subs/alice', seed=1)
    grade.not_judged('chase', 'no placement could be drawn in this world: refused for: ...')
    grade.world_png = rubric.WORLD_PICTURE
    assert '![the world](world.png)' in rubric.markdown(grade).splitlines()
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    again = rubric.Grade.from_json(json.loads((tmp_path / 'g.json').read_text()))
    assert again.world_png == 'world.png'
    # With trials, their own pictures are shown instead.
    grade.trials = [rubric.Trial(0, [0.0, 0.0, 0.0], [1.0, 0.0], png='trial_00.png')]
    assert '![the world](world.png)' not in rubric.markdown(grade)


def test_a_grade_json_without_judged_reads_the_verdict_from_the_evidence():
    """An older grader's grade.json: an item that did not run was not judged."""
    grade = rubric.Grade.from_json({'items': [
        {'name': 'builds', 'passed': True, 'evidence': 'fine'},
        {'name': 'world_launches', 'passed': False, 'evidence': 'world.launch did not parse'},
        {'name': 'sensors', 'passed': False, 'evidence': 'not run: an earlier step failed'},
        {'name': 'chase', 'passed': False, 'evidence': 'not judged: the models were moved'}]})
    assert [item.verdict for item in grade.items] == ['pass', 'fail', 'not judged', 'not judged']
    # An item with no result at all is not judged either.
    assert grade.verdicts()['not judged'] == ['sensors', 'drive_bot_service', 'process_image_calls',
                                              'stops_without_ball', 'chase']


def test_the_reports_isolation_is_one_short_line_linking_the_teaching_doc():
    grade = rubric.Grade('/subs/alice')
    grade.isolation = ('bubblewrap, as uid 1500000007, a uid of its own (the grader runs as root), '
                       'with no capabilities and no_new_privs; limits for the submission as a whole '
                       '(cgroup): 4 GiB of memory and 512 processes; sees only the system (/usr, /bin, '
                       '/lib, part of /etc), this workspace and its own copy of the submission')
    lines = [line for line in rubric.markdown(grade).splitlines() if 'isolation' in line.lower()]
    assert len(lines) == 1, lines
    (line,) = lines
    assert line.startswith('- isolation: bubblewrap, as uid 1500000007, a uid of its own (the grader '
                           'runs as root), with no capabilities and no_new_privs; ')
    assert 'sees only the system' not in line and '4 GiB' not in line
    link = os.path.join(TOP, 'docs', 'teaching.md') + '#isolation-how-and-what-it-does-not-cover)'
    assert line.endswith(link), line
    # The section it links is there, under the title the anchor is made of.
    with open(os.path.join(TOP, 'docs', 'teaching.md')) as stream:
        assert '### Isolation: how, and what it does not cover\n' in stream.read()


class _CameraMaster:
    def getSystemState(self):  # noqa: N802 - the master's XML-RPC name
        from chase_tools.chase_graph import CAMERA_TOPIC
        return [], [[CAMERA_TOPIC, ['/process_image']]], []


def _checks_after_the_chase(grade):
    """The session's checks of the nodes, as they stand once the chase is over: process_image
    subscribes to the camera and its calls were counted (none came)."""
    from types import SimpleNamespace
    from chase_tools.grading import checks, trials
    session = checks.Checks()
    session.grade = grade
    session.master = _CameraMaster()
    session.chaser_nodes = ['/drive_bot', '/process_image']
    session.found = SimpleNamespace(nodes_before=set(), extra_world_calls=0, trial_calls=0)
    session.counter = SimpleNamespace(calls=trials.RollingLog(10))
    session.chaser_log = ''
    session.excerpt = lambda _log: []
    return session


def test_process_image_calls_is_not_judged_when_no_trial_ran():
    grade = rubric.Grade('/subs/alice')
    grade.not_judged('chase', 'no placement could be drawn in this world: no room of 2 m')
    _checks_after_the_chase(grade).check_process_image()
    item = grade.item('process_image_calls')
    assert item.verdict == 'not judged'
    assert item.evidence == ('not judged: no chase trial ran, so /process_image never saw the ball '
                             '(chase: not judged: no placement could be drawn in this world: no room of 2 m)')
    # Trials that could not run are no more of a sight of the ball.
    grade = rubric.Grade('/subs/alice')
    grade.trials = [rubric.Trial(0, [0, 0, 0], [1, 0], error='world.launch ended during the trial')]
    _checks_after_the_chase(grade).check_process_image()
    assert grade.item('process_image_calls').evidence.endswith(
        '(trial 0: world.launch ended during the trial)')


def test_stops_without_ball_is_not_judged_when_the_robot_never_set_off(monkeypatch):
    """Stopping cannot be seen of a robot that never moved; not moving is the chase's to judge."""
    from types import SimpleNamespace
    from chase_tools.grading import checks, trials
    monkeypatch.setattr(checks.chase_graph, 'SimControl', lambda: SimpleNamespace(pause=lambda: None))
    session = checks.Checks()
    session.grade = rubric.Grade('/subs/alice')
    session.world_up = session.alive = lambda: True
    session.found = SimpleNamespace(placements_drawn=[SimpleNamespace(ball_distance=1.2)])
    session.moves = SimpleNamespace(begin=lambda: None)
    session.start_placement = lambda _sim, _placement: 0.0
    session.cmd = trials.RollingLog(10)          # no command came
    ticks = iter(range(1000))
    session.clock = SimpleNamespace(now=lambda: float(next(ticks)), wait=lambda _seconds, _alive: None)
    session.chaser_log = ''
    session.excerpt = lambda _log: []
    session.check_stop()
    item = session.grade.item('stops_without_ball')
    assert item.verdict == 'not judged'
    assert item.evidence == ('not judged: with the ball 1.2 m ahead the robot was never commanded to '
                             'move in 5 s, so stopping cannot be shown')


def test_process_image_calls_fails_when_a_trial_ran_and_no_call_came():
    grade = rubric.Grade('/subs/alice')
    grade.trials = [rubric.Trial(0, [0, 0, 0], [1, 0], reason='saw the ball but sent no command')]
    _checks_after_the_chase(grade).check_process_image()
    item = grade.item('process_image_calls')
    assert item.verdict == 'fail'
    assert item.evidence.startswith('/process_image subscribes to /camera/rgb/image_raw but never called '
                                    '/ball_chaser/command_robot')


# -- the sandbox ---------------------------------------------------------------------------------

needs_sandbox = pytest.mark.skipif(sandbox.check() is not None, reason='bubblewrap cannot run here')


def test_the_sandbox_shows_a_minimal_tree_and_writes_only_to_its_scratch(tmp_path):
    confinement = sandbox.Confinement(1500000001, 1500000001, True, passwd=str(tmp_path / 'passwd'),
                                      group=str(tmp_path / 'group'))
    cmd = sandbox.Sandbox(str(tmp_path / 'box'), visible=['/home/me/ws'],
                          confinement=confinement).command(['true'])
    text = ' '.join(cmd)
    assert '--ro-bind / /' not in text and '--dev-bind' not in text
    assert '--ro-bind /usr /usr' in text and '--ro-bind /etc/ld.so.cache /etc/ld.so.cache' in text
    assert '/etc/shadow' not in text and '/etc/ssh' not in text and '/etc/sudoers' not in text
    assert '--ro-bind /home ' not in text and '/root' not in text
    assert '--ro-bind %s /etc/passwd' % (tmp_path / 'passwd') in text
    assert '--perms 0755 --dir /home/me' in text       # folders above a bind: enterable
    assert '--ro-bind /home/me/ws /home/me/ws' in text
    assert '--bind %s %s' % (tmp_path / 'box', tmp_path / 'box') in text
    assert '--cap-drop ALL' in text and '--unshare-pid' in text and '--new-session' in text
    assert ('setpriv --reuid 1500000001 --regid 1500000001 --clear-groups --inh-caps=-all '
            '--bounding-set=-all --no-new-privs --') in text
    assert cmd.index('--remount-ro') > cmd.index('--bind')


def test_a_clone_under_tmp_stays_visible_with_the_code_beside_its_bin_folders(tmp_path):
    top = tmp_path / 'clone'
    for folder in ('env/bin', '.venv/bin', 'catkin_ws/src'):
        (top / folder).mkdir(parents=True)
    env = {'PATH': os.pathsep.join([str(top / 'env' / 'bin'), str(top / '.venv' / 'bin'), '/usr/bin']),
           'VIRTUAL_ENV': str(top / '.venv'), 'ROS_PACKAGE_PATH': str(top / 'catkin_ws' / 'src')}
    assert sandbox.environment_paths(env, checkout=str(top)) == sorted(
        os.path.realpath(str(top / folder)) for folder in ('.venv', 'catkin_ws/src', 'env'))


def test_folders_the_environment_names_beside_the_checkout_stay_hidden(tmp_path):
    """A checkout in a home folder, whose PATH and PYTHONPATH also name the owner's own
    folders: only the checkout's and the venv's are shown."""
    home = tmp_path / 'home' / 'teacher'
    top = home / 'proj'
    for folder in ('env/bin', '.venv/bin', 'catkin_ws/src', 'catkin_ws/devel/lib', 'bin'):
        (top / folder).mkdir(parents=True)
    for folder in ('.local/bin', '.local/lib/python3/site-packages', 'lib', 'other/bin', 'notes'):
        (home / folder).mkdir(parents=True)
    env = {'PATH': os.pathsep.join([str(top / 'env' / 'bin'), str(top / '.venv' / 'bin'),
                                    str(top / 'bin'), str(home / '.local' / 'bin'),
                                    str(home / 'other' / 'bin'), '/usr/bin']),
           'VIRTUAL_ENV': str(top / '.venv'), 'ROS_PACKAGE_PATH': str(top / 'catkin_ws' / 'src'),
           'PYTHONPATH': os.pathsep.join([str(home / '.local' / 'lib' / 'python3' / 'site-packages'),
                                          str(home / 'notes')]),
           'LD_LIBRARY_PATH': os.pathsep.join([str(top / 'catkin_ws' / 'devel' / 'lib'), str(home / 'lib')])}
    shown = sandbox.environment_paths(env, checkout=str(top))
    assert shown == sorted(os.path.realpath(str(top / folder))
                           for folder in ('.venv', 'catkin_ws/devel/lib', 'catkin_ws/src', 'env'))
    assert not any(path == os.path.realpath(str(top)) or not path.startswith(os.path.realpath(str(top)))
                   for path in shown)


ENVIRONMENT_PATHS = ('VIRTUAL_ENV', 'CMAKE_PREFIX_PATH', 'ROS_PACKAGE_PATH', 'PYTHONPATH',
                     'LD_LIBRARY_PATH', 'PKG_CONFIG_PATH', 'PATH')


@needs_sandbox
def test_a_checkout_reached_through_a_link_under_a_hidden_folder_is_found_in_the_sandbox(tmp_path):
    """This checkout as the environment names it when it was set up through a link under /tmp,
    which the sandbox hides: without a bind at the link, `rospack find xacro` (roslaunch's
    $(find xacro)) fails with "package 'xacro' not found"."""
    link = tmp_path / 'checkout'
    os.symlink(TOP, str(link))
    env = {name: value.replace(TOP, str(link)) if name in ENVIRONMENT_PATHS else value
           for name, value in os.environ.items()}
    assert env['CMAKE_PREFIX_PATH'].startswith(str(link))
    probe = link / 'catkin_ws' / 'src' / ('grade_probe_%d' % os.getpid())
    box = sandbox.Sandbox(str(tmp_path / 'box'), visible=sandbox.environment_paths(env),
                          confinement=sandbox.Confinement.create(str(tmp_path)))
    box.prepare()
    cmd, outer = box.wrap(['sh', '-c', 'rospack find xacro && touch "$0"', str(probe)], env)
    result = subprocess.run(cmd, env=outer, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, timeout=60, check=False)
    assert result.stdout.splitlines()[0] == str(link / 'catkin_ws' / 'src' / 'gazebo_compat' / 'xacro'), \
        result.stdout
    assert 'Read-only file system' in result.stdout            # shown there read-only, like the rest
    assert not os.path.exists(probe)


PROBE = """\
import os, socket, sys
scratch, secret, sibling, writes = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
print('uid', os.getuid(), os.getgid(), os.getgroups())
open(os.path.join(scratch, 'inside'), 'w').write('x')
for path in writes + ['/var/tmp/grade_probe', '/usr/grade_probe', '/tmp/grade_probe']:
    try:
        open(path, 'w').write('x'); print('wrote', path)
    except OSError as error:
        print('refused', path, error.errno)
for path in ('/etc/shadow', secret, '/root', '/home', '/srv', '/var/lib', sibling,
             os.path.join(sibling, 'key')):
    try:
        print('read', path, open(path).read() if os.path.isfile(path) else os.listdir(path))
    except OSError as error:
        print('unreadable', path, error.errno)
print('beside the checkout', os.listdir(os.path.dirname(sibling)))
try:
    socket.create_connection(('192.0.2.1', 80), timeout=5); print('connected')
except OSError as error:
    print('network', error.errno)
"""


@needs_sandbox
@pytest.mark.skipif(os.geteuid() != 0, reason='a uid of its own needs a grader running as root')
def test_sandboxed_code_runs_as_its_own_uid_and_reads_nothing_private(tmp_path):
    """Fails with a sandbox that keeps uid 0: root-only files and the host tree stay readable.

    A folder beside the checkout (as ~/.ssh lies beside ~/proj), world-readable, must not
    be there, wherever the checkout is cloned."""
    secret_folder = os.path.join(HERE, 'fixtures', 'secret_%d' % os.getpid())
    os.mkdir(secret_folder, 0o755)
    secret = os.path.join(secret_folder, 'secret')
    sibling = os.path.join(os.path.dirname(TOP), '.grade_probe_beside_%d' % os.getpid())
    os.mkdir(sibling, 0o755)
    try:
        with open(os.open(secret, os.O_WRONLY | os.O_CREAT, 0o600), 'w') as stream:
            stream.write('root-only-%d' % os.getpid())
        with open(os.path.join(sibling, 'key'), 'w') as stream:
            stream.write('beside-the-checkout-%d' % os.getpid())
        scratch = tmp_path / 'scratch'
        outside = tmp_path / 'outside'
        confinement = sandbox.Confinement.create(str(tmp_path))
        box = sandbox.Sandbox(str(scratch), visible=sandbox.environment_paths(os.environ) + [secret_folder],
                              own_network=True, confinement=confinement)
        box.prepare()
        cmd, outer = box.wrap([sys.executable, '-c', PROBE, str(scratch), secret, sibling, str(outside),
                               os.path.join(HERE, 'test_grading_units.py')], os.environ)
        result = subprocess.run(cmd, env=outer, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                text=True, timeout=60, check=False)
    finally:
        shutil.rmtree(secret_folder)
        shutil.rmtree(sibling)
    assert 'uid %d %d []' % (confinement.uid, confinement.gid) in result.stdout, result.stdout
    assert confinement.uid >= sandbox.UID_BASE
    assert (scratch / 'inside').read_text() == 'x', result.stdout
    assert (scratch / 'inside').stat().st_uid == confinement.uid
    assert not outside.exists()
    assert result.stdout.count('refused') == 5, result.stdout
    assert 'root-only-' not in result.stdout and 'read /etc/shadow' not in result.stdout
    assert 'beside-the-checkout-' not in result.stdout
    for path in ('/etc/shadow', secret, '/root', '/home', '/srv', '/var/lib', sibling):
        assert 'unreadable %s ' % path in result.stdout, result.stdout
    assert os.path.basename(sibling) not in result.stdout.split('beside the checkout', 1)[1]
    assert 'network 101' in result.stdout, result.stdout        # ENETUNREACH: no route at all


def test_non_finite_or_out_of_range_options_are_refused_with_a_clear_message(tmp_path, capsys):
    from chase_tools.grading import cli
    for option, value, said in (('--timeout', 'nan', "'nan' is not a finite number"),
                                ('--timeout', 'inf', "'inf' is not a finite number"),
                                ('--timeout-build', '-5', '-5 must be more than 0'),
                                ('--reach', 'nan', "'nan' is not a finite number"),
                                ('--pass-rate', 'nan', "'nan' is not a finite number"),
                                ('--pass-rate', '1.5', '1.5 must be at most 1'),
                                ('--memory-limit', 'lots', "'lots' is not a size"),
                                ('--process-limit', '2', '2 must be at least 16'),
                                ('--process-limit', '10000000', '10000000 must be at most 4194304'),
                                ('--open-file-limit', '1e3', "'1e3' is not a whole number"),
                                ('--open-file-limit', '100000000', '100000000 must be at most'),
                                ('--memory-limit', '99999999T', '99999999T is more than the kernel can bound'),
                                ('--seed', '-1', '-1 must be at least 0'),
                                ('--seed', '4294967296', '4294967296 must be at most 2147483647')):
        with pytest.raises(SystemExit) as stop:
            cli.parse_args([str(tmp_path), option, value])
        assert stop.value.code == 2
        assert said in capsys.readouterr().err, (option, value)
    args = cli.parse_args([str(tmp_path), '--memory-limit', '512M', '--timeout-build', '30'])
    assert (args.memory_limit, args.timeout_build) == (512 << 20, 30.0)


def test_a_log_keeps_its_first_and_last_part_and_says_what_was_cut(tmp_path):
    from chase_tools.grading import logcap
    cap = logcap.LogCap(1000)
    for index in range(1000):
        cap.feed(b'line %04d\n' % index)
    text = cap.text()
    assert text.startswith('line 0000\nline 0001')
    assert text.endswith('line 0998\nline 0999\n')
    assert cap.total == 10000 and cap.cut == 9000
    assert '[the grader cut 9000 bytes (8.8 KiB) here' in text
    assert len(text) < 1200
    log = logcap.CappedLog(str(tmp_path / 'node.log'), 1000)
    subprocess.run(['sh', '-c', 'yes flood | head -c 1000000'], stdout=log.fd, check=True)
    log.close()
    written = (tmp_path / 'node.log').read_text()
    assert len(written) < 1200 and 'the grader cut 999000 bytes' in written


def test_a_log_keeps_its_allowance_however_often_its_launch_starts_again(tmp_path):
    """A launch started afresh for each trial appends to its log: the file holds the allowance
    and a cut line for each start, however often it floods."""
    from chase_tools.grading import logcap
    path = str(tmp_path / 'launch.log')
    for start in range(5):
        log = logcap.CappedLog(path, 1000)
        subprocess.run(['sh', '-c', 'echo start %d; yes flood | head -c 100000' % start],
                       stdout=log.fd, check=True)
        log.close()
    written = open(path).read()
    assert written.startswith('start 0\nflood\n')
    assert len(written) < 1000 + 5 * 200, len(written)
    assert written.count('[the grader cut ') == 5
    assert ('here: it keeps 1000 bytes of each log however often its launch starts, and earlier '
            'starts had used all but 0 bytes]') in written
    # A quiet launch started again loses nothing.
    quiet = str(tmp_path / 'quiet.log')
    for start in range(5):
        log = logcap.CappedLog(quiet, 1000)
        subprocess.run(['echo', 'start %d' % start], stdout=log.fd, check=True)
        log.close()
    assert open(quiet).read() == ''.join('start %d\n' % start for start in range(5))


def test_a_folder_is_graded_one_submission_per_core_the_process_may_use(monkeypatch, tmp_path):
    from chase_tools.grading import cli
    monkeypatch.setattr(os, 'sched_getaffinity', lambda _pid: {2, 5, 7})
    assert cli.parse_args([str(tmp_path)]).jobs == 3
    assert cli.parse_args([str(tmp_path), '--jobs', '1']).jobs == 1


def test_class_and_one_decide_what_a_folder_is(tmp_path, capsys):
    from chase_tools.grading import class_grade, cli
    for name in ('py_correct', 'cpp_correct'):
        variants.compose(name, tmp_path)
    shutil.rmtree(tmp_path / 'cpp_correct' / 'ball_chaser')
    variants.compose('py_repository', tmp_path)
    assert class_grade.submission_paths(cli.parse_args([str(tmp_path)])) == [str(tmp_path)]
    assert ('2 subfolders of %s hold a whole submission, but not every one' % tmp_path
            in capsys.readouterr().out)
    assert class_grade.submission_paths(cli.parse_args([str(tmp_path), '--class'])) == [
        str(tmp_path / name) for name in ('cpp_correct', 'py_correct', 'py_repository')]
    variants.compose('cpp_correct', tmp_path / 'again')
    shutil.rmtree(tmp_path / 'cpp_correct')
    assert len(class_grade.submission_paths(cli.parse_args([str(tmp_path)]))) == 3
    assert class_grade.submission_paths(cli.parse_args([str(tmp_path), '--one'])) == [str(tmp_path)]
    with pytest.raises(SystemExit):
        cli.parse_args([str(tmp_path), '--class', '--one'])


# -- the world's launch ----------------------------------------------------------------------------

def test_a_world_launch_whose_simulator_died_is_over_though_roslaunch_runs_on(tmp_path):
    """The simulator is the grader's own (grading/simulator.py): the world's launch is over once
    it has ended, whatever roslaunch does."""
    from chase_tools.grading.launches import WorldLaunch
    from chase_tools.procs import ProcessGroup
    launch, simulator = WorldLaunch(stop_timeout=1.0), ProcessGroup(stop_timeout=1.0)
    with open(tmp_path / 'log', 'w') as log:
        launch.start(['sleep', '30'], log)
        simulator.start(['sleep', '30'], log)
    launch.simulator = simulator
    try:
        assert launch.alive() and not launch.simulator_died
        simulator.procs[0].kill()
        simulator.procs[0].wait()
        assert not launch.alive() and launch.simulator_died
    finally:
        launch.stop()
        simulator.stop()


# -- the world, read through the submission's copy --------------------------------------------

CRATE_CONFIG = '<model><name>crate</name><sdf version="1.6">%s</sdf></model>'
CRATE_SDF = ('<sdf version="1.6"><model name="crate"><static>true</static><link name="l"><collision '
             'name="c"><geometry><box><size>1 1 1</size></box></geometry></collision></link></model></sdf>')
CRATE_WORLD = ('<sdf version="1.6"><world name="w"><include><uri>model://crate</uri>'
               '<pose>2 0 0 0 0 0</pose></include></world></sdf>')


def test_the_world_and_the_models_it_includes_are_read_through_a_copy(tmp_path, monkeypatch):
    models = tmp_path / 'models' / 'crate'
    models.mkdir(parents=True)
    (models / 'model.config').write_text(CRATE_CONFIG % 'crate.sdf')
    (models / 'crate.sdf').write_text(CRATE_SDF)
    world = tmp_path / 'office.world'
    world.write_text(CRATE_WORLD)
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(models.parent))
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    assert worldcopy.copy(str(world), str(tmp_path / 'run' / 'world')) == []
    taken = worldcopy.snapshot(str(tmp_path / 'run'), 'world', str(tmp_path / 'grader'), str(world))
    assert taken.left_out == [] and taken.world_file == str(tmp_path / 'grader' / 'office.world')
    loaded = load_world(taken.world_file, taken.model_paths)
    assert [(model.name, model.pose.x) for model in loaded.models] == [('crate', 2.0)]


def test_the_graders_snapshot_takes_no_link_no_entity_and_no_file_outside_a_model_folder(tmp_path):
    """What the submission's sandbox left in the copy, read as root: links to a file of the
    grader's, a model.config naming a file outside its folder, entity declarations."""
    secret = tmp_path / 'secret.world'
    secret.write_text(CRATE_WORLD)
    copy = tmp_path / 'run' / 'world'
    (copy / 'models' / 'crate').mkdir(parents=True)
    (copy / 'models' / 'bomb').mkdir()
    os.symlink(str(secret), str(copy / 'office.world'))
    os.symlink(str(tmp_path), str(copy / 'models' / 'linked'))
    (copy / 'models' / 'crate' / 'model.config').write_text(CRATE_CONFIG % '../../../../secret.world')
    (copy / 'models' / 'bomb' / 'model.config').write_text(
        '<!DOCTYPE model [<!ENTITY a "a">]>' + CRATE_CONFIG % 'crate.sdf')
    taken = worldcopy.snapshot(str(tmp_path / 'run'), 'world', str(tmp_path / 'grader'), 'office.world')
    assert taken.world_file == ''
    said = '\n'.join(taken.left_out)
    assert 'world/office.world (Too many levels of symbolic links)' in said, said
    assert 'crate/model.config (names a file outside its folder)' in said, said
    assert 'world/models/bomb/model.config (declares XML entities)' in said, said
    kept = [os.path.join(root, name) for root, dirs, files in os.walk(str(tmp_path / 'grader'))
            for name in dirs + files]
    assert sorted(os.path.relpath(path, str(tmp_path / 'grader')) for path in kept) == [
        'models', 'models/bomb', 'models/crate']


# -- the disk limit ------------------------------------------------------------------------------

DISK_PROBE = """
import json, os, sys
from chase_tools.grading import disk
if sys.argv[3] == 'no loop device':
    disk.Disk._mount_image = lambda self: 'no loop device'
made = disk.Disk.create(sys.argv[1], int(sys.argv[2]))
written, error = 0, ''
try:
    while written < 4 * made.limit:
        with open(os.path.join(made.folder, 'fill_%d' % written), 'wb') as stream:
            stream.write(b'x' * (1 << 20))
        written += 1 << 20
except OSError as exc:
    error = exc.strerror
full, kind = made.full(), made.describe()
with open('/proc/self/mountinfo') as stream:
    mounted = made.folder in stream.read()
made.unmount()
print(json.dumps(dict(kind=kind, written=written, error=error, full=full, mounted=mounted)))
"""


def _disk_probe(folder, how, prefix=()):
    """Disk.create in a process of its own (it moves into a mount namespace of its own)."""
    result = subprocess.run(list(prefix) + [sys.executable, '-c', DISK_PROBE, os.path.join(folder, 'disk'),
                                            str(8 << 20), how],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=60,
                            check=False)
    assert result.returncode == 0, result.stdout
    return json.loads(result.stdout.splitlines()[-1])


@pytest.mark.skipif(os.geteuid() != 0, reason='mounting needs root')
@pytest.mark.parametrize('how, kind', [
    ('', '8 MiB of disk for its folders together (a filesystem of their own, an ext4 image in the '
         'scratch folder)'),
    ('no loop device', '8 MiB for its folders together (a tmpfs of their own, in memory)'),
])
def test_a_disk_of_the_limit_stops_writes_past_it_and_says_when_it_is_full(tmp_path, how, kind):
    probe = _disk_probe(str(tmp_path), how)
    assert probe['kind'] == kind
    assert probe['error'] == 'No space left on device' and probe['written'] <= 8 << 20, probe
    assert probe['full'] and probe['mounted']
    with open('/proc/self/mountinfo') as stream:
        assert str(tmp_path) not in stream.read()             # the machine's mounts: never there


@pytest.mark.skipif(os.geteuid() != 0 or shutil.which('setpriv') is None,
                    reason='runs the probe as another uid')
def test_a_grader_that_is_not_root_says_the_disk_is_not_bounded():
    folder = tempfile.mkdtemp(prefix='grade_disk_probe_')      # where another uid may write
    try:
        os.chmod(folder, 0o777)
        probe = _disk_probe(folder, '', ['setpriv', '--reuid', '65534', '--regid', '65534',
                                         '--clear-groups'])
    finally:
        shutil.rmtree(folder)
    assert probe['kind'] == 'disk space not bounded (the grader is not root)'
    assert probe['error'] == '' and probe['written'] == 32 << 20 and not probe['full'], probe

# -- trials shared among worlds ------------------------------------------------------------------

def test_the_worlds_are_as_many_as_the_cores_and_the_limits_hold():
    gib = 1 << 30
    assert worlds.worlds_for(trials=3, cores=2, memory=4 * gib, processes=1024) == 1
    assert worlds.worlds_for(trials=3, cores=4, memory=4 * gib, processes=1024) == 2
    assert worlds.worlds_for(trials=3, cores=8, memory=4 * gib, processes=1024) == 3
    assert worlds.worlds_for(trials=3, cores=8, memory=2 * gib, processes=1024) == 2
    assert worlds.worlds_for(trials=3, cores=8, memory=4 * gib, processes=300) == 1
    assert worlds.worlds_for(trials=0, cores=8, memory=4 * gib, processes=1024) == 1


# A stand-in for session.TrialWorld, speaking its protocol: `fails` never comes up, `dies` ends
# during its first trial, a number runs each trial it is given, once it is up a second later.
FAKE_WORLD = textwrap.dedent("""\
    import json, sys, time
    how = sys.argv[1]
    def tell(**message):
        print(json.dumps(message), flush=True)
    if how == 'fails':
        tell(failed='its world did not come up', notes=[])
        sys.exit()
    tell(world_up=True)
    chase = json.loads(sys.stdin.readline())['chase']
    if how.isdigit():
        time.sleep(1)
    tell(ready=True)
    for line in sys.stdin:
        index = json.loads(line).get('run')
        if index is None:
            break
        if how == 'dies':
            sys.exit(1)
        tell(trial={'index': index, 'robot': chase['placements'][index], 'ball': [0, 0],
                    'world': int(how)}, calls=2)
    tell(notes=['world %s: stopped' % how])
    """)


def test_extra_worlds_share_the_trials_and_give_back_what_they_could_not_run(tmp_path):
    script = tmp_path / 'world.py'
    script.write_text(FAKE_WORLD)
    commands = {number: ([sys.executable, str(script), how], str(tmp_path / ('%d.log' % number)))
                for number, how in ((2, '2'), (3, 'fails'), (4, 'dies'))}
    extra = worlds.ExtraWorlds(commands)
    extra.start()
    queue = worlds.TrialQueue(range(6))
    extra.begin_chase(queue, {'placements': [[index, 0, 0] for index in range(6)]})
    # The session's own world takes none here: it looks until every trial is taken.
    deadline = time.monotonic() + 60
    while queue.pending() and time.monotonic() < deadline:
        time.sleep(0.05)
    extra.finish()
    extra.stop()
    ran = {index: trial.world for index, (trial, _calls) in extra.results.items()}
    # World 4, up first, died in its first trial, which went back to the queue: world 2 ran
    # every trial.
    assert ran == {index: 2 for index in range(6)} and not queue.pending()
    assert all(calls == 2 for _trial, calls in extra.results.values())
    notes = extra.take_notes()
    assert any(note.startswith('world 3 did not come up (its world did not come up)') for note in notes)
    assert any(note.startswith('world 4 could not run trial') for note in notes)
    assert 'world 2: stopped' in notes


# -- what a flooding submission costs the grader ----------------------------------------------

class FixedClock:
    def now(self):
        return 1.5


def a_session(tmp_path, monkeypatch):
    """The rubric run's Session as grade makes it, without a master or a sandbox."""
    from chase_tools.grading.session import Session, SessionSpec
    monkeypatch.setattr(os, 'environ', dict(os.environ))      # the session sets ROS's variables
    spec = SessionSpec(overlay_env={}, overlay_root=str(tmp_path), run_scratch=str(tmp_path / 'run'),
                       out_dir=str(tmp_path / 'out'), robot_package='my_robot',
                       chaser_package='ball_chaser', isolate=False)
    session = Session(spec)
    session.clock = FixedClock()
    return session


def test_a_flood_on_cmd_vel_costs_the_grader_bounded_memory(tmp_path, monkeypatch):
    from geometry_msgs.msg import Twist
    from chase_tools.grading import bounds
    session = a_session(tmp_path, monkeypatch)
    before = len(session.cmd)
    command = Twist()
    command.linear.x = 0.3
    flood = 3 * bounds.COMMANDS_KEPT
    for _ in range(flood):
        session.on_cmd(command)
    assert len(session.cmd) - before == flood          # every command is counted
    kept = session.cmd.since(before)
    assert len(kept) == bounds.COMMANDS_KEPT   # and only the last ones are kept
    assert kept[-1] == (1.5, 0.3, 0.0)
    assert session.cmd.dropped_since(before) == flood - bounds.COMMANDS_KEPT



@pytest.mark.parametrize('names', ['.', 'model.config', './', 'sub/..'])
def test_a_model_config_naming_its_folder_or_itself_leaves_the_model_out_with_a_reason(tmp_path, monkeypatch,
                                                                                       names):
    models = tmp_path / 'models' / 'crate'
    models.mkdir(parents=True)
    (models / 'model.config').write_text(CRATE_CONFIG % names)
    (models / 'crate.sdf').write_text(CRATE_SDF)
    world = tmp_path / 'office.world'
    world.write_text(CRATE_WORLD)
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(models.parent))
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    said = worldcopy.copy(str(world), str(tmp_path / 'run' / 'world'))
    assert said == ['%s names %s: not a model file' % (models / 'model.config', os.path.normpath(names))]
    # What the sandbox could have written anyway, read by the grader.
    copied = tmp_path / 'run' / 'world' / 'models' / 'crate' / 'model.config'
    copied.write_text(CRATE_CONFIG % names)
    taken = worldcopy.snapshot(str(tmp_path / 'run'), 'world', str(tmp_path / 'grader'), str(world))
    assert taken.world_file == str(tmp_path / 'grader' / 'office.world')
    assert any('names %s: not a model file' % os.path.normpath(names) in line
               for line in taken.left_out), taken.left_out
    assert load_world(taken.world_file, taken.model_paths).models == []


class ParamMaster:
    """The parameters a submission's launch set, as the master gives them back."""

    def __init__(self, params):
        self.params = params

    def hasParam(self, name):  # noqa: N802 - the master's XML-RPC name
        return name in self.params

    def getParam(self, name):  # noqa: N802 - the master's XML-RPC name
        return self.params[name]


def test_parameters_of_the_wrong_type_are_named_and_not_used(tmp_path, monkeypatch):
    """roslaunch types a <param> by how its value reads: value="3" is an int, "true" a bool,
    and a <rosparam> gives a dictionary. The grader reads three of them."""
    session = a_session(tmp_path, monkeypatch)
    session.master = ParamMaster({'/flatsim/world_name': 3, '/robot_description': {'robot': 'x'},
                                  '/flatsim/model_states_rate': 'fast'})
    notes = []
    assert session.typed_param('/flatsim/world_name', str, 'a file name', '', notes) == ''
    assert notes == ['the parameter /flatsim/world_name holds 3 (int), not a file name; it was not used']
    assert session.urdf_robot_name() is None
    assert ("the parameter /robot_description holds {'robot': 'x'} (dict), not URDF; it was not used"
            in session.grade.notes)

    class Sim:
        def time_step(self):
            return 0.001
    session.read_state_schedule(Sim())
    assert session.found.states_period == pytest.approx(1 / 50.0)
    assert any('/flatsim/model_states_rate holds \'fast\' (str)' in note for note in session.grade.notes)
    session.master = ParamMaster({'/flatsim/model_states_rate': True})
    session.read_state_schedule(Sim())
    assert session.found.states_period == pytest.approx(1 / 50.0)
    session.master = ParamMaster({'/flatsim/model_states_rate': 20})
    session.read_state_schedule(Sim())
    assert session.found.states_period == pytest.approx(1 / 20.0)


# -- the stability advisory ------------------------------------------------------------------------

FRONT_WHEELER = os.path.join(TOP, 'catkin_ws', 'src', 'flatsim', 'test', 'fixtures', 'robots',
                             'front_wheels_no_casters.urdf')
TIPPING = ('robot stability: may tip over: centre of mass (0.033, 0.000) m of 12.00 kg is 0.167 m outside '
           'the support line (no polygon) (0.200, -0.175) (0.200, 0.175) of left_wheel, right_wheel '
           '(margin -0.167 m; a stable design keeps it at least 0.02 m inside)')


class DescriptionMaster(ParamMaster):
    def getParamNames(self):  # noqa: N802 - the master's XML-RPC name
        return sorted(self.params)


def test_a_robot_that_would_tip_gets_an_advisory_and_no_failed_item(tmp_path, monkeypatch):
    session = a_session(tmp_path, monkeypatch)
    with open(FRONT_WHEELER, encoding='utf-8') as stream:
        session.master = DescriptionMaster({'/robot_description': stream.read()})
    session.read_robot_geometry()
    assert session.grade.advisories == [TIPPING]
    assert session.found.geometry is not None
    assert session.grade.items == [] and session.grade.notes == []


def test_the_advisory_is_a_line_of_the_report_and_of_the_json_not_an_item(tmp_path):
    from chase_tools.grading import formats
    grade = rubric.Grade('/subs/alice', seed=1)
    for name in rubric.ITEM_NAMES:
        grade.set(name, True, 'evidence of %s' % name)
    grade.advisories.append(TIPPING)
    assert grade.passed
    text = rubric.markdown(grade)
    assert 'Rubric items (7): 7 passed, 0 failed, 0 not judged.' in text
    assert 'Advisory, not a rubric item: %s' % TIPPING in text.splitlines()
    assert '**FAIL**' not in text
    rubric.write_json(grade, str(tmp_path / 'g.json'))
    again = rubric.Grade.from_json(json.loads((tmp_path / 'g.json').read_text()))
    assert again.advisories == [TIPPING] and again.passed
    scope = formats.gradescope(grade)
    assert scope['output'].endswith('\nAdvisory, not a rubric item: %s' % TIPPING)
    assert scope['score'] == sum(test['max_score'] for test in scope['tests'])


def test_the_course_service_is_ours_whatever_ball_chaser_the_shell_sourced(tmp_path):
    from ball_chaser.srv import DriveToTarget
    from chase_tools.grading import course_service
    assert DriveToTarget._md5sum == course_service.COURSE_MD5
    # A student's own ball_chaser, first on the path, with another DriveToTarget.
    student_srv = tmp_path / 'ball_chaser' / 'srv'
    student_srv.mkdir(parents=True)
    (tmp_path / 'ball_chaser' / '__init__.py').write_text('')
    (student_srv / '__init__.py').write_text("class DriveToTarget:\n    _md5sum = 'theirs'\n")
    probe = ('from ball_chaser.srv import DriveToTarget as Theirs\n'
             'from chase_tools.grading.course_service import course_drive_to_target\n'
             'print(Theirs._md5sum, course_drive_to_target()._md5sum)\n')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), os.environ['PYTHONPATH']]))
    result = subprocess.run([sys.executable, '-c', probe], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, check=False)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ['theirs', course_service.COURSE_MD5]


def a_student_drive_to_target_sourced(monkeypatch):
    """The shell that runs grade has sourced a student's ball_chaser, with another DriveToTarget."""
    import types
    module = types.ModuleType('ball_chaser.srv')
    module.DriveToTarget = type('DriveToTarget', (), {'_md5sum': 'theirs'})
    monkeypatch.setitem(sys.modules, 'ball_chaser.srv', module)


def test_drive_bot_is_judged_against_the_course_service_whatever_the_shell_sourced(tmp_path, monkeypatch):
    from chase_tools.grading import course_service, probe
    session = a_session(tmp_path, monkeypatch)
    a_student_drive_to_target_sourced(monkeypatch)
    session.service_uri = lambda name: 'rosrpc://localhost:1'
    monkeypatch.setattr(probe, 'service_headers', lambda uri, name: {
        'type': 'ball_chaser/DriveToTarget', 'md5sum': course_service.COURSE_MD5})
    session.wait_for_cmd_publishers = lambda: None
    probed = []
    session.probe_drive_bot = lambda srv_type, own=None: probed.append(srv_type)
    session.check_drive_bot()
    assert session.grade.item('drive_bot_service') is None       # not failed on its md5
    assert [srv_type._md5sum for srv_type in probed] == [course_service.COURSE_MD5]


def a_served_srv(tmp_path, monkeypatch, text):
    """A session whose drive_bot serves the type of ball_chaser/srv/DriveToTarget.srv (text)."""
    from chase_tools.grading import probe, service_type
    session = a_session(tmp_path, monkeypatch)
    (tmp_path / 'src' / 'ball_chaser' / 'srv').mkdir(parents=True)
    (tmp_path / 'src' / 'ball_chaser' / 'srv' / 'DriveToTarget.srv').write_text(text)
    md5 = service_type.parse_srv(text, 'ball_chaser/DriveToTarget').md5
    session.service_uri = lambda name: 'rosrpc://localhost:1'
    monkeypatch.setattr(probe, 'service_headers', lambda uri, name: {
        'type': 'ball_chaser/DriveToTarget', 'md5sum': md5})
    session.wait_for_cmd_publishers = lambda: None
    session.counter = None
    return session


def test_a_simulator_taken_over_during_the_service_probe_leaves_it_not_judged(tmp_path, monkeypatch):
    """A node of the submission that takes the simulator's name answers nothing: the probe is not
    judged, and the run goes on to the steps that say who took the name."""
    import rospy
    from chase_tools.grading import checks
    session = a_served_srv(tmp_path, monkeypatch, 'float64 linear_x\nfloat64 angular_z\n---\n'
                                                  'string msg_feedback\n')

    class Refused:
        def unpause(self):
            raise rospy.ServiceException('unable to connect to service: [Errno 111] Connection refused')
    monkeypatch.setattr(checks.chase_graph, 'SimControl', Refused)
    session.models = object()
    session.alive = lambda: True
    session.probe_drive_bot = lambda srv_type, own=None: pytest.fail('probed without sim time')
    session.check_drive_bot()
    item = session.grade.item('drive_bot_service')
    assert item.verdict == 'not judged'
    assert item.evidence.startswith('not judged: the simulator did not answer, so sim time could not run')


def test_drive_bot_of_another_response_is_probed_with_the_submission_s_own_type(tmp_path, monkeypatch):
    session = a_served_srv(tmp_path, monkeypatch, 'float64 linear_x\nfloat64 angular_z\n---\n'
                                                  'float64 linear_x_out\nfloat64 angular_z_out\n')
    probed = []
    session.probe_drive_bot = lambda srv_type, own=None: probed.append((srv_type, own))
    session.check_drive_bot()
    assert session.grade.item('drive_bot_service') is None       # judged by the probe, not the md5
    (srv_type, own), = probed
    assert srv_type._md5sum == own.md5 and srv_type._type == 'ball_chaser/DriveToTarget'
    assert srv_type._response_class.__slots__ == ['linear_x_out', 'angular_z_out']
    assert srv_type._request_class(0.25, -0.35).linear_x == 0.25
    assert any('its response is float64 linear_x_out, float64 angular_z_out where the course\'s is '
               'string msg_feedback (ball_chaser/srv/DriveToTarget.srv)' in note
               for note in session.grade.notes), session.grade.notes


def test_drive_bot_of_another_request_fails_naming_its_fields(tmp_path, monkeypatch):
    session = a_served_srv(tmp_path, monkeypatch,
                           'float64 speed\nfloat64 turn\n---\nstring msg_feedback\n')
    session.probe_drive_bot = lambda srv_type, own=None: pytest.fail('a request of other fields was probed')
    session.check_drive_bot()
    item = session.grade.item('drive_bot_service')
    assert not item.passed
    assert item.evidence.endswith('; its request (ball_chaser/srv/DriveToTarget.srv) has float64 speed, '
                                  'float64 turn, not the course\'s float64 linear_x, float64 angular_z')


class StillSim:
    """What an extra world's warm-up asks of the simulator, doing nothing."""

    def pause(self):
        pass

    def unpause(self):
        pass


def an_extra_world(tmp_path, out):
    """TrialWorld number 2 of a session, its calls to drive_bot recorded in .called."""
    import io
    from chase_tools.grading.session import SessionSpec
    from chase_tools.grading.trial_world import TrialWorld
    spec = SessionSpec(overlay_env={}, overlay_root=str(tmp_path), run_scratch=str(tmp_path / 'run'),
                       out_dir=str(tmp_path / out), robot_package='my_robot',
                       chaser_package='ball_chaser', isolate=False,
                       extra_world={'number': 2, 'robot': 'robot', 'ball': 'ball', 'overlays': {}})
    world = TrialWorld(spec, io.StringIO(), io.StringIO())
    world.called = []
    world.call_drive_bot = lambda srv_type, request, within: world.called.append((srv_type._md5sum, request))
    return world


def test_an_extra_world_warms_its_chaser_up_with_the_course_service(tmp_path, monkeypatch):
    from chase_tools.grading import course_service
    monkeypatch.setattr(os, 'environ', dict(os.environ))
    a_student_drive_to_target_sourced(monkeypatch)
    world = an_extra_world(tmp_path, 'out')
    world.counter = None
    world.warm_up(StillSim(), wall_timeout=0.1)
    assert world.called == [(course_service.COURSE_MD5, (0.0, 0.0))]


def test_an_extra_world_counts_and_warms_up_with_the_submission_s_own_type_as_the_session_does(
        tmp_path, monkeypatch):
    from chase_tools.grading import course_service, service_type
    text = ('float64 linear_x\nfloat64 angular_z\n---\n'
            'float64 linear_x_out\nfloat64 angular_z_out\n')
    own = service_type.parse_srv(text, 'ball_chaser/DriveToTarget', 'ball_chaser/srv/DriveToTarget.srv')

    class Counter:
        def __init__(self, srv_type):
            self.srv_type = srv_type

        def serve_as(self, srv_type):
            self.srv_type = srv_type
    # What the session's own world hands its extra worlds, its stand-in serving its own type.
    session = a_session(tmp_path, monkeypatch)
    session.found.own_service = (own.md5, own)
    session.counter = Counter(service_type.service_class(own))
    share = session.own_service_share()
    assert share == {'type': 'ball_chaser/DriveToTarget', 'text': text}
    session.counter = Counter(course_service.course_drive_to_target())
    assert session.own_service_share() is None         # its stand-in serves the course's
    monkeypatch.setattr(os, 'environ', dict(os.environ))
    world = an_extra_world(tmp_path, 'extra_out')
    world.counter = Counter(course_service.course_drive_to_target())
    world.count_as_the_session({'count_calls': True, 'own_service': share})
    assert world.counter.srv_type._md5sum == own.md5
    assert world.counter.srv_type._response_class.__slots__ == ['linear_x_out', 'angular_z_out']
    world.counter.calls = [(0.0, 0.0, 0.0)]
    world.warm_up(StillSim(), wall_timeout=0.1)
    assert world.called == [(own.md5, (0.0, 0.0))]


def test_the_stand_in_holds_a_call_back_with_an_answer_of_the_type_it_serves():
    """While drive_bot itself is tested, process_image's calls are counted and answered, not
    forwarded: with the course's text, or a response of other fields left at its defaults."""
    from chase_tools.grading import course_service, service_type, trials
    from chase_tools.grading.listeners import CallCounter
    counter = CallCounter.__new__(CallCounter)
    counter.clock, counter.calls, counter.forwarding = FixedClock(), trials.RollingLog(10), False
    counter.srv_type = course_service.course_drive_to_target()
    request = counter.srv_type._request_class(0.4, 0.1)
    assert counter.handle(request).msg_feedback == 'held while drive_bot is tested'
    counter.srv_type = service_type.service_class(service_type.parse_srv(
        'float64 linear_x\nfloat64 angular_z\n---\nfloat64 linear_x_out\nfloat64 angular_z_out\n',
        'ball_chaser/DriveToTarget'))
    answer = counter.handle(counter.srv_type._request_class(0.3, -0.2))
    assert (answer.linear_x_out, answer.angular_z_out) == (0.0, 0.0)
    assert [call[1:] for call in counter.calls.since(0)] == [(0.4, 0.1), (0.3, -0.2)]


def test_the_graders_node_refuses_a_message_announced_larger_than_its_limit_at_its_length():
    """rospy would buffer a message of any announced length until all of it had come."""
    import io
    import socket
    import struct
    from rospy.impl.tcpros_base import TransportTerminated
    from rospy.impl.tcpros_pubsub import TCPROSSub
    from rospy.impl.tcpros_service import TCPROSServiceClient
    from std_msgs.msg import String
    from std_srvs.srv import Trigger
    from chase_tools.grading.message_limit import MessageLimit
    asked = []

    def sender(topic, port):
        asked.append((topic, port))
        return '/hostile'
    limit = MessageLimit(limit=1024, sender=sender)
    server = socket.create_server(('127.0.0.1', 0))
    left = socket.create_connection(server.getsockname())
    right, _peer = server.accept()
    server.close()
    port = right.getsockname()[1]
    try:
        within = io.BytesIO()
        String('hello').serialize(within)
        framed = io.BytesIO()
        framed.write(struct.pack('<I', len(within.getvalue())) + within.getvalue())
        taken = []
        TCPROSSub('/chatter', String).read_messages(framed, taken, left)
        assert [msg.data for msg in taken] == ['hello']
        announced = io.BytesIO()
        announced.write(struct.pack('<I', 1500000000) + b'x' * 100)
        with pytest.raises(TransportTerminated):
            TCPROSSub('/chatter', String).read_messages(announced, [], left)
        # A service's answer: an ok byte, then the length.
        answer = io.BytesIO()
        answer.write(b'\x01' + struct.pack('<I', 2000000) + b'x' * 100)
        with pytest.raises(TransportTerminated):
            TCPROSServiceClient('/serve', Trigger).read_messages(answer, [], left)
    finally:
        left.close()
        right.close()
    said = limit.notes()
    assert asked == [('/chatter', port), ('/serve', port)]
    assert len(said) == 2
    assert said[0].startswith('the grader refused a message of 1.4 GiB on /chatter from /hostile '
                              '(127.0.0.1:%d) (1 time), larger than the 1 KiB it takes' % port)
    assert said[1].startswith('the grader refused a message of 1.9 MiB on /serve from /hostile')
    limit.allow_frames(2560, 1440)
    assert limit.limit == 2560 * 1440 * 4 + (64 << 10)
    limit.allow_frames(320, 240)           # the course's camera: the floor for any message
    assert limit.limit == 8 << 20


def test_the_graders_simulator_takes_no_message_larger_than_the_graders_node_and_says_what_it_refused(
        tmp_path):
    """The simulator runs under message_limit's guard: its refusals go to its record, and the
    grader's notes name them, with the sending node found from the port."""
    import subprocess
    import sys
    record = tmp_path / 'refused.json'
    program = tmp_path / 'program.py'
    program.write_text(
        'import io, struct, sys\n'
        'from rospy.impl.tcpros_base import TransportTerminated\n'
        'from rospy.impl.tcpros_pubsub import TCPROSSub\n'
        'from geometry_msgs.msg import Twist\n'
        'class Peer:\n'
        '    def getpeername(self):\n'
        '        return ("127.0.0.1", 40404)\n'
        'bomb = io.BytesIO()\n'
        'bomb.write(struct.pack("<I", 1500000000) + bytes(64))\n'
        'try:\n'
        '    TCPROSSub("/cmd_vel", Twist).read_messages(bomb, [], Peer())\n'
        'except TransportTerminated:\n'
        '    print("REFUSED", sys.argv[1:])\n')
    done = subprocess.run([sys.executable, '-m', 'chase_tools.grading.message_limit', str(record),
                           str(program), '__name:=flatsim'], stdout=subprocess.PIPE, text=True,
                          timeout=60, check=True)
    assert done.stdout == "REFUSED ['__name:=flatsim']\n"
    from chase_tools.grading.message_limit import simulator_notes
    said = simulator_notes(record.read_text(), lambda topic, port: '/hostile' if port == 40404 else None)
    assert said == ["the grader's simulator refused a message of 1.4 GiB on /cmd_vel from /hostile "
                    "(127.0.0.1:40404) (1 time), larger than the 8 MiB it takes: the connection was "
                    "closed before it was read"]
    assert simulator_notes('{"limit": 1', None) == [
        "the grader's simulator kept a record of refused messages that could not be read"]


def test_roscores_logs_are_copied_capped_without_following_a_link_or_opening_a_fifo(tmp_path):
    from chase_tools.grading.core import Core
    box = Core(str(tmp_path / 'core'), 64 << 10, switch_user=False)
    try:
        run = os.path.join(box.log_dir, 'run_id')
        os.makedirs(run)
        with open(os.path.join(run, 'rosout.log'), 'wb') as stream:
            stream.write(b'r' * (1 << 20))
        with open(os.path.join(run, 'master.log'), 'w') as stream:
            stream.write('small\n')
        secret = tmp_path / 'secret'
        secret.write_text('not roscore\'s\n')
        os.symlink(str(secret), os.path.join(run, 'linked.log'))
        os.mkfifo(os.path.join(run, 'fifo.log'))
        out = tmp_path / 'report'
        cut = box.copy_logs(str(out))
        assert sorted(os.listdir(out / 'run_id')) == ['master.log', 'rosout.log']
        assert (out / 'run_id' / 'master.log').read_text() == 'small\n'
        assert os.path.getsize(out / 'run_id' / 'rosout.log') < (64 << 10) + 200
        assert [(name, cap.total) for name, cap in cut] == [('run_id/rosout.log', 1 << 20)]
        with open(box.logging) as stream:
            assert "args=(os.environ['ROS_LOG_FILENAME'], 'a', 32768, 1)" in stream.read()
    finally:
        box.end()


def test_a_session_a_signal_ended_says_which():
    from chase_tools.grading.submission_grade import exit_text
    assert exit_text(-9) == 'killed by SIGKILL'
    assert exit_text(1) == 'exit 1'


def fake_unified_hierarchy(tmp_path, offered, enabled=''):
    """A folder laid out as a cgroup v2 hierarchy's files, with this process in /grading."""
    mount = tmp_path / 'unified'
    (mount / 'grading').mkdir(parents=True)
    (mount / 'grading' / 'cgroup.controllers').write_text(offered + '\n')
    (mount / 'grading' / 'cgroup.subtree_control').write_text(enabled + '\n')
    proc_cgroup = tmp_path / 'cgroup'
    proc_cgroup.write_text('0::/grading\n')
    return str(mount), str(proc_cgroup)


def test_without_cgroup_v1_the_submissions_cgroup_is_made_in_cgroup_v2(tmp_path):
    """Files only: this machine's memory and pids controllers are bound to cgroup v1, so its
    unified hierarchy offers neither (see docs/teaching.md)."""
    from chase_tools.grading import limits
    mount, proc_cgroup = fake_unified_hierarchy(tmp_path, 'cpu memory pids')
    made = limits.Cgroups.create_unified('grade_1', limits.Limits(memory=768 << 20, processes=200),
                                         mount=mount, proc_cgroup=proc_cgroup)
    folder = os.path.join(mount, 'grading', 'grade_1')
    assert made.folders == {limits.UNIFIED: folder} and made.active
    with open(os.path.join(mount, 'grading', 'cgroup.subtree_control')) as stream:
        assert stream.read() == '+memory +pids'
    with open(os.path.join(folder, 'memory.max')) as stream:
        assert stream.read() == str(768 << 20)
    with open(os.path.join(folder, 'pids.max')) as stream:
        assert stream.read() == '200'
    assert made.procs_files() == [os.path.join(folder, 'cgroup.procs')]
    with open(os.path.join(folder, 'memory.events'), 'w') as stream:
        stream.write('low 0\nhigh 0\nmax 7\noom 2\noom_kill 2\n')
    with open(os.path.join(folder, 'pids.events'), 'w') as stream:
        stream.write('max 5\n')
    assert made.usage() == limits.Usage(oom_kills=2, refused_forks=5)
    restored = limits.Cgroups.from_json(made.as_json())
    assert restored.usage() == limits.Usage(oom_kills=2, refused_forks=5)


def test_a_cgroup_v2_without_memory_and_pids_for_the_grader_says_how_to_delegate_them(tmp_path):
    from chase_tools.grading import limits
    mount, proc_cgroup = fake_unified_hierarchy(tmp_path, 'hugetlb')
    made = limits.Cgroups.create_unified('grade_1', limits.Limits(), mount=mount,
                                         proc_cgroup=proc_cgroup)
    assert not made.active
    assert made.why == ("cgroup v2 does not give the grader's cgroup /grading the memory and pids "
                        "controllers (delegate them, as systemd-run --scope -p Delegate=yes does)")
    assert not os.path.exists(os.path.join(mount, 'grading', 'grade_1'))


def test_the_mount_of_the_unified_hierarchy_is_read_from_mountinfo(tmp_path):
    from chase_tools.grading import limits
    mountinfo = tmp_path / 'mountinfo'
    mountinfo.write_text(
        '30 24 0:26 / /sys/fs/cgroup/memory rw,relatime shared:9 - cgroup cgroup rw,memory\n'
        '35 24 0:31 / /sys/fs/cgroup/unified rw,relatime shared:14 - cgroup2 cgroup2 rw\n')
    assert limits.unified_mount(str(mountinfo)) == '/sys/fs/cgroup/unified'
    mountinfo.write_text('30 24 0:26 / /sys/fs/cgroup/memory rw - cgroup cgroup rw,memory\n')
    assert limits.unified_mount(str(mountinfo)) is None


CGROUP2_PROBE = r'''
import json, os, subprocess, sys, time
from chase_tools.grading import limits
mount = sys.argv[1]
subprocess.run(['mount', '-t', 'cgroup2', 'none', mount], check=True)
own = limits.own_unified_cgroup('/proc/self/cgroup')
offered = open(os.path.join(mount, own.lstrip('/'), 'cgroup.controllers')).read().split()
made = limits.Cgroups.create_unified('grade_probe', limits.Limits(memory=64 << 20, processes=20),
                                     mount=mount)
said = {'offered': offered, 'why': made.why, 'active': made.active}
if made.active:
    hog = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(0.5); '
                            'x = bytearray(256 << 20); time.sleep(5)'])
    for path in made.procs_files():
        with open(path, 'w') as stream:
            stream.write(str(hog.pid))
    said['hog_exit'] = hog.wait(30)
    said['usage'] = [made.usage().oom_kills, made.usage().refused_forks]
    made.remove()
    said['removed'] = not any(os.path.exists(folder) for folder in made.folders.values())
print(json.dumps(said))
'''


def test_cgroup_v2_on_this_kernel_bounds_memory_or_says_why_it_cannot(tmp_path):
    """A cgroup v2 hierarchy, mounted in a mount namespace of the test's own: where its
    grader's cgroup offers memory and pids (a Debian 12 machine, delegated), a process past
    memory.max is killed and counted; where the controllers are bound to cgroup v1 (as on
    a machine with both), the grader says so, and why, from the kernel's own files."""
    import json
    import shutil
    import subprocess
    import sys
    if os.geteuid() != 0 or shutil.which('unshare') is None:
        pytest.skip('mounting a cgroup2 hierarchy needs root and unshare')
    mount = tmp_path / 'cgroup2'
    mount.mkdir()
    done = subprocess.run(['unshare', '--mount', '--propagation', 'private', sys.executable, '-c',
                           CGROUP2_PROBE, str(mount)], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=120, check=False)
    if done.returncode != 0 and 'mount' in done.stdout:
        pytest.skip('this machine lets no cgroup2 hierarchy be mounted: %s' % done.stdout[-300:])
    said = json.loads(done.stdout.splitlines()[-1])
    if {'memory', 'pids'} <= set(said['offered']):
        assert said['active'], said
        assert said['hog_exit'] == -9, said
        assert said['usage'][0] >= 1, said
        assert said['removed'], said
    else:
        assert not said['active']
        missing = [name for name in ('memory', 'pids') if name not in said['offered']]
        assert said['why'].startswith('cgroup v2 does not give the grader\'s cgroup / the %s '
                                      'controller' % ' and '.join(missing)), said


def test_the_master_refuses_calls_and_parameters_past_its_bounds_and_says_so(tmp_path):
    """The session's master under master_limit: a call past the request limit is refused before
    it is read (HTTP 413), a parameter that would take what the master holds past its limit is
    refused with the API's error code, a deleted one frees its room, and each refusal is in
    the record the report reads."""
    import socket
    import xmlrpc.client
    from rosmaster.master import Master
    from chase_tools.grading.master_limit import MasterLimit, master_notes
    record = tmp_path / 'refused.json'
    uninstall = MasterLimit(record=str(record), request_limit=1 << 20, parameters_limit=3 << 20).install()
    with socket.socket() as probe:
        probe.bind(('127.0.0.1', 0))
        port = probe.getsockname()[1]
    master = Master(port)
    master.start()
    try:
        api = xmlrpc.client.ServerProxy('http://127.0.0.1:%d/' % port)
        value = 'v' * (700 << 10)
        for index in range(4):
            assert api.setParam('/test', '/big_%d' % index, value)[0] == 1
        code, text, _ = api.setParam('/test', '/big_4', value)
        assert code == -1 and text.startswith('parameter /big_4 refused: the parameters would hold '
                                              'more than 3145728 bytes'), text
        # Setting a parameter again replaces it: no more room taken.
        assert api.setParam('/test', '/big_0', value)[0] == 1
        assert api.deleteParam('/test', '/big_1')[0] == 1
        assert api.setParam('/test', '/big_4', value)[0] == 1
        with pytest.raises(xmlrpc.client.ProtocolError) as refused:
            api.setParam('/test', '/huge', 'h' * (2 << 20))
        assert refused.value.errcode == 413
        assert api.getParam('/test', '/big_4')[2] == value
    finally:
        master.stop()
        uninstall()
    said = master_notes(record.read_text())
    assert said == [
        'the ROS master refused %s from 127.0.0.1 (the last: %s bytes): it takes no call '
        'larger than 1 MiB' % (said[0].split(' from ')[0].split('refused ')[1],
                               said[0].split('the last: ')[1].split()[0]),
        'the ROS master refused 1 parameter from /test (the last: /big_4, %d bytes): it holds at most '
        '3 MiB of parameters' % len(xmlrpc.client.dumps((value,), allow_none=True))]
    assert int(said[0].split('the last: ')[1].split()[0]) > 2 << 20
