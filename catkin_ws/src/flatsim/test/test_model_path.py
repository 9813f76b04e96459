"""Gazebo's model path, the Insert tab's list, gui.ini, and model:// includes in worlds and spawns."""
import math
import os

import pytest

from flatsim.loading import model_path as mp
from flatsim.loading.sdf_world import parse_sdf_models, parse_world

CONFIG = """<?xml version="1.0" ?>
<model>
  <name>{name}</name>
  <version>1.0</version>
  {sdf}
  <description>{description}</description>
</model>
"""
BOX_SDF = """<?xml version="1.0" ?>
<sdf version="1.6">
  <model name="{name}">
    <pose>0 0 0.5 0 0 0</pose>
    <link name="link">
      <collision name="collision"><geometry><box><size>1 2 1</size></box></geometry></collision>
      <visual name="visual"><geometry><box><size>1 2 1</size></box></geometry></visual>
    </link>
    {extra}
  </model>
</sdf>
"""


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, 'w') as stream:
        stream.write(text)


def make_model(root, folder, name=None, sdf_text=None, description='a box', extra='',
               sdf_entries='<sdf version="1.6">model.sdf</sdf>'):
    write(os.path.join(root, folder, 'model.config'),
          CONFIG.format(name=name or folder, sdf=sdf_entries, description=description))
    write(os.path.join(root, folder, 'model.sdf'),
          sdf_text if sdf_text is not None else BOX_SDF.format(name=folder, extra=extra))
    return os.path.join(root, folder)


# The model path

def test_model_path_is_in_gazebos_order(home, tmp_path, monkeypatch):
    monkeypatch.setenv('GAZEBO_MODEL_PATH', '/env/a::/env/b')
    write(os.path.join(home, '.gazebo', 'gui.ini'),
          '[geometry]\nx=0\n[model_paths]\nfilenames=/saved/one:/env/a:/saved/two\n')
    assert mp.model_path() == ['/env/a', '/env/b', '/saved/one', '/saved/two',
                               os.path.join(home, '.gazebo', 'models'), mp.shipped_models()]


def test_home_is_read_at_each_call(tmp_path, monkeypatch):
    monkeypatch.delenv('GAZEBO_MODEL_PATH', raising=False)
    for name in ('first', 'second'):
        monkeypatch.setenv('HOME', str(tmp_path / name))
        assert os.path.join(str(tmp_path / name), '.gazebo', 'models') in mp.model_path()


def test_an_unreadable_gui_ini_adds_no_folders(home):
    write(os.path.join(home, '.gazebo', 'gui.ini'), 'this is [not an ini\n= =\n')
    assert mp.gui_ini_model_paths() == []


def test_adding_a_folder_makes_gui_ini_when_missing(home):
    assert mp.add_to_gui_ini('/tmp/my_models')
    with open(os.path.join(home, '.gazebo', 'gui.ini')) as stream:
        assert stream.read() == '[model_paths]\nfilenames=/tmp/my_models\n'
    assert mp.gui_ini_model_paths() == ['/tmp/my_models']


def test_adding_a_folder_keeps_the_rest_of_gui_ini(home):
    before = ('; written by Gazebo\n[geometry]\nx=10\ny=20\n\n[model_paths]\nfilenames=/a:/b\n\n'
              '[other]\nkey=value\n')
    write(os.path.join(home, '.gazebo', 'gui.ini'), before)
    assert mp.add_to_gui_ini('/c/')
    assert not mp.add_to_gui_ini('/b')
    with open(os.path.join(home, '.gazebo', 'gui.ini')) as stream:
        assert stream.read() == before.replace('filenames=/a:/b', 'filenames=/a:/b:/c')
    assert mp.gui_ini_model_paths() == ['/a', '/b', '/c']


def test_adding_a_folder_to_a_section_without_filenames(home):
    write(os.path.join(home, '.gazebo', 'gui.ini'), '[model_paths]\n[geometry]\nx=1\n')
    mp.add_to_gui_ini('/m')
    with open(os.path.join(home, '.gazebo', 'gui.ini')) as stream:
        assert stream.read() == '[model_paths]\nfilenames=/m\n[geometry]\nx=1\n'


# The Insert tab's list

def test_listing_reads_names_descriptions_and_the_newest_readable_sdf(tmp_path):
    root = str(tmp_path)
    make_model(root, 'crate', name='Wooden Crate', description='  a   crate\n for tests ')
    make_model(root, 'multi', sdf_entries='<sdf version="1.4">old.sdf</sdf><sdf version="1.6">model.sdf</sdf>'
                                          '<sdf version="1.9">future.sdf</sdf>')
    os.makedirs(tmp_path / 'not_a_model' / 'src')
    crate, multi = mp.list_models([root])
    assert (crate.name, crate.description, crate.problem) == ('Wooden Crate', 'a crate for tests', '')
    assert crate.uri == 'model://crate' and crate.path == root
    assert crate.sdf == os.path.join(root, 'crate', 'model.sdf') and crate.sdf_version == '1.6'
    assert multi.sdf == os.path.join(root, 'multi', 'model.sdf') and not multi.problem


@pytest.mark.parametrize('config, sdf, problem', [
    (None, BOX_SDF.format(name='m', extra=''), 'no model.config'),
    ('<model><name>m</name>', BOX_SDF.format(name='m', extra=''), 'model.config cannot be read'),
    ('<model><name>m</name></model>', BOX_SDF.format(name='m', extra=''), 'names no <sdf> file'),
    (CONFIG.format(name='m', sdf='<sdf version="1.6">model.sdf</sdf>', description=''), None,
     'model.sdf is missing'),
    (CONFIG.format(name='m', sdf='<sdf version="1.6">model.sdf</sdf>', description=''), '<sdf><model>',
     'model.sdf cannot be read'),
    (CONFIG.format(name='m', sdf='<sdf version="1.6">model.sdf</sdf>', description=''), '<robot name="r"/>',
     'model.sdf has <robot> at its root, not <sdf>'),
    (CONFIG.format(name='m', sdf='<sdf version="1.6">model.sdf</sdf>', description=''), '<sdf version="1.6"/>',
     'model.sdf holds no <model>'),
])
def test_a_malformed_model_folder_is_listed_with_its_problem(tmp_path, config, sdf, problem):
    folder = tmp_path / 'broken'
    os.makedirs(folder)
    if config is not None:
        write(str(folder / 'model.config'), config)
    if sdf is not None:
        write(str(folder / 'model.sdf'), sdf)
    elif config is None:
        write(str(folder / 'other.sdf'), '<sdf/>')
    make_model(str(tmp_path), 'good')
    broken, good = mp.list_models([str(tmp_path)])
    assert problem in broken.problem and broken.name in ('m', 'broken')
    assert good.problem == ''


def test_listing_includes_the_shipped_models_and_skips_missing_folders(home):
    entries = {entry.uri: entry for entry in mp.list_models()}
    assert entries['model://ground_plane'].name == 'Ground Plane' and not entries['model://ground_plane'].problem
    assert entries['model://sun'].name == 'Sun' and not entries['model://sun'].problem


def test_find_model_takes_the_first_folder_on_the_path(tmp_path):
    first, second = str(tmp_path / 'first'), str(tmp_path / 'second')
    make_model(first, 'crate', name='first crate')
    make_model(second, 'crate', name='second crate')
    assert mp.find_model('crate', [first, second]).name == 'first crate'
    assert mp.find_model('crate', [str(tmp_path / 'missing'), second]).name == 'second crate'
    assert mp.find_model('../first/crate', [second]) is None
    assert mp.find_model('nothing', [first]) is None


# Includes

def world_with(body, version='1.6'):
    return '<sdf version="%s"><world name="w">%s</world></sdf>' % (version, body)


def test_an_include_loads_the_model_with_its_overrides(tmp_path):
    make_model(str(tmp_path), 'crate')
    spec = parse_world(world_with(
        '<include><uri>model://crate</uri><name>crate_7</name><pose>1 2 0.25 0 0 1.5</pose>'
        '<static>true</static></include>'), model_paths=[str(tmp_path)])
    crate = spec.model('crate_7')
    assert crate is not None and crate.static and not spec.skipped
    assert (crate.pose.x, crate.pose.y, crate.pose.z, crate.pose.yaw) == pytest.approx((1, 2, 0.25, 1.5))
    assert crate.collisions[0].size == (1.0, 2.0, 1.0)
    assert crate.element.get('name') == 'crate_7' and crate.element.findtext('static') == 'true'
    assert [part.model for part in spec.parts] == ['crate_7']


def test_an_include_without_overrides_keeps_the_models_own(tmp_path):
    make_model(str(tmp_path), 'crate')
    spec = parse_world(world_with('<include><uri>model://crate/</uri></include>'), model_paths=[str(tmp_path)])
    crate = spec.model('crate')
    assert crate.pose.z == pytest.approx(0.5) and not crate.static


def test_nested_includes_are_read_into_the_including_model(tmp_path):
    root = str(tmp_path)
    make_model(root, 'leg')
    make_model(root, 'table', extra='<include><uri>model://leg</uri><name>leg_a</name>'
                                    '<pose>3 0 0 0 0 0</pose></include>')
    spec = parse_world(world_with('<include><uri>model://table</uri><pose>0 5 0 0 0 0</pose></include>'),
                       model_paths=[root])
    table = spec.model('table')
    assert [link for link, _ in table.links] == ['link', 'leg_a::link']
    leg = [geom for geom in table.collisions if geom.link == 'leg_a::link'][0]
    assert (leg.pose.x, leg.pose.y) == pytest.approx((3.0, 0.0))
    assert table.element.find('model').get('name') == 'leg_a'


def test_a_model_that_includes_itself_stops_at_the_bound(tmp_path):
    make_model(str(tmp_path), 'loop', extra='<include><uri>model://loop</uri><name>inner</name></include>')
    spec = parse_world(world_with('<include><uri>model://loop</uri></include>'), model_paths=[str(tmp_path)])
    assert spec.model('loop') is not None
    assert any('includes nested deeper' in item.reason for item in spec.skipped)


def test_an_unresolved_include_is_reported_as_before(tmp_path):
    spec = parse_world(world_with('<include><uri>model://bookshelf</uri><name>shelf_1</name></include>'
                                  '<include><uri>model://ground_plane</uri></include>'),
                       model_paths=[str(tmp_path)])
    assert [str(item) for item in spec.skipped] == [
        "include model://bookshelf (as shelf_1): needs Gazebo's model database, which flatsim does "
        "not read; left out"]
    assert spec.ground_plane and spec.models == []
    assert [part.element.tag for part in spec.parts] == ['include', 'include']


def test_an_include_of_a_broken_model_folder_names_its_problem(tmp_path):
    make_model(str(tmp_path), 'broken', sdf_text='<sdf><model name="b">')
    spec = parse_world(world_with('<include><uri>model://broken</uri></include>'), model_paths=[str(tmp_path)])
    (item,) = spec.skipped
    assert item.subject == 'include model://broken'
    assert 'model.sdf cannot be read' in item.reason and str(tmp_path) in item.reason


def test_an_included_light_is_kept_as_a_world_element(tmp_path):
    write(str(tmp_path / 'lamp' / 'model.config'),
          CONFIG.format(name='lamp', sdf='<sdf version="1.6">model.sdf</sdf>', description=''))
    write(str(tmp_path / 'lamp' / 'model.sdf'),
          '<sdf version="1.6"><light name="lamp" type="point"><pose>0 0 3 0 0 0</pose></light></sdf>')
    spec = parse_world(world_with('<include><uri>model://lamp</uri><name>lamp_2</name></include>'),
                       model_paths=[str(tmp_path)])
    (part,) = spec.parts
    assert part.element.tag == 'light' and part.element.get('name') == 'lamp_2' and not spec.skipped


def test_a_spawned_sdf_resolves_its_includes(tmp_path):
    root = str(tmp_path)
    make_model(root, 'leg')
    models, skipped = parse_sdf_models(BOX_SDF.format(
        name='table', extra='<include><uri>model://leg</uri></include>'), model_paths=[root])
    assert not skipped and [link for link, _ in models[0].links] == ['link', 'leg::link']


def test_a_spawned_world_include_gives_the_model(tmp_path):
    """What spawn_model -database NAME sends."""
    make_model(str(tmp_path), 'crate')
    models, skipped = parse_sdf_models(
        '<sdf version="1.5"><world name="default"><include><uri>model://crate</uri></include></world></sdf>',
        model_paths=[str(tmp_path)])
    assert [model.name for model in models] == ['crate'] and not skipped
    assert models[0].pose.z == pytest.approx(0.5) and not math.isnan(models[0].mass)


def test_the_spawn_service_takes_an_include_on_the_path_and_names_the_path_otherwise(home, tmp_path,
                                                                                     monkeypatch):
    from flatsim.ros.gazebo_api import sdf_spawn_obstacle
    make_model(str(tmp_path / 'models'), 'crate')
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(tmp_path / 'models'))
    database = '<sdf version="1.5"><world name="default"><include><uri>model://%s</uri></include></world></sdf>'
    assert sdf_spawn_obstacle(database % 'crate') is None
    reason = sdf_spawn_obstacle(database % 'bookshelf')
    assert reason.startswith('flatsim has no model database to resolve model://bookshelf, and no folder of '
                             'that name is on the model path (%s:' % (tmp_path / 'models'))


def unreadable(monkeypatch, *folders):
    """os.listdir refuses folders, as it does another user's folder of mode 700 (the tests may
    run as root, whom no mode keeps out)."""
    real = os.listdir
    refused = {os.path.normpath(str(folder)) for folder in folders}

    def listdir(path='.'):
        if os.path.normpath(str(path)) in refused:
            raise PermissionError(13, 'Permission denied', str(path))
        return real(path)
    monkeypatch.setattr(mp.os, 'listdir', listdir)


def test_an_unreadable_folder_is_listed_with_the_reason(tmp_path, monkeypatch):
    make_model(str(tmp_path), 'good')
    os.makedirs(tmp_path / 'locked')
    unreadable(monkeypatch, tmp_path / 'locked', tmp_path / 'locked_path')
    os.makedirs(tmp_path / 'locked_path')
    listed = {entry.name: entry for entry in mp.list_models([str(tmp_path), str(tmp_path / 'locked_path'),
                                                             str(tmp_path / 'missing')])}
    assert listed['locked'].problem == 'the folder cannot be read (Permission denied)'
    assert listed['locked'].folder == str(tmp_path / 'locked')
    assert listed['locked_path'].problem == 'this model path folder cannot be read (Permission denied)'
    assert listed['good'].problem == ''
    assert 'missing' not in listed
