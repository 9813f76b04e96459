"""Placements from the robot's own camera, among every collider flatsim simulates, and the reach
measured from the robot's outline to the ball's surface. Pure: no master."""
import math
import re

import pytest

from chase_tools import placement, reach
from chase_tools.placement import FreeSpace, RobotGeometry
from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import parse_world
from flatsim.loading.urdf_robot import load_robot

CAMERA_TOPIC = '/camera/rgb/image_raw'

# One 8 x 6 m room (inner faces at x = +-4, y = +-3) with a 1 m square pillar in the middle,
# saved as the Building Editor saves it: one static model.
ROOM = """<?xml version="1.0"?>
<sdf version="1.6"><world name="room">
  <model name="building"><static>1</static>
    <link name="l">
      <collision name="north"><pose>0 3.1 0.5 0 0 0</pose>
        <geometry><box><size>8.4 0.2 1</size></box></geometry></collision>
      <collision name="south"><pose>0 -3.1 0.5 0 0 0</pose>
        <geometry><box><size>8.4 0.2 1</size></box></geometry></collision>
      <collision name="east"><pose>4.1 0 0.5 0 0 0</pose>
        <geometry><box><size>0.2 6.4 1</size></box></geometry></collision>
      <collision name="west"><pose>-4.1 0 0.5 0 0 0</pose>
        <geometry><box><size>0.2 6.4 1</size></box></geometry></collision>
      <collision name="pillar"><pose>0 0 0.5 0 0 0</pose><geometry><box><size>1 1 1</size></box></geometry></collision>
    </link>
  </model>
  <model name="white_ball"><pose>1 1 0.1 0 0 0</pose>
    <link name="l"><collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision></link>
  </model>
</world></sdf>
"""
OPEN = """<?xml version="1.0"?>
<sdf version="1.6"><world name="open">
  <include><uri>model://ground_plane</uri></include>
  <model name="white_ball"><pose>1 1 0.1 0 0 0</pose>
    <link name="l"><collision name="c"><geometry><sphere><radius>0.1</radius></sphere></geometry></collision></link>
  </model>
</world></sdf>
"""


def robot_urdf(camera_xyz='0.2 0 0', camera_rpy='0 0 0', hfov=1.3962634, width=320, height=240):
    """A course-like robot: a 0.4 x 0.3 m chassis 0.1 m up, a camera link (with a 5 cm
    collision box) on a joint from the chassis."""
    return """<robot name="probe">
  <link name="robot_footprint"/>
  <joint name="chassis_joint" type="fixed"><origin xyz="0 0 0.1"/>
    <parent link="robot_footprint"/><child link="chassis"/></joint>
  <link name="chassis"><collision><geometry><box size="0.4 0.3 0.1"/></geometry></collision></link>
  <joint name="camera_joint" type="fixed"><origin xyz="%s" rpy="%s"/>
    <parent link="chassis"/><child link="camera"/></joint>
  <link name="camera"><collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision></link>
  <gazebo reference="camera"><sensor type="camera" name="camera1">
    <camera><horizontal_fov>%s</horizontal_fov><image><width>%d</width><height>%d</height></image></camera>
    <plugin name="c" filename="libgazebo_ros_camera.so"><cameraName>camera</cameraName>
      <imageTopicName>rgb/image_raw</imageTopicName></plugin>
  </sensor></gazebo>
</robot>""" % (camera_xyz, camera_rpy, hfov, width, height)


def robot(**kwargs):
    return RobotGeometry.from_urdf(robot_urdf(**kwargs), CAMERA_TOPIC)


@pytest.fixture(scope='module')
def room():
    return parse_world(ROOM)


@pytest.fixture(scope='module')
def room_space(room):
    return FreeSpace(room, keep_out={'white_ball'})


def plan(world, geometry, count=20, seed=1, **kwargs):
    places, _notes = placement.plan_placements(world, geometry, count, seed, 'white_ball', **kwargs)
    return places


def assert_whole_ball_in_view(space, geometry, places, ball_range=(1.0, 4.0)):
    for place in places:
        camera = geometry.camera.world(place.robot_x, place.robot_y, place.robot_yaw)
        ball = (place.ball_x, place.ball_y)
        assert placement.whole_ball_in_view(geometry.camera, camera, ball, 0.1, 0.1), place
        assert space.ball_edges_visible(camera[:2], ball, 0.1), place
        assert ball_range[0] <= math.hypot(ball[0] - camera[0], ball[1] - camera[1]) <= ball_range[1]
        outline = geometry.outline(place.robot_x, place.robot_y, place.robot_yaw)
        assert placement.polygon_distance(outline, [ball])[0] - 0.1 >= placement.START_GAP_M
        assert space.outline_clear(outline, placement.ROBOT_MARGIN_M - 1e-9)


# -- the robot's geometry -----------------------------------------------------------------

def test_the_camera_pose_comes_through_the_urdfs_joints_and_the_fov_from_the_sensor():
    urdf = robot_urdf(camera_xyz='1.0 0.1 0.05', camera_rpy='0 0.2 0.3', hfov=1.2, width=320, height=240)
    geometry = RobotGeometry.from_urdf(urdf, CAMERA_TOPIC)
    camera = geometry.camera
    assert (camera.x, camera.y, camera.z) == (pytest.approx(1.0), pytest.approx(0.1), pytest.approx(0.15))
    assert (camera.yaw, camera.pitch) == (pytest.approx(0.3), pytest.approx(0.2))
    assert camera.hfov == 1.2
    assert camera.vfov == pytest.approx(2 * math.atan(math.tan(0.6) * 240 / 320))
    # The outline is the one flatsim's physics simulates, camera box included.
    assert geometry.footprint == tuple(load_robot(urdf).footprint)
    assert max(x for x, _y in geometry.footprint) > 1.0
    assert geometry.note == ''


def test_a_robot_whose_camera_publishes_elsewhere_says_which_camera_was_used():
    urdf = robot_urdf().replace('rgb/image_raw', 'front/image')
    geometry = RobotGeometry.from_urdf(urdf, CAMERA_TOPIC)
    assert geometry.camera.x == pytest.approx(0.2)
    assert 'no camera of the robot publishes /camera/rgb/image_raw' in geometry.note
    assert 'camera/front/image' in geometry.note


# -- placements ----------------------------------------------------------------------------

def test_clearance_is_the_distance_to_the_nearest_wall_face(room_space):
    assert room_space.clearance(3.0, 1.0) == pytest.approx(1.0)   # the east wall's inner face at x = 4
    assert room_space.clearance(0.0, 2.5) == pytest.approx(0.5)   # north face at 3, pillar top at 0.5
    assert room_space.clearance(0.8, 0.8) == pytest.approx(math.hypot(0.3, 0.3))  # the pillar's corner
    assert room_space.clearance(0.0, 0.0) == 0.0                  # inside the pillar


def test_points_outside_the_walls_are_not_free(room_space):
    assert room_space.free(3.0, 1.0)
    assert not room_space.free(5.0, 0.0)
    assert not room_space.free(0.0, 2.7)  # inside, but within 0.5 m of the north wall


def test_the_pillar_blocks_the_corridor(room_space):
    assert not room_space.in_sight((-3.0, 0.0), (3.0, 0.0))
    assert room_space.in_sight((-3.0, 1.2), (3.0, 1.2))
    # The corridor is as wide as the robot: a line that grazes the pillar is blocked.
    assert not room_space.in_sight((-3.0, 0.6), (3.0, 0.6))


def refusals(error):
    """{why: count} of a placement refusal's text."""
    said = str(error).split('refused for: ')[1]
    return {why: int(count.replace(',', '')) for why, count in re.findall(r'(?:^|, )([^,(]+) \(([\d,]+)\)', said)}


def test_a_world_without_room_for_the_ball_is_refused_saying_why_the_draws_were(room):
    with pytest.raises(FlatsimError, match='no free placement') as refused:
        plan(room, robot(), count=1, ball_range=(11.0, 12.0))
    # The room is 8 m across: a ball 11 m from a camera inside it lies beyond its walls.
    counts = refusals(refused.value)
    assert sum(counts.values()) == placement.MAX_DRAWS
    assert max(counts, key=counts.get) == placement.NO_SIGHT
    assert 'is there a room' not in str(refused.value)


def test_a_camera_that_cannot_see_the_ball_at_its_height_is_refused_saying_so():
    # Pitched 1.2 rad up: the ball on the floor is never in its view, however large the room.
    with pytest.raises(FlatsimError) as refused:
        plan(parse_world(ROOM), robot(camera_rpy='0 -1.2 0'), count=1)
    reasons = refusals(refused.value)
    # Every draw that got past where the ball and the robot stand failed on the view.
    assert placement.BALL_OUT_OF_VIEW in reasons
    assert set(reasons) <= {placement.BALL_NOT_FREE, placement.ROBOT_OUTSIDE, placement.BALL_OUT_OF_VIEW}


def test_a_camera_1_m_ahead_of_the_base_sees_the_whole_ball_in_every_placement(room, room_space):
    ahead = robot(camera_xyz='1.0 0 0')
    places = plan(room, ahead)
    assert_whole_ball_in_view(room_space, ahead, places)
    # Judged from the base instead, some of these balls would lie beside or behind the camera.
    assert all(math.hypot(p.ball_x - p.robot_x, p.ball_y - p.robot_y) > 1.5 for p in places)


def test_a_camera_turned_sideways_puts_the_ball_to_the_robots_side(room, room_space):
    sideways = robot(camera_rpy='0 0 %r' % (math.pi / 2))
    places = plan(room, sideways)
    assert_whole_ball_in_view(room_space, sideways, places)
    for place in places:
        bearing = math.atan2(place.ball_y - place.robot_y, place.ball_x - place.robot_x)
        # To the left, within the camera's half field of view of straight left.
        assert abs(math.remainder(bearing - place.robot_yaw - math.pi / 2, 2 * math.pi)) < 0.7


def test_a_narrow_field_of_view_keeps_the_whole_ball_inside_it(room, room_space):
    narrow = robot(hfov=0.3)
    places = plan(room, narrow)
    assert_whole_ball_in_view(room_space, narrow, places)
    for place in places:
        camera = narrow.camera.world(place.robot_x, place.robot_y, place.robot_yaw)
        distance = math.hypot(place.ball_x - camera[0], place.ball_y - camera[1])
        off_axis = math.remainder(math.atan2(place.ball_y - camera[1], place.ball_x - camera[0]) - camera[2],
                                  2 * math.pi)
        assert abs(off_axis) + math.asin(0.1 / distance) <= 0.15 - placement.VIEW_MARGIN_RAD + 1e-9


def test_a_field_of_view_too_narrow_for_the_ball_is_refused_with_why(room):
    with pytest.raises(FlatsimError, match=r'field of view \(0.12 rad\) is too narrow to hold the whole ball'):
        plan(room, robot(hfov=0.12))


def test_a_wall_between_camera_and_ball_hides_it(room_space):
    # The pillar's corner (0.5, 0.5) stands between the camera and the ball's lower edge,
    # while the line to the ball's centre passes just above it.
    camera, ball = (-3.0, 0.51), (1.0, 0.51)
    assert room_space.clear_rays(camera, [ball])
    assert not room_space.ball_edges_visible(camera, ball, 0.1)
    assert room_space.ball_edges_visible((-3.0, 0.8), (3.0, 0.8), 0.1)


def test_no_placement_hides_the_ball_behind_the_pillar(room, room_space):
    geometry = robot()
    places = plan(room, geometry, count=40, seed=5)
    assert_whole_ball_in_view(room_space, geometry, places)


def test_a_building_saved_as_a_non_static_model_is_among_the_colliders(room):
    loose = parse_world(ROOM.replace('<model name="building"><static>1</static>',
                                     '<model name="building"><static>0</static>'))
    space = FreeSpace(loose, keep_out={'white_ball'})
    assert not space.open
    assert space.clearance(3.0, 1.0) == pytest.approx(1.0)    # the east wall's inner face at x = 4
    assert space.clearance(0.0, 0.0) == 0.0                    # inside the pillar
    places, notes = placement.plan_placements(loose, robot(), 10, 2, 'white_ball')
    assert notes == []
    assert places == plan(room, robot(), count=10, seed=2)
    assert all(-4 < p.robot_x < 4 and -3 < p.robot_y < 3 for p in places)


def test_a_building_with_a_floor_slab_gets_the_placements_of_the_same_building_without():
    # The Building Editor's floor: a slab 0.1 m thick under the whole room, which robots drive on.
    floored = parse_world(ROOM.replace(
        '<link name="l">',
        '<link name="Floor_0"><collision name="Floor_0_Collision"><pose>0 0 0.05 0 0 0</pose>'
        '<geometry><box><size>8.4 6.4 0.1</size></box></geometry></collision></link>'
        '<link name="l">', 1))
    space = FreeSpace(floored, keep_out={'white_ball'})
    assert space.clearance(3.0, 1.0) == pytest.approx(1.0)
    places, notes = placement.plan_placements(floored, robot(), 10, 2, 'white_ball')
    assert notes == []
    assert places == plan(room_world(), robot(), count=10, seed=2)
    assert all(-4 < p.robot_x < 4 and -3 < p.robot_y < 3 for p in places)


def room_world():
    return parse_world(ROOM)


def test_an_open_world_gets_placements_around_the_spawn_point():
    world = parse_world(OPEN)
    geometry = robot()
    places, notes = placement.plan_placements(world, geometry, 10, 0, 'white_ball', spawn=(5.0, -3.0))
    assert notes == ['the world has no colliders at working height: placements lie within 5 m of '
                     'the robot\'s spawn point (5.00, -3.00)']
    assert all(abs(p.robot_x - 5.0) <= 5.0 and abs(p.robot_y + 3.0) <= 5.0 for p in places)
    assert_whole_ball_in_view(FreeSpace(world, keep_out={'white_ball'}), geometry, places)


def test_the_same_seed_gives_the_same_placements(room):
    assert plan(room, robot(), seed=3) == plan(room, robot(), seed=3)
    assert plan(room, robot(), seed=3) != plan(room, robot(), seed=4)
    assert plan(room, robot(), count=3, seed=3) == plan(room, robot(), seed=3)[:3]


# -- sight past thin colliders ------------------------------------------------------------

# The room of ROOM without its pillar, and a table whose 1.6 x 0.9 m top stands 0.75 m up, above
# the robots: flatsim simulates only its legs (%s), which stand at working height.
TABLE_ROOM = ROOM.replace(
    '<collision name="pillar"><pose>0 0 0.5 0 0 0</pose><geometry><box><size>1 1 1</size></box></geometry></collision>',
    '').replace('<model name="white_ball">', """<model name="table"><static>1</static>
    <link name="top"><collision name="top"><pose>0 0 0.74 0 0 0</pose>
      <geometry><box><size>1.6 0.9 0.03</size></box></geometry></collision>%s</link>
  </model>
  <model name="white_ball">""")


def table_world(legs):
    """The table room with legs given as (x, y, SDF geometry)."""
    return parse_world(TABLE_ROOM % ''.join(
        '<collision name="leg%d"><pose>%r %r 0.36 0 0 0</pose><geometry>%s</geometry></collision>'
        % (index, x, y, geometry) for index, (x, y, geometry) in enumerate(legs)))


def cylinder_leg(diameter):
    return '<cylinder><radius>%r</radius><length>0.72</length></cylinder>' % (diameter / 2)


def box_leg(width):
    return '<box><size>%r %r 0.72</size></box>' % (width, width)


THIN_LEGS = [pytest.param(cylinder_leg(0.04), id='4 cm cylinder'),
             pytest.param(box_leg(0.015), id='1.5 cm box')]
# The camera 2 m from a table leg, the ball's centre 2 m beyond it: there the rays to the ball's
# centre and to its edges run 5 cm apart.
CAMERA, BALL = (-2.0, 0.0), (2.0, 0.0)
# The robot whose camera (0.2 m ahead of its origin) stands there.
FACING_BALL = placement.Placement(-2.2, 0.0, 0.0, 2.0, 0.0)


@pytest.mark.parametrize('leg', THIN_LEGS)
def test_a_thin_table_leg_between_the_camera_and_the_ball_hides_it(leg):
    # Between the ray to the ball's centre and the ray to its edge, as a three-ray check casts them.
    space = FreeSpace(table_world([(0.0, 0.025, leg)]), keep_out={'white_ball'})
    assert space.clear_rays(CAMERA, placement.ball_edges(CAMERA, BALL, 0.1))
    assert not space.ball_edges_visible(CAMERA, BALL, 0.1)


@pytest.mark.parametrize('leg', THIN_LEGS)
def test_a_thin_table_leg_in_the_corridor_to_the_ball_blocks_it(leg):
    # Halfway between the corridor's middle and its side, outside the camera's sight of the ball.
    space = FreeSpace(table_world([(0.0, 0.1, leg)]), keep_out={'white_ball'})
    assert space.ball_edges_visible(CAMERA, BALL, 0.1)
    assert not space.in_sight(CAMERA, BALL, 0.2)


@pytest.mark.parametrize('leg', THIN_LEGS)
def test_a_placement_with_a_thin_table_leg_between_robot_and_ball_is_out_of_sight(leg):
    geometry = robot()
    assert placement.in_plain_sight(FreeSpace(table_world([(0.0, 2.0, leg)]), keep_out={'white_ball'}),
                                    geometry, FACING_BALL, 0.1)
    for where in ((0.0, 0.025), (0.0, -0.03), (-1.0, 0.12), (1.0, -0.15)):
        space = FreeSpace(table_world([where + (leg,)]), keep_out={'white_ball'})
        assert not placement.in_plain_sight(space, geometry, FACING_BALL, 0.1), where


@pytest.mark.parametrize('leg', THIN_LEGS)
def test_a_table_leg_just_beside_the_corridor_is_not_in_the_way(leg):
    geometry = robot()
    # The corridor reaches 0.2 m to each side of the line; these legs' near faces stand 1 cm beyond.
    half_leg = 0.02 if 'cylinder' in leg else 0.0075
    for side in (1.0, -1.0):
        space = FreeSpace(table_world([(0.0, side * (0.21 + half_leg), leg)]), keep_out={'white_ball'})
        # The table's top, over the whole corridor, stands above the robots: only its legs count.
        assert space.clearance(0.0, 0.0) == pytest.approx(0.21)
        assert space.ball_edges_visible(CAMERA, BALL, 0.1)
        assert space.in_sight((-2.2, 0.0), BALL, 0.2)
        assert placement.in_plain_sight(space, geometry, FACING_BALL, 0.1)


def test_the_camera_casts_rays_no_more_than_1_cm_apart_across_the_ball():
    assert placement.SIGHT_GAP_M == 0.01
    assert placement.sight_ray_count(0.2) == 21
    assert placement.sight_ray_count(0.005) == 3


@pytest.mark.parametrize('leg_x', [-1.5, 0.0, 1.7])
def test_no_leg_wider_than_1_cm_slips_between_the_cameras_rays(leg_x):
    """A leg 1.1 cm across, moved across the whole sight of the ball in 2 mm steps, 0.5 m,
    2 m and 3.7 m from the camera, hides the ball wherever it stands."""
    ball = (2.0, 0.0)
    # The sight lines to the ball's edges, at the leg's distance from the camera.
    half = math.asin(0.1 / 4.0)
    reach_y = (leg_x - CAMERA[0]) * math.tan(half)
    for leg_y in [-reach_y + step * 0.002 for step in range(int(2 * reach_y / 0.002) + 1)]:
        space = FreeSpace(table_world([(leg_x, leg_y, cylinder_leg(0.011))]), keep_out={'white_ball'})
        assert not space.ball_edges_visible(CAMERA, ball, 0.1), leg_y
    # Just beyond the sight lines to the ball's edges, it hides nothing.
    for leg_y in (reach_y + 0.0075, -reach_y - 0.0075):
        space = FreeSpace(table_world([(leg_x, leg_y, cylinder_leg(0.011))]), keep_out={'white_ball'})
        assert space.ball_edges_visible(CAMERA, ball, 0.1), leg_y


def test_no_placement_among_thin_table_legs_has_a_leg_in_its_sight():
    """Every placement drawn in a room with two tables of thin legs, checked against the exact
    shapes: the triangle from the camera to the ball's edges and the corridor's rectangle."""
    legs = [(x, y, cylinder_leg(0.04) if x < 0 else box_leg(0.015))
            for x in (-3.0, -2.2, -1.4, 1.4, 2.2, 3.0) for y in (-1.8, -1.0, -0.2, 0.6, 1.4)]
    world = table_world(legs)
    space = FreeSpace(world, keep_out={'white_ball'})
    geometry = robot()
    for place in plan(world, geometry, count=60, seed=11):
        camera = geometry.camera.world(place.robot_x, place.robot_y, place.robot_yaw)[:2]
        ball = (place.ball_x, place.ball_y)
        _centre, right, left = placement.ball_edges(camera, ball, 0.1)
        assert space.outline_clear([camera, right, left], margin=0.0), place
        start = (place.robot_x, place.robot_y)
        length = math.hypot(ball[0] - start[0], ball[1] - start[1])
        across_x, across_y = (start[1] - ball[1]) * 0.2 / length, (ball[0] - start[0]) * 0.2 / length
        corridor = [(start[0] - across_x, start[1] - across_y), (ball[0] - across_x, ball[1] - across_y),
                    (ball[0] + across_x, ball[1] + across_y), (start[0] + across_x, start[1] + across_y)]
        assert space.outline_clear(corridor, margin=0.0), place


# -- the reach -----------------------------------------------------------------------------

SQUARE = RobotGeometry(((0.2, -0.2), (0.2, 0.2), (-0.2, 0.2), (-0.2, -0.2)),
                       placement.CameraView(0.2, 0.0, 0.1, 0.0, 0.0, 1.4, 1.1))


def test_the_gap_runs_from_the_robots_outline_to_the_balls_surface():
    gaps = reach.surface_gaps(SQUARE, [(0.0, 0.0, 0.0), (0.0, 0.0, math.pi / 4), (1.0, 0.0, 0.0),
                                           (0.0, 1.0, 0.0)], (1.0, 0.0), 0.1)
    assert gaps[0] == pytest.approx(1.0 - 0.2 - 0.1)
    assert gaps[1] == pytest.approx(1.0 - 0.2 * math.sqrt(2) - 0.1)  # a corner leads
    assert gaps[2] == pytest.approx(-0.3)                              # the ball is inside the outline
    assert gaps[3] == pytest.approx(math.hypot(0.8, 0.8) - 0.1)        # nearest is the corner (0.2, 0.8)


def test_a_robot_that_stops_11_cm_short_of_the_balls_surface_has_reached_it():
    """The review's robot: its front 0.345 m ahead of its base, stopped with the ball's centre
    0.55 m ahead, beyond the old 0.54 m centre-to-centre reach."""
    long = RobotGeometry(((0.345, -0.15), (0.345, 0.15), (-0.3, 0.15), (-0.3, -0.15)), SQUARE.camera)
    gap = reach.surface_gaps(long, [(0.0, 0.0, 0.0)], (0.55, 0.0), 0.1)[0]
    assert gap == pytest.approx(0.105)
    assert reach.surface_reached_how(gap, 0.0) == 'came within 15 cm of the ball\'s surface'
    assert reach.surface_reached_how(0.16, 0.0) == ''
    assert reach.surface_reached_how(0.4, 0.06) == 'pushed the ball'
