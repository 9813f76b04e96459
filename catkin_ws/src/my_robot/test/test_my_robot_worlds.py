"""The worlds: SDF 1.6 as Gazebo saves it, one white ball and nothing else
white, a state block that agrees with the models, and a floor plan where the
robot starts free with the ball in view and can reach every room."""
import math
import pathlib
import xml.etree.ElementTree as ET

import cv2
import numpy as np
import pytest

PACKAGE_DIR = pathlib.Path(__file__).resolve().parent.parent
HOUSE = PACKAGE_DIR / 'worlds' / 'chase_house.world'
EMPTY = PACKAGE_DIR / 'worlds' / 'empty.world'
COLOUR_TAGS = ('ambient', 'diffuse', 'specular', 'emissive')

# Occupancy raster of the plane the robot drives in.
CELL = 0.02
X_RANGE, Y_RANGE = (-5.0, 9.0), (-6.0, 6.0)
ROBOT_CLEARANCE = 0.3     # covers the chassis and wheels from the footprint origin
WORKING_HEIGHT = 0.3      # anything with a part below this blocks the robot
ROOM_CENTRES = {'hall': (-1.0, 1.5), 'office': (5.5, 2.3), 'store': (5.5, -1.7), 'kitchen': (-1.0, -2.8)}
OUTSIDE = (8.0, 5.0)


def numbers(text):
    return [float(v) for v in text.split()]


def pose_of(element):
    found = element.find('pose')
    values = numbers(found.text) if found is not None else [0.0] * 6
    assert values[3:5] == [0, 0], 'only yaw rotations are expected in this world'
    return values[0], values[1], values[2], values[5]


def compose(parent, child):
    px, py, pz, pyaw = parent
    cx, cy, cz, cyaw = child
    c, s = math.cos(pyaw), math.sin(pyaw)
    return px + c * cx - s * cy, py + s * cx + c * cy, pz + cz, pyaw + cyaw


@pytest.fixture(scope='module')
def world():
    root = ET.parse(HOUSE).getroot()
    assert root.tag == 'sdf'
    return root.find('world')


def models(world):
    return {m.get('name'): m for m in world.findall('model')}


def state_models(world):
    return {m.get('name'): m for m in world.find('state').findall('model')}


def link_world_poses(world):
    """(model, link) -> the link's world pose as the state block records it."""
    return {(m.get('name'), link.get('name')): pose_of(link)
            for m in world.find('state').findall('model') for link in m.findall('link')}


@pytest.fixture(scope='module')
def occupancy(world):
    width = int((X_RANGE[1] - X_RANGE[0]) / CELL)
    height = int((Y_RANGE[1] - Y_RANGE[0]) / CELL)
    grid = np.zeros((height, width), np.uint8)

    def to_px(points):
        pts = np.asarray(points, dtype=float)
        cols = (pts[:, 0] - X_RANGE[0]) / CELL
        rows = (Y_RANGE[1] - pts[:, 1]) / CELL
        return np.round(np.stack([cols, rows], axis=1)).astype(np.int32)

    link_poses = link_world_poses(world)
    for name, model in models(world).items():
        if name in ('ground_plane', 'white_ball'):
            continue
        for link in model.findall('link'):
            for collision in link.findall('collision'):
                x, y, z, yaw = compose(link_poses[(name, link.get('name'))], pose_of(collision))
                box = collision.find('geometry/box/size')
                cylinder = collision.find('geometry/cylinder')
                if box is not None:
                    sx, sy, sz = numbers(box.text)
                    if z - sz / 2 >= WORKING_HEIGHT:
                        continue
                    corners = np.array([[sx, sy], [-sx, sy], [-sx, -sy], [sx, -sy]]) / 2
                    rot = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
                    cv2.fillPoly(grid, [to_px(corners @ rot.T + [x, y])], 1)
                elif cylinder is not None:
                    radius = float(cylinder.findtext('radius'))
                    if z - float(cylinder.findtext('length')) / 2 >= WORKING_HEIGHT:
                        continue
                    cv2.circle(grid, tuple(to_px([[x, y]])[0]), int(round(radius / CELL)), 1, -1)
    return grid, to_px


def ball(world):
    return models(world)['white_ball']


def test_worlds_are_single_sdf_1_6_worlds():
    for path in (HOUSE, EMPTY):
        root = ET.parse(path).getroot()
        assert (root.tag, root.get('version')) == ('sdf', '1.6'), path.name
        assert len(root.findall('world')) == 1


def test_ground_and_sun_are_written_out_not_included(world):
    assert world.find('include') is None
    ground = models(world)['ground_plane']
    assert ground.findtext('static') == '1'
    assert ground.find('link/collision/geometry/plane') is not None
    sun = world.find("light[@name='sun']")
    assert sun.get('type') == 'directional'


def test_exactly_one_white_thing_and_it_is_the_ball(world):
    whites = [e for e in world.iter() if e.tag in COLOUR_TAGS and numbers(e.text)[:3] == [1, 1, 1]]
    in_ball = [e for tag in COLOUR_TAGS for e in ball(world).iter(tag)]
    assert len(in_ball) == 4
    assert whites == in_ball
    assert all(numbers(e.text) == [1, 1, 1, 1] for e in in_ball)


def test_the_ball_is_a_loose_ten_centimetre_sphere(world):
    the_ball = ball(world)
    assert the_ball.findtext('static') == '0'
    links = the_ball.findall('link')
    assert len(links) == 1
    assert float(links[0].findtext('inertial/mass')) == pytest.approx(0.5)
    for part in ('visual', 'collision'):
        assert float(links[0].findtext(part + '/geometry/sphere/radius')) == 0.1


def test_building_is_made_of_building_editor_walls(world):
    building = models(world)['building']
    assert building.findtext('static') == '1'
    walls = building.findall('link')
    assert len(walls) >= 10
    for index, wall in enumerate(walls):
        assert wall.get('name') == 'Wall_%d' % index
        sizes = {part: numbers(wall.findtext(part + '/geometry/box/size')) for part in ('collision', 'visual')}
        assert sizes['collision'] == sizes['visual']
        assert sizes['collision'][1:] == [0.15, 1.0]
        assert wall.findtext('visual/material/script/name') == 'Gazebo/Grey'
        assert numbers(wall.findtext('visual/material/ambient'))[:3] != [1, 1, 1]


def test_furniture_includes_a_table_a_shelf_and_a_round_pillar(world):
    found = models(world)
    for name in ('table', 'shelf', 'pillar'):
        assert found[name].findtext('static') == '1'
    assert found['pillar'].find('link/collision/geometry/cylinder') is not None
    assert len(found['table'].findall('link/collision')) == 5


def test_every_state_entry_matches_a_model_and_its_links(world):
    defined = models(world)
    recorded = state_models(world)
    assert set(recorded) == set(defined)
    for name, entry in recorded.items():
        assert {link.get('name') for link in entry.findall('link')} == \
            {link.get('name') for link in defined[name].findall('link')}


def test_state_link_poses_are_the_model_poses_composed(world):
    defined = models(world)
    for name, entry in state_models(world).items():
        model_pose = pose_of(entry)
        assert model_pose == pytest.approx(pose_of(defined[name]))
        for link in entry.findall('link'):
            local = pose_of(defined[name].find("link[@name='%s']" % link.get('name')))
            assert pose_of(link) == pytest.approx(compose(model_pose, local), abs=1e-5)


def test_house_is_about_ten_by_eight_metres(world):
    poses = link_world_poses(world)
    ends = []
    for wall in models(world)['building'].findall('link'):
        x, y, _, yaw = poses[('building', wall.get('name'))]
        half = numbers(wall.findtext('collision/geometry/box/size'))[0] / 2
        ends += [(x + half * math.cos(yaw), y + half * math.sin(yaw)),
                 (x - half * math.cos(yaw), y - half * math.sin(yaw))]
    span = np.ptp(np.array(ends), axis=0)
    assert span == pytest.approx([10.15, 8.15], abs=0.01)


def test_spawn_point_is_clear(occupancy):
    grid, to_px = occupancy
    col, row = to_px([[0.0, 0.0]])[0]
    free = np.ones_like(grid)
    free[grid > 0] = 0
    distance = cv2.distanceTransform(free, cv2.DIST_L2, 5)
    assert distance[row, col] * CELL > ROBOT_CLEARANCE


def test_ball_is_in_plain_view_two_to_three_metres_ahead(world, occupancy):
    grid, to_px = occupancy
    bx, by, _, _ = link_world_poses(world)[('white_ball', 'link')]
    assert 2.0 <= math.hypot(bx, by) <= 3.0
    assert abs(math.atan2(by, bx)) < 1.3962634 / 2
    line = np.zeros_like(grid)
    cv2.line(line, tuple(to_px([[0, 0]])[0]), tuple(to_px([[bx, by]])[0]), 1, 1)
    assert not np.any(grid & line)


def test_every_room_is_reachable_and_the_house_is_closed(occupancy):
    grid, to_px = occupancy
    kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * int(ROBOT_CLEARANCE / CELL) + 1,) * 2)
    blocked = cv2.dilate(grid, kernel)
    mask = np.zeros((blocked.shape[0] + 2, blocked.shape[1] + 2), np.uint8)
    reach = blocked.copy()
    cv2.floodFill(reach, mask, tuple(int(v) for v in to_px([[0, 0]])[0]), 2)
    for room, centre in ROOM_CENTRES.items():
        col, row = to_px([centre])[0]
        assert reach[row, col] == 2, room
    col, row = to_px([OUTSIDE])[0]
    assert reach[row, col] == 0


def test_empty_world_holds_only_ground_and_sun():
    world = ET.parse(EMPTY).getroot().find('world')
    assert world.findall('model') == []
    assert sorted(i.findtext('uri') for i in world.findall('include')) == ['model://ground_plane', 'model://sun']
