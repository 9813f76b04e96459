"""rosdep answers offline, from the rules ./setup.sh registers (env/rosdep_rules.py).

The course's commands, as it gives them: `rosdep check <pkg>` and
`rosdep install -i <pkg>` with the workspace sourced, and
`rosdep install --from-paths src --ignore-src -y` from the workspace's root.
Installs run with --simulate, so the tests print rosdep's plan and change nothing.
"""
import os
import pathlib
import shutil
import subprocess

import pytest
import yaml

TOP = pathlib.Path(__file__).resolve().parent.parent
FIXTURES = pathlib.Path(__file__).resolve().parent / 'fixtures'
DEBIAN_RULES = '/usr/share/python3-rosdep2/debian.yaml'
# Proxies that lead nowhere: any download rosdep tried would fail.
NO_NETWORK = {'http_proxy': 'http://127.0.0.1:9', 'https_proxy': 'http://127.0.0.1:9',
              'HTTP_PROXY': 'http://127.0.0.1:9', 'HTTPS_PROXY': 'http://127.0.0.1:9'}


def rosdep(*args, cwd=None, package_path=None):
    env = dict(os.environ, **NO_NETWORK)
    if package_path:
        env['ROS_PACKAGE_PATH'] = os.pathsep.join([str(package_path), env.get('ROS_PACKAGE_PATH', '')])
    return subprocess.run(['rosdep'] + list(args), cwd=cwd, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=120, check=False)


def installed(package):
    status = subprocess.run(['dpkg-query', '-W', '-f=${Status}', package], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True, check=False).stdout
    return status == 'install ok installed'


@pytest.fixture(scope='module')
def missing():
    """The Debian packages of ball_tracker's one uninstalled key, image_geometry."""
    with open(DEBIAN_RULES) as rules:
        packages = yaml.safe_load(rules)['image_geometry']['debian']
    assert not any(installed(p) for p in packages), (
        'image_geometry is installed on this machine; the fixture needs a dependency that is not')
    return packages


@pytest.fixture
def workspace(tmp_path):
    """A student's catkin_ws holding ball_tracker, with src on ROS_PACKAGE_PATH as if sourced."""
    shutil.copytree(FIXTURES / 'ball_tracker', tmp_path / 'src' / 'ball_tracker')
    return tmp_path


def test_rosdep_is_this_environments():
    assert shutil.which('rosdep') == str(TOP / 'env' / 'bin' / 'rosdep')


def test_update_works_without_network():
    result = rosdep('update')
    assert result.returncode == 0, result.stdout
    assert 'ERROR' not in result.stdout, result.stdout


def test_check_names_the_missing_system_dependency(workspace, missing):
    result = rosdep('check', 'ball_tracker', package_path=workspace / 'src')
    assert result.returncode != 0, result.stdout
    assert 'System dependencies have not been satisfied' in result.stdout, result.stdout
    reported = sorted(line.split('\t')[1] for line in result.stdout.splitlines() if line.startswith('apt\t'))
    # roscpp, cv_bridge and numpy are installed; the stand-ins and Gazebo's plugins are provided.
    assert reported == sorted(missing), result.stdout


def planned_installs(output, command):
    """The packages of each `<command> <package>` line that rosdep install --simulate prints."""
    return sorted(line.strip()[len(command):].strip() for line in output.splitlines()
                  if line.strip().startswith(command))


def test_install_i_plans_the_apt_install(workspace, missing):
    result = rosdep('install', '-i', '--simulate', 'ball_tracker', package_path=workspace / 'src')
    assert result.returncode == 0, result.stdout
    assert planned_installs(result.stdout, 'apt-get install') == sorted(missing), result.stdout


def test_install_from_paths_plans_the_apt_install(workspace, missing):
    result = rosdep('install', '--from-paths', 'src', '--ignore-src', '-y', '--simulate', cwd=workspace)
    assert result.returncode == 0, result.stdout
    assert planned_installs(result.stdout, 'apt-get install -y') == sorted(missing), result.stdout


def test_a_key_nothing_provides_is_reported(tmp_path):
    package = tmp_path / 'src' / 'plugin_user'
    shutil.copytree(FIXTURES / 'ball_tracker', package)
    xml = package / 'package.xml'
    xml.write_text(xml.read_text().replace('ball_tracker', 'plugin_user')
                   .replace('<depend>image_geometry</depend>', '<depend>gazebo_dev</depend>'))
    result = rosdep('check', '--from-paths', 'src', '--ignore-src', cwd=tmp_path)
    assert 'Cannot locate rosdep definition for [gazebo_dev]' in result.stdout, result.stdout


def test_this_workspace_needs_nothing_more():
    # As docs/course.md gives it, from the checkout: every key resolves, none is only skipped.
    result = rosdep('check', '--from-paths', 'catkin_ws/src', '--ignore-src', cwd=TOP)
    assert result.returncode == 0, result.stdout
    assert result.stdout.strip() == 'All system dependencies have been satisfied', result.stdout


@pytest.mark.skipif(not (TOP / 'catkin_ws' / 'src' / 'simple_arm' / 'package.xml').is_file(),
                    reason='the simple_arm lesson package is not in this workspace')
def test_the_course_check_of_simple_arm():
    result = rosdep('check', 'simple_arm')
    assert result.returncode == 0, result.stdout
    assert result.stdout.strip() == 'All system dependencies have been satisfied', result.stdout
