"""env/catkin_make.py's decisions, without building: which packages are Gazebo plugins,
which folders catkin_make will use, and the command line it hands to Debian's catkin_make.
(tests/test_student_packages.py and test_course_workspace.py build with it.)"""
import os
import pathlib
import sys

import pytest

TOP = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(TOP / 'env'))
import catkin_make  # noqa: E402

PACKAGE_XML = '''<?xml version="1.0"?>
<package format="2"><name>%s</name><version>0.0.0</version><description>d</description>
<maintainer email="student@example.com">s</maintainer><license>MIT</license>
<buildtool_depend>catkin</buildtool_depend></package>
'''


def make_package(src, name, cmake):
    folder = src / name
    folder.mkdir(parents=True)
    (folder / 'package.xml').write_text(PACKAGE_XML % name)
    (folder / 'CMakeLists.txt').write_text(cmake)
    return folder


@pytest.mark.parametrize('cmake, expected', [
    ('find_package(gazebo REQUIRED)', ['gazebo']),
    ('find_package(catkin REQUIRED COMPONENTS\n  roscpp\n  gazebo_plugins\n)', ['gazebo_plugins']),
    ('FIND_PACKAGE( gazebo_dev )\nfind_package(gazebo)', ['gazebo_dev', 'gazebo']),
    ('find_package(catkin REQUIRED COMPONENTS roscpp gazebo_ros gazebo_msgs)', []),
    ('# find_package(gazebo REQUIRED)\nfind_package(catkin REQUIRED)', []),
    ('#[[\nfind_package(gazebo REQUIRED)\n]]\nfind_package(roscpp)', []),
    ('message("gazebo")\nset(gazebo_plugins 1)', []),
])
def test_gazebo_dependencies(cmake, expected):
    assert catkin_make.gazebo_dependencies(cmake) == expected


def test_workspace_paths_follow_catkin_make_options(tmp_path):
    cwd = str(tmp_path)
    assert catkin_make.workspace_paths([], cwd) == (cwd + '/src', cwd + '/devel')
    assert catkin_make.workspace_paths(['-C', 'ws'], cwd) == (cwd + '/ws/src', cwd + '/ws/devel')
    # As Debian's catkin_make: --source is relative to the current folder, not to -C.
    paths = catkin_make.workspace_paths(['--directory=/w', '--source', 'code'], cwd)
    assert paths == (cwd + '/code', '/w/devel')
    assert catkin_make.workspace_paths(['-DCATKIN_DEVEL_PREFIX=/d', 'install'], cwd) == (cwd + '/src', '/d')


def test_command_adds_the_include_and_keeps_the_students_arguments(tmp_path):
    (tmp_path / 'src').mkdir()
    said = []
    cmd = catkin_make.command(['-j1', 'drive_bot', '-DFOO=1'], str(tmp_path), {}, said.append)
    assert cmd[0] == '/usr/bin/catkin_make'
    assert '-DCMAKE_PROJECT_INCLUDE=%s' % catkin_make.PROJECT_INCLUDE in cmd
    assert os.path.isfile(catkin_make.PROJECT_INCLUDE)
    assert cmd[-3:] == ['-j1', 'drive_bot', '-DFOO=1']
    assert '-DCATKIN_BLACKLIST_PACKAGES=' in cmd
    assert said == [] and '--force-cmake' not in cmd


def test_command_blacklists_plugin_packages_with_the_students_own(tmp_path):
    src = tmp_path / 'src'
    make_package(src, 'pusher', 'find_package(gazebo REQUIRED)')
    make_package(src, 'ball_chaser', 'find_package(catkin REQUIRED COMPONENTS roscpp)')
    said = []
    cmd = catkin_make.command(['-DCATKIN_BLACKLIST_PACKAGES=old_pkg'], str(tmp_path), {}, said.append)
    assert [arg for arg in cmd if 'BLACKLIST' in arg] == ['-DCATKIN_BLACKLIST_PACKAGES=old_pkg;pusher']
    assert len(said) == 1 and said[0].startswith('skipping package pusher (src/pusher): it builds a Gazebo')


def test_a_changed_underlay_forces_cmake(tmp_path):
    underlay = tmp_path / 'project' / 'devel'
    underlay.mkdir(parents=True)
    (underlay / '.catkin').write_text('')
    devel = tmp_path / 'devel'
    devel.mkdir()
    (tmp_path / 'src').mkdir()
    (devel / '_setup_util.py').write_text("            CMAKE_PREFIX_PATH = r''.split(';')\n")
    environ = {'CMAKE_PREFIX_PATH': '%s:/opt/not_a_workspace' % underlay}
    said = []
    cmd = catkin_make.command([], str(tmp_path), environ, said.append)
    assert '--force-cmake' in cmd
    assert said == ['the workspaces underneath changed (built on: none; now: %s): running CMake again '
                    'so devel/setup.bash chains to them' % underlay]
    # Dated long ago, so that CMake copies the new one in even within the second of the last build.
    assert (devel / '_setup_util.py').stat().st_mtime == 0
    (devel / '_setup_util.py').write_text("            CMAKE_PREFIX_PATH = r'%s;%s'.split(';')\n"
                                          % (devel, underlay))
    assert '--force-cmake' not in catkin_make.command([], str(tmp_path), environ, said.append)
