"""Fixtures shared by flatsim's unit tests."""
import os
import pathlib

import pytest

from flatsim.loading.urdf_robot import expand_xacro, load_robot

SRC = pathlib.Path(__file__).resolve().parents[2]
MY_ROBOT_XACRO = SRC / 'my_robot' / 'urdf' / 'my_robot.xacro'


@pytest.fixture
def home(tmp_path, monkeypatch):
    """A fresh HOME (for ~/.gazebo) and no GAZEBO_MODEL_PATH, so only the test's model folders count."""
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    monkeypatch.delenv('GAZEBO_MODEL_PATH', raising=False)
    os.makedirs(tmp_path / 'home')
    return str(tmp_path / 'home')


@pytest.fixture(scope='module')
def my_robot_spec():
    """The project's my_robot, loaded as flatsim loads it after xacro."""
    saved = pytest.MonkeyPatch()
    saved.setenv('ROS_PACKAGE_PATH', str(SRC))
    try:
        return load_robot(expand_xacro(MY_ROBOT_XACRO), name='my_robot')
    finally:
        saved.undo()
