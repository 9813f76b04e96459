"""spawn_model takes gazebo_ros's command line as course launch files write it."""
import pytest
import rosgraph

from flatsim.nodes.spawn_model import (SERVICE_POLL_S, SpawnError, parse_args, prepare_xml,
                                       wait_for_service)


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


class _MasterAnsweringAfter:
    """A master that knows the service from the given lookup on."""

    def __init__(self, lookups_before_known):
        self.lookups_before_known = lookups_before_known
        self.lookups = []

    def lookupService(self, name):  # noqa: N802 - rosgraph.Master's name
        self.lookups.append(name)
        if len(self.lookups) <= self.lookups_before_known:
            raise rosgraph.MasterError('no provider')
        return 'rosrpc://localhost:1234'


class _Clock:
    def __init__(self):
        self.now = 0.0
        self.sleeps = []

    def sleep(self, seconds):
        self.sleeps.append(seconds)
        self.now += seconds


def test_waits_for_a_service_by_looking_often():
    """rospy's own wait looks every 0.3 s, which the launch's first camera frame waited for."""
    master, clock = _MasterAnsweringAfter(3), _Clock()
    assert wait_for_service('/gazebo/spawn_urdf_model', 60.0, master=master,
                            clock=lambda: clock.now, sleep=clock.sleep)
    assert master.lookups == ['/gazebo/spawn_urdf_model'] * 4
    assert clock.sleeps == [SERVICE_POLL_S] * 3 and SERVICE_POLL_S <= 0.05


def test_gives_up_on_a_service_after_the_timeout():
    master, clock = _MasterAnsweringAfter(10 ** 6), _Clock()
    assert not wait_for_service('/gazebo/spawn_urdf_model', 1.0, master=master,
                                clock=lambda: clock.now, sleep=clock.sleep)
    assert 1.0 <= clock.now <= 1.0 + 2 * SERVICE_POLL_S


def test_a_master_not_answering_yet_is_waited_for():
    class Refusing(_MasterAnsweringAfter):
        def lookupService(self, name):  # noqa: N802
            self.lookups.append(name)
            if len(self.lookups) < 3:
                raise ConnectionRefusedError(111, 'Connection refused')
            return 'rosrpc://localhost:1234'

    master, clock = Refusing(0), _Clock()
    assert wait_for_service('/gazebo/spawn_urdf_model', 5.0, master=master,
                            clock=lambda: clock.now, sleep=clock.sleep)
    assert len(master.lookups) == 3
