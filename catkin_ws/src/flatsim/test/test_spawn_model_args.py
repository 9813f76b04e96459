"""spawn_model takes gazebo_ros's command line as course launch files write it."""
import pytest

from flatsim.nodes.spawn_model import parse_args


def test_course_command_line():
    args = parse_args('-urdf -param robot_description -model my_robot -x 1 -y -2 -z 0 '
                      '-R 0 -P -0.785 -Y 1.57'.split())
    assert args.urdf and not args.sdf
    assert args.param == 'robot_description' and args.file is None
    assert args.model == 'my_robot'
    assert (args.x, args.y, args.P, args.Y) == (1.0, -2.0, -0.785, 1.57)


def test_sdf_from_file_and_ignored_gazebo_flags():
    args = parse_args(['-sdf', '-file', 'ball.sdf', '-model', 'ball2', '-unpause'])
    assert args.sdf and args.file == 'ball.sdf'


@pytest.mark.parametrize('argv', [
    ['-param', 'robot_description', '-model', 'r'],            # neither -urdf nor -sdf
    ['-urdf', '-model', 'r'],                                  # no source
    ['-urdf', '-param', 'p', '-file', 'f', '-model', 'r'],     # two sources
    ['-urdf', '-param', 'p'],                                  # no name
])
def test_incomplete_command_lines_are_refused(argv):
    with pytest.raises(SystemExit):
        parse_args(argv)
