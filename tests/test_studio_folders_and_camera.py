"""The studio's folder chooser commands (list_folder in a fresh home, make_folder) and the
world's gui camera pose, without a browser or a ROS master."""
import logging
import os
from types import SimpleNamespace

import pytest

from flatsim.loading.sdf_world import load_world
from flatsim.studio.editors import Editors
from flatsim.studio.protocol import CommandError
from flatsim.studio.world import gui_camera_pose

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
EMPTY_WORLD = os.path.join(TOP, 'catkin_ws', 'src', 'my_robot', 'worlds', 'empty.world')


class Registry:
    def add(self, *args, **fields):
        pass


@pytest.fixture
def editors(tmp_path, monkeypatch):
    monkeypatch.setenv('HOME', str(tmp_path))
    hub = SimpleNamespace(log=logging.getLogger('test'), registry=Registry(), sessions={})
    return Editors(hub)


def request(**args):
    return SimpleNamespace(args=args, session=SimpleNamespace(label='window 1'))


def test_listing_the_model_folder_in_a_fresh_home_makes_it_and_lists_worlds(editors, tmp_path):
    (tmp_path / 'mine.world').write_text('<sdf/>')
    (tmp_path / 'notes.txt').write_text('')
    models = tmp_path / '.gazebo' / 'models'
    listed = editors.on_list_folder(request(path=str(models)))
    assert models.is_dir() and listed['path'] == str(models) and listed['folders'] == []
    home = editors.on_list_folder(request())
    assert home['path'] == str(tmp_path)
    assert home['folders'] == ['.gazebo'] and home['files'] == ['mine.world']
    # Any other folder that is not there is still refused, and not made.
    with pytest.raises(CommandError, match='cannot open the folder .*missing'):
        editors.on_list_folder(request(path=str(tmp_path / 'missing')))
    assert not (tmp_path / 'missing').exists()


def test_new_folder_is_made_in_a_pickable_folder_and_bad_names_are_refused(editors, tmp_path):
    made = editors.on_make_folder(request(path=str(tmp_path), name='worlds'))
    assert made == {'path': str(tmp_path / 'worlds')} and (tmp_path / 'worlds').is_dir()
    with pytest.raises(CommandError, match='is there already'):
        editors.on_make_folder(request(path=str(tmp_path), name='worlds'))
    for name in ('a/b', '..', ' '):
        with pytest.raises(CommandError, match="a folder name holds no '/'"):
            editors.on_make_folder(request(path=str(tmp_path), name=name))
    with pytest.raises(CommandError, match='files may not be saved in the root folder'):
        editors.on_make_folder(request(path='/', name='evil'))
    assert not os.path.exists('/evil')
    assert sorted(os.listdir(tmp_path)) == ['worlds']


def test_the_gui_camera_pose_is_read_from_the_world(tmp_path):
    assert gui_camera_pose(load_world(EMPTY_WORLD)) == pytest.approx([-3.0, -3.0, 2.5, 0.0, 0.5, 0.785398], abs=1e-4)
    plain = tmp_path / 'plain.world'
    plain.write_text('<sdf version="1.6"><world name="default"><gui><camera name="c"/></gui></world></sdf>')
    assert gui_camera_pose(load_world(str(plain))) is None
    assert gui_camera_pose(None) is None
