"""The stability check: centre of mass against the support polygon, with hand-computed numbers."""
import math
import os

import numpy as np
import pytest

from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose
from flatsim.stability import (MIN_MARGIN, assess, centre_of_mass, convex_hull, lowest_points,
                               signed_margin)

HERE = os.path.dirname(os.path.abspath(__file__))
FRONT_WHEELER = os.path.join(HERE, 'fixtures', 'robots', 'front_wheels_no_casters.urdf')
# sqrt(0.35^2 + 0.175^2): the edge from a caster at x = -0.15 to a wheel at (0.2, 0.175).
SLANT = math.hypot(0.35, 0.175)


def same(actual, expected):
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    return actual.shape == expected.shape and np.allclose(actual, expected)


def front_wheeler(chassis_extra='', chassis_com='0 0 0', extra_links=''):
    with open(FRONT_WHEELER, encoding='utf-8') as handle:
        xml = handle.read()
    xml = xml.replace('<mass value="10"/>', '<origin xyz="%s"/><mass value="10"/>' % chassis_com)
    xml = xml.replace('<geometry><box size="0.4 0.2 0.1"/></geometry>\n    </collision>',
                      '<geometry><box size="0.4 0.2 0.1"/></geometry>\n    </collision>' + chassis_extra)
    xml = xml.replace('</robot>', extra_links + '</robot>')
    return assess(load_robot(xml))


def rear_caster(bottom=0.0):
    """A caster sphere (r 0.05) under the chassis at x = -0.15, its bottom `bottom` above the ground."""
    return ('<collision><origin xyz="-0.15 0 %r"/><geometry><sphere radius="0.05"/></geometry></collision>'
            % (-0.1 + bottom + 0.05))


def test_the_hull_keeps_corners_counter_clockwise_and_drops_inner_and_collinear_points():
    points = [(0, 0), (1, 0), (0.5, 0), (1, 1), (0, 1), (0.5, 0.5), (1, 0.5)]
    assert convex_hull(points).tolist() == [[0, 0], [1, 0], [1, 1], [0, 1]]


def test_points_on_a_line_make_a_two_point_hull():
    assert convex_hull([(0.2, 0.1), (0.2, -0.1), (0.2, 0.0), (0.2, 0.1)]).tolist() == [[0.2, -0.1], [0.2, 0.1]]


@pytest.mark.parametrize('point, margin', [
    ((0.5, 0.5), 0.5),        # the centre of the unit square
    ((0.9, 0.5), 0.1),        # 0.1 from the right edge
    ((1.5, 0.5), -0.5),       # 0.5 beyond it
    ((2.0, 2.0), -math.sqrt(2)),   # nearest the corner (1, 1)
    ((1.0, 0.3), 0.0),        # on the edge
])
def test_the_margin_is_the_distance_to_the_nearest_edge_signed_by_inside(point, margin):
    square = [(0, 0), (1, 0), (1, 1), (0, 1)]
    assert signed_margin(square, point) == pytest.approx(margin)


def test_a_line_or_a_point_has_no_inside():
    line = [(0.0, -1.0), (0.0, 1.0)]
    assert signed_margin(line, (0.0, 0.0)) == 0.0
    assert signed_margin(line, (0.1, 0.5)) == pytest.approx(-0.1)
    assert signed_margin([(1.0, 1.0)], (1.0, 4.0)) == pytest.approx(-3.0)


def test_the_centre_of_mass_is_the_mass_weighted_mean():
    assert centre_of_mass([1.0, 3.0], [(0, 0, 0), (4, 0, 2)]).tolist() == [3.0, 0.0, 1.5]


def test_a_sphere_touches_below_its_centre():
    assert lowest_points('sphere', Pose(1, 2, 3).matrix(), (0.5,)).tolist() == [[1, 2, 2.5]]


def test_a_lying_wheel_touches_along_its_tread_from_end_to_end():
    points = lowest_points('cylinder', Pose(0, 0, 0, math.pi / 2, 0, 0).matrix(), (0.1, 0.04))
    assert same(sorted(points.tolist()), [[0, -0.02, -0.1], [0, 0.02, -0.1]])


def test_a_standing_cylinder_touches_with_its_whole_base():
    points = lowest_points('cylinder', Pose(0, 0, 1).matrix(), (0.1, 0.4))
    assert len(points) == 32
    assert np.allclose(points[:, 2], 0.8)
    assert np.allclose(np.hypot(points[:, 0], points[:, 1]), 0.1)


def test_a_box_touches_with_its_bottom_face():
    points = lowest_points('box', Pose(1, 0, 0).matrix(), (0.2, 0.4, 0.1))
    assert same(sorted(points.tolist()),
                [[0.9, -0.2, -0.05], [0.9, 0.2, -0.05], [1.1, -0.2, -0.05], [1.1, 0.2, -0.05]])


def test_wheels_at_the_front_edge_and_no_caster_tip_over():
    stability, _ = front_wheeler()
    # Centre of mass: 2 kg of wheels at x = 0.2 with 10 kg at 0 gives 0.4 / 12.
    assert stability.centre_of_mass == pytest.approx((0.4 / 12, 0.0))
    # The treads (0.05 wide, centred at y = +-0.15) make one line at x = 0.2.
    assert same(stability.support, ((0.2, -0.175), (0.2, 0.175)))
    assert stability.margin == pytest.approx(-(0.2 - 0.4 / 12))
    assert not stability.stable
    assert stability.contacts == ('left_wheel', 'right_wheel')
    assert stability.describe() == (
        'may tip over: centre of mass (0.033, 0.000) m of 12.00 kg is 0.167 m outside the support line '
        '(no polygon) (0.200, -0.175) (0.200, 0.175) of left_wheel, right_wheel (margin -0.167 m; a stable '
        'design keeps it at least 0.02 m inside)')


def test_a_rear_caster_makes_a_triangle_that_holds_the_centre_of_mass():
    stability, _ = front_wheeler(chassis_extra=rear_caster())
    assert same(stability.support, ((-0.15, 0.0), (0.2, -0.175), (0.2, 0.175)))
    # The slanted edges are nearer than the front one (0.167 m).
    assert stability.margin == pytest.approx(0.175 * (0.4 / 12 + 0.15) / SLANT)
    assert stability.stable
    assert stability.describe().startswith('stable: centre of mass (0.033, 0.000) m of 12.00 kg is 0.082 m inside '
                                           'the support polygon (-0.150, 0.000) (0.200, -0.175) (0.200, 0.175)')


def test_a_centre_of_mass_within_2_cm_of_the_edge_warns():
    # The chassis's inertial origin at x = 0.188 puts the whole (10 * 0.188 + 0.4) / 12 = 0.19 m forward.
    stability, _ = front_wheeler(chassis_extra=rear_caster(), chassis_com='0.188 0 0')
    assert stability.centre_of_mass == pytest.approx((0.19, 0.0))
    assert stability.margin == pytest.approx(0.01)
    assert not stability.stable and stability.margin < MIN_MARGIN
    assert 'margin 0.010 m' in stability.describe()


@pytest.mark.parametrize('bottom, touches', [(0.003, True), (0.01, False)])
def test_a_caster_above_the_ground_counts_only_within_the_tolerance(bottom, touches):
    stability, _ = front_wheeler(chassis_extra=rear_caster(bottom))
    assert (len(stability.support) == 3) is touches
    assert stability.stable is touches


def test_inertial_origins_are_composed_through_the_joints():
    # A caster link turned a quarter turn at x = -0.1: its inertial x of 0.05 points along the robot's y.
    caster = ('<link name="caster_link"><inertial><origin xyz="0.05 0 0"/><mass value="1"/>'
              '<inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial>'
              '<collision><geometry><sphere radius="0.05"/></geometry></collision></link>'
              '<joint name="caster_joint" type="fixed"><parent link="chassis"/><child link="caster_link"/>'
              '<origin xyz="-0.1 0 -0.05" rpy="0 0 %r"/></joint>' % (math.pi / 2))
    stability, _ = front_wheeler(extra_links=caster)
    assert stability.centre_of_mass == pytest.approx(((0.4 - 0.1) / 13, 0.05 / 13))
    assert stability.contacts == ('left_wheel', 'right_wheel', 'caster_link')
    assert same(stability.support, ((-0.1, 0.0), (0.2, -0.175), (0.2, 0.175)))


ARM = ('<robot name="arm"><link name="world"/><link name="base"><inertial><mass value="1"/>'
       '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>'
       '<joint name="fix" type="fixed"><parent link="world"/><child link="base"/></joint></robot>')
BOX = ('<robot name="box"><link name="base"><inertial><mass value="1"/>'
       '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>'
       '<collision><geometry><box size="1 1 1"/></geometry></collision></link></robot>')
MASSLESS = '<robot name="ghost"><link name="base"/></robot>'


@pytest.mark.parametrize('xml, why', [
    (ARM, 'fixed to the world'),
    (BOX, 'no wheels or casters: no collision shape of a wheel link, and no caster sphere'),
    (MASSLESS, 'no link has a positive <inertial><mass>'),
])
def test_a_robot_that_cannot_be_judged_says_why(xml, why):
    assert assess(load_robot(xml)) == (None, why)
