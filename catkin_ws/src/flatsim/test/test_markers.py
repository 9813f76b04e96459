"""The world as rviz markers: one per visual, with the world file's sizes, heights and colours."""
import math
import pathlib

import pytest
from visualization_msgs.msg import Marker

from flatsim.loading.sdf_world import load_world
from flatsim.pose import Pose
from flatsim.ros.markers import MIN_THICKNESS, NAMESPACE, build_specs, marker_array_msg
from flatsim.ros.overhead import moving_indices
from flatsim.world.scene import Prim, Scene
from flatsim.world.sim import Simulation

WORLD = pathlib.Path(__file__).parent / 'fixtures' / 'worlds' / 'marker_room.world'


@pytest.fixture
def sim():
    simulation = Simulation(load_world(str(WORLD)))
    simulation.sync_moving_prims()
    return simulation


def by_name(specs):
    return {spec.name: spec for spec in specs}


def test_one_marker_per_visual_and_none_for_collisions(sim):
    specs = by_name(build_specs(sim.scene))
    assert sorted(specs) == ['post::visual', 'room::east', 'room::north', 'white_ball::visual']


def test_walls_keep_the_world_files_place_size_height_and_colour(sim):
    specs = by_name(build_specs(sim.scene))
    north = specs['room::north']
    assert north.shape == 'cube'
    assert (north.x, north.y, north.z) == pytest.approx((1.0, 2.0, 0.5))
    assert north.yaw == pytest.approx(0.0)
    assert north.size == pytest.approx((4.0, 0.2, 1.0))
    assert north.color == pytest.approx((0.2, 0.4, 0.6, 1.0))
    east = specs['room::east']
    assert (east.x, east.y, east.z) == pytest.approx((3.0, 0.0, 0.75))
    assert east.yaw == pytest.approx(math.pi / 2)
    assert east.size == pytest.approx((3.0, 0.1, 1.5))
    assert east.color == pytest.approx((0.5, 0.1, 0.1, 1.0))


def test_cylinder_and_ball_keep_their_shapes_and_heights(sim):
    specs = by_name(build_specs(sim.scene))
    post = specs['post::visual']
    assert post.shape == 'cylinder'
    assert (post.x, post.y, post.z) == pytest.approx((-1.0, 1.0, 0.6))
    assert post.size == pytest.approx((0.4, 0.4, 1.2))
    assert post.color == pytest.approx((0.1, 0.6, 0.2, 1.0))
    ball = specs['white_ball::visual']
    assert ball.shape == 'sphere'
    assert (ball.x, ball.y, ball.z) == pytest.approx((0.5, -1.0, 0.1))
    assert ball.size == pytest.approx((0.2, 0.2, 0.2))
    assert ball.color == (1.0, 1.0, 1.0, 1.0)


def test_marker_ids_are_scene_indices_so_updates_replace(sim):
    specs = build_specs(sim.scene)
    assert [spec.id for spec in specs] == list(sim.scene.select(visual=True))
    moving = build_specs(sim.scene, moving_indices(sim))
    assert [spec.name for spec in moving] == ['white_ball::visual']
    assert moving[0].id == by_name(specs)['white_ball::visual'].id


def test_ball_marker_follows_the_ball(sim):
    sim.set_model_state('white_ball', Pose(-0.4, 0.3, 0.1), twist=(1.0, 0.0, 0.0))
    for _ in range(100):
        sim.step()
    sim.sync_moving_prims()
    (ball,) = build_specs(sim.scene, moving_indices(sim))
    x, y, _ = sim.physics.pose(sim.models['white_ball'].handle)
    assert x > -0.35
    assert (ball.x, ball.y, ball.z) == pytest.approx((x, y, 0.1))


def test_deleted_model_has_no_markers(sim):
    sim.delete_model('post')
    assert 'post::visual' not in by_name(build_specs(sim.scene))
    assert len(build_specs(sim.scene)) == 3


def test_flat_visual_gets_a_visible_thickness():
    scene = Scene([Prim.box('mat', 0, 0, 0, 1, 1, 0.0, 0.0)])
    (spec,) = build_specs(scene)
    assert spec.size == (1.0, 1.0, MIN_THICKNESS)


def test_message_carries_types_poses_scales_and_colours(sim):
    specs = build_specs(sim.scene)
    array = marker_array_msg(specs, 'odom')
    assert len(array.markers) == len(specs)
    kinds = {m.id: m.type for m in array.markers}
    east = by_name(specs)['room::east']
    assert kinds[east.id] == Marker.CUBE
    marker = next(m for m in array.markers if m.id == east.id)
    assert marker.header.frame_id == 'odom'
    assert marker.ns == NAMESPACE and marker.action == Marker.ADD
    assert (marker.pose.position.x, marker.pose.position.y, marker.pose.position.z) == \
        pytest.approx((3.0, 0.0, 0.75))
    quaternion = marker.pose.orientation
    assert (quaternion.x, quaternion.y, quaternion.z, quaternion.w) == \
        pytest.approx((0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)))
    assert (marker.scale.x, marker.scale.y, marker.scale.z) == pytest.approx((3.0, 0.1, 1.5))
    assert (marker.color.r, marker.color.g, marker.color.b, marker.color.a) == \
        pytest.approx((0.5, 0.1, 0.1, 1.0))
    by_type = sorted(m.type for m in array.markers)
    assert by_type == sorted([Marker.CUBE, Marker.CUBE, Marker.CYLINDER, Marker.SPHERE])


def test_clear_first_starts_with_deleteall(sim):
    array = marker_array_msg(build_specs(sim.scene), 'odom', clear_first=True)
    assert array.markers[0].action == Marker.DELETEALL
    assert all(m.action == Marker.ADD for m in array.markers[1:])
    assert marker_array_msg([], 'odom').markers == []
