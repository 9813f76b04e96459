"""env/platform_devel.py on a made-up devel space: what the student mode's view hides,
links and wraps. The real one is used end to end in test_student_mode.py."""
import importlib.util
import os
import pathlib
import subprocess

import pytest

TOP = pathlib.Path(__file__).resolve().parent.parent
_spec = importlib.util.spec_from_file_location('platform_devel', TOP / 'env' / 'platform_devel.py')
platform_devel = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(platform_devel)


def write(path, text='', mode=None):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    if mode:
        path.chmod(mode)


def package(folder, name=None):
    write(folder / 'package.xml', '<package><name>%s</name></package>' % (name or folder.name))


def relay(path, script):
    write(path, "#!/usr/bin/python3\n# generated from catkin/cmake/template/script.py.in\n"
                "python_script = '%s'\nexec(open(python_script).read())\n" % script, 0o755)


@pytest.fixture
def workspace(tmp_path):
    ws = tmp_path / 'catkin_ws'
    src, devel = ws / 'src', ws / 'devel'
    for name in ('ball_chaser', 'my_robot', 'flatsim', 'chase_tools'):
        package(src / name)
    package(src / 'gazebo_compat' / 'gazebo_ros')
    package(src / 'gazebo_compat' / 'gazebo_msgs')
    # A folder holding a solution beside a platform package.
    package(src / 'course' / 'simple_arm')
    package(src / 'course' / 'turtlesim')
    write(devel / '.catkin', str(src))
    write(devel / 'cmake.lock')
    write(devel / 'setup.sh', ': ${_CATKIN_SETUP_DIR:=%s}\n' % devel, 0o644)
    write(devel / '_setup_util.py', "CMAKE_PREFIX_PATH = r''.split(';')\n", 0o755)
    for name in ('ball_chaser', 'flatsim', 'gazebo_msgs'):
        write(devel / 'lib' / 'python3' / 'dist-packages' / name / '__init__.py')
        write(devel / 'lib' / 'python3' / 'dist-packages' / name / '__pycache__' / '__init__.cpython-311.pyc')
    write(devel / 'lib' / 'python3' / 'dist-packages' / 'gazebo_msgs' / 'srv' / '__init__.py')
    write(devel / 'lib' / 'pkgconfig' / 'my_robot.pc')
    write(devel / 'lib' / 'pkgconfig' / 'flatsim.pc')
    relay(devel / 'lib' / 'ball_chaser' / 'drive_bot', src / 'ball_chaser' / 'scripts' / 'drive_bot')
    relay(devel / 'lib' / 'flatsim' / 'flatsim_node', src / 'flatsim' / 'scripts' / 'flatsim_node')
    relay(devel / 'lib' / 'chase_tools' / 'chase_demo', src / 'chase_tools' / 'scripts' / 'chase_demo')
    write(devel / 'lib' / 'chase_tools' / 'cmake.lock')
    relay(devel / 'bin' / 'grade', src / 'chase_tools' / 'scripts' / 'grade')
    relay(devel / 'bin' / 'rqt_image_view', src / 'gazebo_compat' / 'rqt_image_view' / 'scripts' / 'x')
    write(devel / 'share' / 'my_robot' / 'cmake' / 'my_robotConfig.cmake')
    write(devel / 'share' / 'gazebo_msgs' / 'cmake' / 'gazebo_msgsConfig.cmake')
    write(devel / 'share' / 'common-lisp' / 'ros' / 'ball_chaser' / 'srv' / 'x.lisp')
    write(devel / 'share' / 'common-lisp' / 'ros' / 'gazebo_msgs' / 'msg' / 'x.lisp')
    write(devel / 'include' / 'simple_arm' / 'GoToPosition.h')
    return ws


def test_the_view_leaves_out_every_entry_of_the_solutions(workspace):
    view = pathlib.Path(platform_devel.build(str(workspace)))
    assert view == workspace / 'devel_platform'
    for gone in ('lib/python3/dist-packages/ball_chaser', 'lib/pkgconfig/my_robot.pc', 'lib/ball_chaser',
                 'share/my_robot', 'share/common-lisp/ros/ball_chaser', 'include/simple_arm', 'cmake.lock',
                 'lib/chase_tools/cmake.lock'):
        assert not os.path.lexists(view / gone), gone
    for kept in ('lib/python3/dist-packages/flatsim', 'lib/python3/dist-packages/gazebo_msgs',
                 'lib/pkgconfig/flatsim.pc', 'lib/flatsim', 'share/gazebo_msgs', 'share/common-lisp/ros/gazebo_msgs',
                 'bin/rqt_image_view', 'include'):
        assert os.path.lexists(view / kept), kept
    assert (view / 'lib' / 'flatsim').resolve() == workspace / 'devel' / 'lib' / 'flatsim'


def test_ros_package_path_comes_from_the_platform_folders_alone(workspace):
    view = pathlib.Path(platform_devel.build(str(workspace)))
    src = workspace / 'src'
    assert (view / '.catkin').read_text().split(';') == [
        str(src / 'chase_tools'), str(src / 'course' / 'turtlesim'), str(src / 'flatsim'), str(src / 'gazebo_compat')]


def test_the_setup_files_are_devels_pointed_at_the_view(workspace):
    view = pathlib.Path(platform_devel.build(str(workspace)))
    assert (view / 'setup.sh').read_text() == ': ${_CATKIN_SETUP_DIR:=%s}\n' % view
    assert os.access(view / '_setup_util.py', os.X_OK)


def test_chase_tools_commands_find_the_solutions_behind_the_environment(workspace):
    view = pathlib.Path(platform_devel.build(str(workspace)))
    devel, src = workspace / 'devel', workspace / 'src'
    demo = pathlib.Path('lib', 'chase_tools', 'chase_demo')
    for wrapped, target in ((view / 'bin' / 'grade', devel / 'bin' / 'grade'), (view / demo, devel / demo)):
        assert not wrapped.is_symlink() and os.access(wrapped, os.X_OK)
        assert 'exec %s %s "$@"' % (view / 'with_reference', target) in wrapped.read_text()
    env = {'PATH': os.environ['PATH'], 'ROS_PACKAGE_PATH': '/mine/src', 'PYTHONPATH': '/mine/py'}
    seen = subprocess.run([str(view / 'with_reference'), 'sh', '-c',
                           'echo "$ROS_PACKAGE_PATH|$CMAKE_PREFIX_PATH|$PYTHONPATH"'],
                          env=env, stdout=subprocess.PIPE, text=True, check=True).stdout.strip()
    assert seen == '/mine/src:%s:%s:%s|%s|/mine/py:%s' % (
        src / 'ball_chaser', src / 'course' / 'simple_arm', src / 'my_robot', devel,
        devel / 'lib' / 'python3' / 'dist-packages')


def test_it_is_made_again_only_when_devel_changes(workspace):
    platform_devel.build(str(workspace))
    assert platform_devel.is_current(str(workspace))
    relay(workspace / 'devel' / 'lib' / 'chase_tools' / 'evaluate',
          workspace / 'src' / 'chase_tools' / 'scripts' / 'evaluate')
    assert not platform_devel.is_current(str(workspace))
    view = pathlib.Path(platform_devel.build(str(workspace)))
    assert (view / 'lib' / 'chase_tools' / 'evaluate').is_file()
    assert platform_devel.is_current(str(workspace))
    assert sorted(p.name for p in workspace.iterdir()) == ['devel', 'devel_platform', 'src']


def test_pythons_caches_in_devel_do_not_make_it_again(workspace):
    """A view made again while a grade runs in it would pull its files from under the sandbox."""
    platform_devel.build(str(workspace))
    caches = workspace / 'devel' / 'lib' / 'python3' / 'dist-packages' / 'gazebo_msgs' / 'srv' / '__pycache__'
    caches.mkdir()
    (caches / '_ApplyBodyWrench.cpython-311.pyc').write_bytes(b'')
    assert platform_devel.is_current(str(workspace))


def test_an_unbuilt_workspace_is_a_clear_error(tmp_path):
    with pytest.raises(platform_devel.ViewError, match='is not a built devel space; run setup.sh'):
        platform_devel.build(str(tmp_path))
    result = subprocess.run(['python3', str(TOP / 'env' / 'platform_devel.py'), '--now'],
                            stderr=subprocess.PIPE, text=True, check=False)
    assert result.returncode == 2 and 'usage: python3 env/platform_devel.py [--if-stale]' in result.stderr


def test_python_packages_are_folders_of_their_own_without_devels_caches(workspace):
    """The grader's sandbox mounts writable copies over a package's __pycache__, which it cannot
    do through a link; Python writes the view's own caches beside the files it finds."""
    view = pathlib.Path(platform_devel.build(str(workspace)))
    packages = view / 'lib' / 'python3' / 'dist-packages'
    for folder in (packages, packages / 'flatsim', packages / 'gazebo_msgs', packages / 'gazebo_msgs' / 'srv'):
        assert folder.is_dir() and not folder.is_symlink(), folder
    assert (packages / 'gazebo_msgs' / 'srv' / '__init__.py').is_symlink()
    assert not os.path.lexists(packages / 'flatsim' / '__pycache__')
