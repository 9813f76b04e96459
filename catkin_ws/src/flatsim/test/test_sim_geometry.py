"""How SDF geometry becomes the 2.5D shapes that physics, lidar and camera share."""
import math

import pytest

from flatsim.loading.sdf_world import Geom
from flatsim.pose import Pose
from flatsim.world.model_geometry import geom_prims


def box_prim(yaw=0.0, roll=0.0, size=(0.6, 0.2, 0.5)):
    geom = Geom('crate', 'box', Pose(0, 0, 0.25, roll, 0, 0), size)
    (prim,) = geom_prims('m', Pose(1.0, 2.0, 0.0, 0, 0, yaw), [geom], 'lidar')
    return prim


@pytest.mark.parametrize('yaw', [0.0, 0.4, math.pi / 2, -2.5])
def test_a_turned_box_keeps_its_size(yaw):
    prim = box_prim(yaw)
    assert (prim.x, prim.y) == pytest.approx((1.0, 2.0))
    assert (prim.half_x, prim.half_y) == pytest.approx((0.3, 0.1))
    assert math.cos(prim.yaw - yaw) == pytest.approx(1.0)
    assert (prim.z_min, prim.z_max) == pytest.approx((0.0, 0.5))


def test_a_box_on_its_side_stands_as_tall_as_it_is_wide():
    prim = box_prim(roll=math.pi / 2)
    assert (prim.half_x, prim.half_y) == pytest.approx((0.3, 0.25))
    assert prim.z_max - prim.z_min == pytest.approx(0.2)


def test_upright_cylinder_and_sphere():
    cylinder = Geom('post', 'cylinder', Pose(0, 0, 0.5), (0.1, 1.0))
    sphere = Geom('ball', 'sphere', Pose(0.5, 0, 0.1), (0.1,))
    post, ball = geom_prims('m', Pose(2.0, 0.0, 0.0), [cylinder, sphere], 'camera')
    assert post.kind == 'cylinder' and post.radius == 0.1
    assert (post.z_min, post.z_max) == pytest.approx((0.0, 1.0))
    assert ball.kind == 'sphere' and (ball.x, ball.z_min, ball.z_max) == pytest.approx((2.5, 0.0, 0.2))
    assert ball.visual and not ball.collision
