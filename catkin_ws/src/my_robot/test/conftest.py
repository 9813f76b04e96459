"""Fixtures for my_robot's file checks: expanded robot descriptions and parsed worlds."""
import os
import pathlib
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

PACKAGE_DIR = pathlib.Path(__file__).resolve().parent.parent
ROBOT_XACRO = PACKAGE_DIR / 'urdf' / 'my_robot.xacro'


def xacro_executable():
    beside_python = pathlib.Path(sys.executable).with_name('xacro')
    if beside_python.exists():
        return str(beside_python)
    found = shutil.which('xacro')
    if found is None:
        pytest.fail('the xacro command (pip package xacro==1.13.3) is not installed')
    return found


def run_xacro(*args):
    """Runs xacro as the launch file does, with $(find my_robot) resolving to this source tree."""
    env = dict(os.environ)
    env['ROS_PACKAGE_PATH'] = os.pathsep.join(
        [str(PACKAGE_DIR.parent)] + [p for p in env.get('ROS_PACKAGE_PATH', '').split(os.pathsep) if p])
    return subprocess.run([xacro_executable(), str(ROBOT_XACRO)] + list(args), env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, check=False)


@pytest.fixture(scope='session', name='run_xacro')
def run_xacro_fixture():
    return run_xacro


@pytest.fixture(scope='session')
def expanded_urdf():
    """drive -> URDF text, expanded once per session."""
    cache = {}

    def expand(drive):
        if drive not in cache:
            result = run_xacro('drive:=%s' % drive)
            assert result.returncode == 0, result.stderr
            cache[drive] = result.stdout
        return cache[drive]
    return expand


@pytest.fixture(scope='session')
def urdf_root(expanded_urdf):
    return lambda drive: ET.fromstring(expanded_urdf(drive))
