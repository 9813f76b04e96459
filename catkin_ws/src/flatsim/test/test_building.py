"""The Building Editor's output: walls cut around doors and windows, read by flatsim as colliders."""
import math
import os
import xml.etree.ElementTree as ET

import numpy as np
import pytest

import sdf_check
from flatsim.authoring import building as bd
from flatsim.authoring import model_writer as mw
from flatsim.errors import AuthoringError
from flatsim.loading.config import LaserConfig
from flatsim.loading.sdf_world import load_world, parse_world
from flatsim.sensors.lidar import Lidar
from flatsim.world.sim import Simulation

# A 4 m x 3 m room, walls drawn anticlockwise from the origin, a door in the
# middle of the south wall and a window in the east wall.
ROOM = [bd.Wall((0, 0), (4, 0)), bd.Wall((4, 0), (4, 3)), bd.Wall((4, 3), (0, 3)), bd.Wall((0, 3), (0, 0))]
HALF = bd.WALL_THICKNESS / 2
LIDAR_Z = 0.25


def save(design, allowed_folders, folder):
    """The building's model folder, written as the studio's save_building writes it
    (flatsim.studio.editors)."""
    sdf = bd.building_sdf(design)    # checked first, as the studio checks it
    return mw.save_model_files(design.name, bd.building_config(design), sdf, allowed_folders, folder)



def room(openings=None):
    return bd.BuildingDesign('house', [bd.Wall(w.start, w.end) for w in ROOM],
                             [bd.door(0, 2.0), bd.window(1, 1.5)] if openings is None else openings)


@pytest.fixture
def house_world(tmp_path, monkeypatch):
    """The room saved as Gazebo saves a building, and a world that includes it."""
    home = tmp_path / 'home'
    models = home / 'building_editor_models'
    os.makedirs(models)
    monkeypatch.setenv('HOME', str(home))
    monkeypatch.setenv('GAZEBO_MODEL_PATH', str(models))
    save(room(), [str(home)], str(models))
    world = tmp_path / 'house.world'
    world.write_text('<sdf version="1.6"><world name="default"><include><uri>model://house</uri>'
                     '</include></world></sdf>')
    return load_world(str(world))


def scan(sim, x, y, angles):
    """Ranges from (x, y) at LIDAR_Z along world angles (a lidar facing +x)."""
    ranges = []
    for angle in angles:
        config = LaserConfig(samples=1, min_angle=angle, max_angle=angle, range_min=0.05, range_max=30.0)
        ranges.append(float(Lidar(config).scan(sim.scene, x, y, LIDAR_Z, 0.0)[0]))
    return ranges


def test_the_walls_are_named_and_cut_as_gazebo_does():
    model = ET.fromstring(bd.building_sdf(room())).find('model')
    assert model.findtext('static') == '1' and model.findtext('pose') == '2 1.5 0 0 0 0'
    links = model.findall('link')
    assert [link.get('name') for link in links] == ['Wall_0', 'Wall_1', 'Wall_2', 'Wall_3']
    # A door leaves the two sides and the lintel; a window also the sill.
    assert [v.get('name') for v in links[0].findall('visual')] == ['Wall_0_Visual_0', 'Wall_0_Visual_1',
                                                                  'Wall_0_Visual_2']
    assert [c.get('name') for c in links[1].findall('collision')] == [
        'Wall_1_Collision_0', 'Wall_1_Collision_1', 'Wall_1_Collision_2', 'Wall_1_Collision_3']
    assert [v.get('name') for v in links[2].findall('visual')] == ['Wall_2_Visual']
    assert links[2].findtext('collision/geometry/box/size') == '4.15 0.15 2.5'
    assert links[1].findtext('pose').split()[:2] == ['2', '0']
    assert float(links[1].findtext('pose').split()[5]) == pytest.approx(math.pi / 2)


def test_the_building_is_valid_sdf(tmp_path):
    assert sdf_check.problems(bd.building_sdf(room()), tmp_path) == []


def test_the_walls_are_colliders_a_lidar_hits_at_the_analytic_distance(house_world):
    assert not house_world.skipped
    sim = Simulation(house_world)
    house = sim.models['house']
    # Two door jambs, the wall under the window and the two beside it, and two whole walls;
    # the lintel and what is above the window stand above the robots.
    assert house.kind == 'static' and len(house.colliders) == 7
    x, y = 1.0, 1.0
    east, north, west = scan(sim, x, y, [0.0, math.pi / 2, math.pi])
    assert east == pytest.approx(4 - HALF - x, abs=1e-4)
    assert north == pytest.approx(3 - HALF - y, abs=1e-4)
    assert west == pytest.approx(x - HALF, abs=1e-4)
    # The wall beside the door: south of (1, 1) the door (1.55 to 2.45 m) is not in the way.
    (south,) = scan(sim, x, y, [-math.pi / 2])
    assert south == pytest.approx(y - HALF, abs=1e-4)


def test_the_door_lets_a_ray_through_and_the_window_sill_does_not(house_world):
    sim = Simulation(house_world)
    (through_door,) = scan(sim, 2.0, 1.5, [-math.pi / 2])
    assert math.isinf(through_door)
    (at_window,) = scan(sim, 2.0, 1.5, [0.0])
    assert at_window == pytest.approx(4 - HALF - 2.0, abs=1e-4)


def test_a_window_above_the_lidar_lets_the_ray_pass_over_its_sill():
    design = room([bd.window(1, 1.5, elevation=0.1, height=1.0)])
    sim = Simulation(load_world_text(design))
    (through_window,) = scan(sim, 2.0, 1.5, [0.0])
    assert math.isinf(through_window)


def load_world_text(design):
    model = ET.fromstring(bd.building_sdf(design)).find('model')
    return parse_world('<sdf version="1.7"><world name="w">%s</world></sdf>' % ET.tostring(model, encoding='unicode'),
                       model_paths=[])


def test_pieces_cover_the_wall_but_the_holes():
    wall = bd.Wall((0, 0), (4, 0), thickness=0.2, height=2.0)
    openings = [bd.door(0, 1.0, width=1.0, height=1.5), bd.window(0, 3.0, width=0.5, height=0.5, elevation=1.0)]
    pieces = bd.wall_pieces(wall, openings)
    area = sum(length * height for _, _, length, height in pieces)
    assert area == pytest.approx(4.2 * 2.0 - 1.0 * 1.5 - 0.5 * 0.5)
    for x, z, length, height in pieces:
        for opening in openings:
            low, high = opening.offset - 2.0 - opening.width / 2, opening.offset - 2.0 + opening.width / 2
            overlap_x = min(x + length / 2, high) - max(x - length / 2, low)
            overlap_z = min(z + height / 2, opening.elevation + opening.height) - max(z - height / 2, opening.elevation)
            assert overlap_x <= 1e-9 or overlap_z <= 1e-9


@pytest.mark.parametrize('change, message', [
    (lambda d: setattr(d, 'name', ''), 'building needs a name'),
    (lambda d: setattr(d, 'name', 'a/b'), "may not hold '/'"),
    (lambda d: setattr(d, 'walls', []), 'has no wall'),
    (lambda d: setattr(d.walls[2], 'end', (4, 3)), 'Wall_2 has no length'),
    (lambda d: setattr(d.walls[0], 'thickness', -0.1), 'Wall_0 thickness must be a positive number'),
    (lambda d: setattr(d.walls[0], 'height', 0.0), 'Wall_0 height must be a positive number'),
    (lambda d: setattr(d.walls[1], 'start', (float('nan'), 0)), 'Wall_1 start must be two finite numbers'),
    (lambda d: setattr(d.walls[1], 'end', (4, float('inf'))), 'Wall_1 end must be two finite numbers'),
    (lambda d: setattr(d.walls[0], 'color', (1, 1, 1)), 'Wall_0 colour must be four numbers'),
    (lambda d: setattr(d.walls[0], 'material', 'Gazebo/Gold'), 'Wall_0 material must be one of'),
    (lambda d: setattr(d.openings[0], 'offset', 3.7), 'door on Wall_0 does not fit: it spans 3.25 to 4.15'),
    (lambda d: setattr(d.openings[0], 'width', 0.0), 'door on Wall_0 width must be a positive number'),
    (lambda d: setattr(d.openings[1], 'elevation', 2.0), "window on Wall_1 does not fit: its top at 2.8"),
    (lambda d: setattr(d.openings[1], 'elevation', -0.5), 'window on Wall_1: elevation -0.5 is below the floor'),
    (lambda d: setattr(d.openings[1], 'offset', float('nan')), 'must be finite numbers'),
    (lambda d: setattr(d.openings[1], 'wall', 7), 'window on wall 7: there is no such wall'),
    (lambda d: d.openings.append(bd.window(0, 2.5)), 'window on Wall_0 overlaps another opening'),
])
def test_a_bad_building_gets_a_clear_error_and_writes_nothing(change, message, tmp_path):
    design = room()
    change(design)
    with pytest.raises(AuthoringError, match=message.replace('(', r'\(')):
        save(design, [str(tmp_path)], str(tmp_path))
    assert os.listdir(tmp_path) == []


def test_points_snap_to_the_grid_and_to_other_walls_ends():
    assert bd.snap_to_grid((0.13, 0.37)) == (0.25, 0.25)
    assert bd.snap_to_grid((1.1, -0.6), step=0.5) == (1.0, -0.5)
    walls = [bd.Wall((0.1, 0.1), (4.03, 0.02))]
    assert bd.snap_point((4.2, 0.1), walls) == (4.03, 0.02)
    assert bd.snap_point((4.4, 0.1), walls) == (4.5, 0.0)
    assert bd.snap_point((4.2, 0.1), walls, skip=0) == (4.25, 0.0)


def test_a_sloppily_drawn_room_is_closed_by_snapping():
    sloppy = bd.BuildingDesign('shed', [bd.Wall((0.02, -0.04), (3.1, 0.05)), bd.Wall((2.97, 0.1), (3.04, 2.1)),
                                        bd.Wall((3.2, 1.93), (0.1, 2.05)), bd.Wall((-0.05, 2.1), (0.1, 0.1))])
    snapped = bd.snap_design(sloppy)
    ends = [(wall.start, wall.end) for wall in snapped.walls]
    assert ends == [((0.0, 0.0), (3.0, 0.0)), ((3.0, 0.0), (3.0, 2.0)), ((3.0, 2.0), (0.0, 2.0)),
                    ((0.0, 2.0), (0.0, 0.0))]
    assert all(isinstance(value, float) for pair in ends for point in pair for value in point)
    assert np.isfinite(bd.wall_length(snapped.walls[0]))


def test_snapping_refuses_a_point_that_is_not_a_number():
    with pytest.raises(AuthoringError, match='two finite numbers'):
        bd.snap_point((float('nan'), 1.0), [])
