"""overlay_check.shadowed without a master: which student's package the project's hides."""
import io
import os

import pytest

from overlay_check import shadowed


def package(folder, name=None):
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(folder, 'package.xml'), 'w') as manifest:
        manifest.write('<package format="2">\n  <name>%s</name>\n</package>\n' % (name or os.path.basename(folder)))
    return str(folder)


@pytest.fixture
def project(tmp_path):
    src = tmp_path / 'project' / 'catkin_ws' / 'src'
    return {name: package(src / name) for name in ('my_robot', 'ball_chaser', 'simple_arm', 'flatsim')}


@pytest.fixture
def home(tmp_path):
    home = tmp_path / 'home'
    home.mkdir()
    return home


def warning(project, name, home, ros_package_path=''):
    return shadowed.shadow_warning(project[name], str(home), ros_package_path,
                                   project_src=os.path.dirname(project[name]))


def test_a_students_package_in_catkin_ws_is_named_with_ours_and_the_source_line(project, home):
    mine = package(home / 'catkin_ws' / 'src' / 'ball_chaser')
    (home / 'catkin_ws' / 'devel').mkdir()
    (home / 'catkin_ws' / 'devel' / 'setup.bash').write_text('')
    line = warning(project, 'ball_chaser', home)
    assert line == ("ball_chaser: this is the project's ball_chaser (%s), not yours (%s): your workspace "
                    "is not sourced; to run yours: source %s"
                    % (project['ball_chaser'], mine, home / 'catkin_ws' / 'devel' / 'setup.bash'))
    assert '\n' not in line


def test_an_unbuilt_workspace_is_told_to_build_first(project, home):
    package(home / 'catkin_ws' / 'src' / 'my_robot')
    line = warning(project, 'my_robot', home)
    assert line.endswith('to run yours: cd %s && catkin_make && source devel/setup.bash' % (home / 'catkin_ws'))


def test_a_workspace_beside_catkin_ws_and_a_package_one_folder_down_count(project, home):
    mine = package(home / 'go_chase_it_ws' / 'src' / 'RoboND-project' / 'my_robot')
    line = warning(project, 'my_robot', home)
    assert 'not yours (%s)' % mine in line
    assert 'cd %s && catkin_make' % (home / 'go_chase_it_ws') in line


def test_catkin_ws_comes_first_and_the_others_are_named_in_the_same_line(project, home):
    first = package(home / 'catkin_ws' / 'src' / 'my_robot')
    other = package(home / 'another_ws' / 'src' / 'my_robot')
    line = warning(project, 'my_robot', home)
    assert 'not yours (%s) (another in %s)' % (first, other) in line
    assert '\n' not in line


def test_a_sourced_workspace_is_not_warned_about(project, home):
    package(home / 'catkin_ws' / 'src' / 'ball_chaser')
    sourced = os.pathsep.join([str(home / 'catkin_ws' / 'src'), os.path.dirname(project['ball_chaser'])])
    assert warning(project, 'ball_chaser', home, sourced) is None


def test_nothing_to_say_without_a_package_of_that_name(project, home):
    package(home / 'catkin_ws' / 'src' / 'my_robot')
    # Named after the package.xml, not the folder.
    package(home / 'catkin_ws' / 'src' / 'simple_arm', name='my_arm')
    (home / 'notes').mkdir()
    (home / 'notes.txt').write_text('')
    assert warning(project, 'ball_chaser', home) is None
    assert warning(project, 'simple_arm', home) is None


def test_deeper_folders_and_hidden_ones_are_not_searched(project, home):
    package(home / 'catkin_ws' / 'src' / 'a' / 'b' / 'ball_chaser')
    package(home / '.cache' / 'src' / 'ball_chaser')
    package(home / 'projects' / 'ws' / 'src' / 'ball_chaser')
    assert warning(project, 'ball_chaser', home) is None


def test_only_the_projects_own_package_warns(project, home, tmp_path):
    """A copy of ours built elsewhere (the grader's, a test's) is not the reference."""
    package(home / 'catkin_ws' / 'src' / 'ball_chaser')
    copy = package(tmp_path / 'grader' / 'src' / 'ball_chaser')
    assert shadowed.shadow_warning(copy, str(home), '', project_src=os.path.dirname(project['ball_chaser'])) is None


def test_the_project_cloned_as_catkin_ws_is_not_its_own_shadow(tmp_path):
    home = tmp_path
    ours = package(home / 'catkin_ws' / 'src' / 'my_robot')
    assert shadowed.shadow_warning(ours, str(home), '', project_src=os.path.dirname(ours)) is None


def test_a_missing_or_unreadable_home_says_nothing(project, tmp_path):
    assert warning(project, 'my_robot', tmp_path / 'nowhere') is None
    assert warning(project, 'my_robot', '') is None


def test_a_node_file_is_traced_to_its_package_folder(project):
    node = os.path.join(project['ball_chaser'], 'src', 'ball_chaser', 'nodes', 'drive_bot.py')
    os.makedirs(os.path.dirname(node))
    open(node, 'w').close()
    assert shadowed.package_folder(node) == project['ball_chaser']
    assert shadowed.package_folder('/') is None


def test_a_node_started_by_roslaunch_leaves_the_line_to_its_launch_file(monkeypatch):
    monkeypatch.setattr(shadowed, 'warning_for', lambda path: 'the line')
    out = io.StringIO()
    assert shadowed.warn_if_shadowed('drive_bot.py', ['drive_bot', '__name:=drive_bot', '__log:=/x.log'],
                                     out) is None
    assert out.getvalue() == ''
    assert shadowed.warn_if_shadowed('drive_bot.py', ['drive_bot'], out) == 'the line'
    assert out.getvalue() == 'the line\n'


def test_the_launch_command_prints_the_folder_that_ran_and_refuses_bad_arguments(project, capsys):
    assert shadowed.main([project['my_robot']]) == 0
    assert capsys.readouterr().out == os.path.realpath(project['my_robot'])
    assert shadowed.main([]) == 2
    assert 'usage: shadowed PACKAGE_FOLDER (got nothing)' in capsys.readouterr().err
    assert shadowed.main(['/no/such/folder']) == 2
    assert 'usage: shadowed PACKAGE_FOLDER (got /no/such/folder)' in capsys.readouterr().err


def test_the_project_src_is_where_the_reference_packages_are():
    assert os.path.isfile(os.path.join(shadowed.PROJECT_SRC, 'ball_chaser', 'package.xml'))
    assert os.path.isfile(os.path.join(shadowed.PROJECT_SRC, 'overlay_check', 'package.xml'))
