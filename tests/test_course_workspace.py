"""A student's ~/catkin_ws, made as the course says, with this project underneath it.

Each test starts a bash with a bare environment (a fresh HOME, no ROS
variables) and types the course's commands in the course's order. The
workspace holds the student's own my_robot, whose robot_description.launch
runs `$(find xacro)/xacro` on `$(find my_robot)/urdf/my_robot.xacro`:
`roslaunch --dump-params` evaluates both, as roslaunch does before it starts
anything, so a workspace that lost the project fails with "Resource not
found: xacro".
"""
import pathlib
import subprocess

TOP = pathlib.Path(__file__).resolve().parent.parent
FIXTURES = pathlib.Path(__file__).resolve().parent / 'fixtures'
BARE_PATH = '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'

COURSE_WORKSPACE = '''
mkdir -p ~/catkin_ws/src
cd ~/catkin_ws/src
catkin_init_workspace
cd ~/catkin_ws
catkin_make
'''
ADD_PACKAGE_AND_BUILD = '''
cp -r {fixture} ~/catkin_ws/src/my_robot
cd ~/catkin_ws
catkin_make
source devel/setup.bash
roslaunch --dump-params my_robot robot_description.launch
'''


def bash(script, home, timeout=600):
    """Run script in bash -e with a bare environment whose HOME is home."""
    env = {'HOME': str(home), 'PATH': BARE_PATH, 'LANG': 'C.UTF-8'}
    return subprocess.run(['bash', '-ec', script], env=env, cwd=str(home), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=timeout, check=False)


def assert_students_robot_described(result):
    assert result.returncode == 0, result.stdout[-6000:]
    assert 'Resource not found' not in result.stdout
    # The overlay's my_robot, through the project's xacro.
    assert 'students_robot' in result.stdout and 'robot_footprint_joint' in result.stdout, \
        result.stdout[-3000:]


def test_the_course_setup_line_enters_this_environment_when_opted_in(tmp_path):
    opt_ros = tmp_path / 'opt' / 'ros' / 'noetic'
    setup = subprocess.run([str(TOP / 'setup.sh'), '--opt-ros=%s' % opt_ros], cwd=TOP,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=False)
    assert setup.returncode == 0, setup.stdout[-3000:]
    assert 'wrote %s/setup.bash' % opt_ros in setup.stdout, setup.stdout[-3000:]
    again = subprocess.run([str(TOP / 'setup.sh'), '--opt-ros=%s' % opt_ros], cwd=TOP,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=False)
    assert again.returncode == 0 and 'already enters' in again.stdout, again.stdout[-3000:]

    home = tmp_path / 'home'
    home.mkdir()
    # The course: put the setup line in ~/.bashrc, and start each terminal with it.
    result = bash('echo "source %s/setup.bash" >> ~/.bashrc\nsource ~/.bashrc\n' % opt_ros
                  + COURSE_WORKSPACE + 'source devel/setup.bash\n'
                  + ADD_PACKAGE_AND_BUILD.format(fixture=FIXTURES / 'student_my_robot'), home)
    assert_students_robot_described(result)


def test_opting_in_leaves_another_ros_install_alone(tmp_path):
    opt_ros = tmp_path / 'noetic'
    opt_ros.mkdir()
    (opt_ros / 'setup.bash').write_text('# a real ROS install\n')
    setup = subprocess.run([str(TOP / 'setup.sh'), '--opt-ros=%s' % opt_ros], cwd=TOP,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=False)
    assert setup.returncode != 0
    assert 'belongs to another ROS install' in setup.stdout, setup.stdout[-3000:]
    assert (opt_ros / 'setup.bash').read_text() == '# a real ROS install\n'


def test_a_workspace_built_before_env_sh_is_configured_again_on_the_project(tmp_path):
    """Built with nothing sourced, its devel space chains to no workspace, and Debian's
    catkin_make would not run CMake again for an unchanged package list. One catkin_make
    after `source env.sh` puts the project underneath."""
    fixture = FIXTURES / 'student_my_robot'
    result = bash(COURSE_WORKSPACE.replace('catkin_make', 'cp -r %s src/my_robot\ncatkin_make' % fixture)
                  + 'source %s/env.sh\n' % TOP
                  + 'catkin_make\nsource devel/setup.bash\n'
                  + 'roslaunch --dump-params my_robot robot_description.launch\n', tmp_path)
    assert 'catkin_make: the workspaces underneath changed (built on: none; now: %s' % (
        TOP / 'catkin_ws' / 'devel') in result.stdout, result.stdout[-3000:]
    assert_students_robot_described(result)
