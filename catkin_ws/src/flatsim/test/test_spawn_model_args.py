"""spawn_model takes gazebo_ros's command line as course launch files write it."""
import pytest

from flatsim.nodes.spawn_model import SpawnError, parse_args, prepare_xml


def test_course_command_line():
    args, unknown = parse_args('-urdf -param robot_description -model my_robot -x 1 -y -2 -z 0 '
                               '-R 0 -P -0.785 -Y 1.57'.split())
    assert args.urdf and not args.sdf and unknown == []
    assert args.param == 'robot_description' and args.file is None
    assert args.model == 'my_robot'
    assert (args.x, args.y, args.P, args.Y) == (1.0, -2.0, -0.785, 1.57)
    assert args.gazebo_namespace == '/gazebo' and args.reference_frame == ''


def test_every_option_of_the_real_tool():
    args, unknown = parse_args(
        ['-sdf', '-database', 'cafe_table', '-model', 't', '-reference_frame', 'my_robot::chassis',
         '-gazebo_namespace', '/sim', '-robot_namespace', '/r1', '-unpause', '-wait', 'ground',
         '-J', 'elbow', '1.5', '-J', 'wrist', '-0.5', '-package_to_model', '-b'])
    assert unknown == []
    assert args.database == 'cafe_table' and args.reference_frame == 'my_robot::chassis'
    assert (args.gazebo_namespace, args.robot_namespace) == ('/sim', '/r1')
    assert args.unpause and args.wait == 'ground' and args.package_to_model and args.bond
    assert args.joints == [['elbow', 1.5], ['wrist', -0.5]]


def test_kinetic_era_typos_are_returned_as_unknown_not_fatal():
    # A launch file that wrote `_r $(arg roll)` for `-R $(arg roll)`.
    args, unknown = parse_args('-urdf -param robot_description -model my_robot -x 0 _r 0.3 -Y 0.5'
                               .split())
    assert unknown == ['_r', '0.3']
    assert args.model == 'my_robot' and args.Y == 0.5 and args.R == 0.0
    # Not an abbreviation of -reference_frame or -robot_namespace either.
    args, unknown = parse_args('-urdf -param p -model r -r 0 -ro /x'.split())
    assert unknown == ['-r', '0', '-ro', '/x']
    assert args.robot_namespace == '/' and args.reference_frame == ''


@pytest.mark.parametrize('argv', [
    ['-param', 'robot_description', '-model', 'r'],            # neither -urdf nor -sdf
    ['-urdf', '-model', 'r'],                                  # no source
    ['-urdf', '-param', 'p', '-file', 'f', '-model', 'r'],     # two sources
    ['-urdf', '-param', 'p'],                                  # no name
    ['-urdf', '-param', 'p', '-model', 'r', '-J', 'elbow', 'up'],  # a joint position that is no number
])
def test_incomplete_command_lines_are_refused(argv):
    with pytest.raises(SystemExit):
        parse_args(argv)


def test_xml_is_checked_and_package_meshes_become_model_meshes():
    xml = prepare_xml('<robot name="r"><link name="a"><visual><geometry>'
                      '<mesh filename="package://my_robot/meshes/hokuyo.dae"/></geometry></visual>'
                      '</link></robot>', package_to_model=True)
    assert 'model://my_robot/meshes/hokuyo.dae' in xml
    with pytest.raises(SpawnError, match='Invalid XML'):
        prepare_xml('<robot name="r"><link>', package_to_model=False)
