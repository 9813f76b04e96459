"""Finding a submission's packages and copying them into scratch (grading/submission.py):
what is found, what is refused and why, and what the copies hold. No master."""
import os
import shutil
import sys

import pytest

from chase_tools.grading import incomplete, submission

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, 'fixtures', 'submissions'))
import chase_variants  # noqa: E402
import variants  # noqa: E402


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
        'my_robot/upstream -> %s (points outside the submission)' % chase_variants.OUTSIDE_ROBOT,
        'my_robot/worlds/up -> ../.. (loops back to a folder above it)']
    copy = tmp_path / 'ws' / 'my_robot'
    assert not os.path.lexists(copy / 'upstream') and not os.path.lexists(copy / 'gone')
    assert (copy / 'worlds' / 'same.world').read_text() == (robot / 'worlds' / 'office.world').read_text()
    assert (copy / 'worlds' / 'shared.world').read_text() == '<sdf/>'
    assert (copy / 'chaser_launch' / 'ball_chaser.launch').is_file()
    # Links inside are copied as what they point to: the copy holds none.
    for root, dirs, files in os.walk(copied['my_robot']):
        assert not any(os.path.islink(os.path.join(root, name)) for name in dirs + files)
