"""Fixtures shared by flatsim's unit tests."""
import os

import pytest


@pytest.fixture
def home(tmp_path, monkeypatch):
    """A fresh HOME (for ~/.gazebo) and no GAZEBO_MODEL_PATH, so only the test's model folders count."""
    monkeypatch.setenv('HOME', str(tmp_path / 'home'))
    monkeypatch.delenv('GAZEBO_MODEL_PATH', raising=False)
    os.makedirs(tmp_path / 'home')
    return str(tmp_path / 'home')
