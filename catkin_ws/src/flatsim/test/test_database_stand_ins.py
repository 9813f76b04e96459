"""The stand-ins flatsim ships for the most used models of Gazebo's online model database."""
import os

import pytest

from flatsim.loading import model_path as mp
from flatsim.loading.sdf_world import parse_world
from flatsim.studio.editors import model_list

STAND_INS = ('cafe_table', 'cardboard_box', 'coke_can', 'construction_barrel', 'construction_cone',
             'oak_tree', 'person_walking', 'plastic_cup', 'table_marble', 'turtlebot')


def include(name, extra=''):
    return ('<sdf version="1.6"><world name="w"><include><uri>model://%s</uri>%s</include>'
            '</world></sdf>' % (name, extra))


def test_an_include_of_cafe_table_resolves_to_the_shipped_stand_in(home):
    world = parse_world(include('cafe_table', '<name>table_1</name><pose>2 1 0 0 0 0</pose>'))
    assert world.skipped == []
    (table,) = world.models
    assert table.name == 'table_1' and table.static
    assert (table.pose.x, table.pose.y) == (2.0, 1.0)
    # The database model's own collisions: a 0.913 m top at 0.755 m on a column and a base.
    shapes = sorted((geom.size, round(geom.pose.z, 3)) for geom in table.collisions)
    assert shapes == [((0.042, 0.042, 0.74), 0.37), ((0.56, 0.56, 0.04), 0.02),
                      ((0.913, 0.913, 0.04), 0.755)]
    assert len(table.visuals) == 3


def test_a_cafe_table_elsewhere_on_the_model_path_wins_over_the_stand_in(home, tmp_path, monkeypatch):
    folder = tmp_path / 'models' / 'cafe_table'
    folder.mkdir(parents=True)
    (folder / 'model.config').write_text('<model><name>mine</name><sdf version="1.6">model.sdf</sdf>'
                                         '</model>')
    (folder / 'model.sdf').write_text(
        '<sdf version="1.6"><model name="mine"><static>1</static><link name="l"><collision name="c">'
        '<geometry><box><size>2 2 2</size></box></geometry></collision></link></model></sdf>')
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(tmp_path / 'models'))
    (table,) = parse_world(include('cafe_table')).models
    assert [geom.size for geom in table.collisions] == [(2.0, 2.0, 2.0)]
    assert mp.find_model('cafe_table').folder == str(folder)


@pytest.mark.parametrize('name', STAND_INS)
def test_each_stand_in_loads_with_shapes_and_nothing_left_out(home, name):
    world = parse_world(include(name))
    assert world.skipped == []
    (model,) = world.models
    assert model.collisions and model.visuals
    # Stand-ins stand on the floor: nothing below it, something above it.
    assert min(geom.pose.z for geom in model.collisions) > 0


def test_the_insert_tab_offers_the_stand_ins_as_a_library(home):
    listed = {entry['uri']: entry for entry in model_list()['models']}
    for name in STAND_INS:
        entry = listed['model://%s' % name]
        assert entry['problem'] == '' and entry['path'] == mp.shipped_models()
        assert 'online model database' in entry['description']
    assert os.path.basename(mp.model_path()[-1]) == 'models'
