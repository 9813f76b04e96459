"""Checks on the workspace as a whole: lint, launch files, and the setup path."""
import pathlib
import re
import shutil
import subprocess

import pytest

TOP = pathlib.Path(__file__).resolve().parent.parent
SRC = TOP / 'catkin_ws' / 'src'
PACKAGES = sorted(p.parent for p in list(SRC.glob('*/package.xml')) + list(SRC.glob('*/*/package.xml')))
LAUNCH_FILES = sorted(p for p in SRC.rglob('*.launch') if 'test' not in p.parts)
# Debian ships roslaunch-check with roslaunch's scripts, not on PATH.
ROSLAUNCH_CHECK = shutil.which('roslaunch-check') or '/usr/share/roslaunch/scripts/roslaunch-check'


def run(cmd, **kwargs):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          check=False, **kwargs)


def test_workspace_has_the_course_packages():
    names = {p.name for p in PACKAGES}
    assert {'my_robot', 'ball_chaser', 'flatsim', 'gazebo_ros', 'xacro', 'turtlesim'} <= names


@pytest.mark.parametrize('package', PACKAGES, ids=lambda p: p.name)
def test_catkin_lint_is_clean(package):
    result = run(['catkin_lint', '-W2', '--strict', str(package)])
    assert result.returncode == 0, result.stdout
    assert 'warning' not in result.stdout and 'error' not in result.stdout, result.stdout


@pytest.mark.parametrize('launch_file', LAUNCH_FILES, ids=lambda p: '%s/%s' % (p.parts[-3], p.name))
def test_roslaunch_check_passes(launch_file):
    result = run([ROSLAUNCH_CHECK, str(launch_file)])
    assert result.returncode == 0 and 'FAILURE' not in result.stdout, result.stdout


def test_setup_is_idempotent():
    """Run after a completed setup, the script must skip every step."""
    result = run(['bash', str(TOP / 'setup.sh')], cwd=TOP)
    assert result.returncode == 0, result.stdout
    steps = [line for line in result.stdout.splitlines() if line.startswith('[setup]     ')]
    # One line for each numbered step, whatever their number.
    numbered = [line for line in result.stdout.splitlines() if re.match(r'\[setup\] \d+/\d+ ', line)]
    assert len(steps) == len(numbered) == 7, result.stdout
    assert all('skipping' in line for line in steps), result.stdout
