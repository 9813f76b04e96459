"""The student's own packages beside the project's: `source env.sh` and `source env.sh --student`.

A fresh HOME holds ~/catkin_ws/src with a student's my_robot, ball_chaser and
simple_arm (tests/fixtures/student_workspace), built as the course says:
`cd ~/catkin_ws && catkin_make`. The student mode is entered by the ~/.bashrc
line that docs/course.md's "Student mode" gives, read from the text. Each test
starts a bash with a bare environment and types the course's commands verbatim:

- with devel/setup.bash sourced, both modes run the student's packages;
- in the student mode, without it, ROS says the packages are not found;
- in the default mode, without it, the project's run, and say so in one line
  that names both folders and the `source` line that fixes it.
"""
import os
import pathlib
import re
import shutil
import signal
import subprocess
import time
import xmlrpc.client

import pytest

from chase_tools.grading import sandbox
from rosproc import ReadAsItComes, free_port, wait_until

TOP = pathlib.Path(__file__).resolve().parent.parent
REFERENCE = TOP / 'catkin_ws' / 'src'
FIXTURE = pathlib.Path(__file__).resolve().parent / 'fixtures' / 'student_workspace'
BARE_PATH = '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'
COURSE = TOP / 'docs' / 'course.md'
STUDENT_MODE_HEADING = "### Student mode: your packages, not the project's"
ENTER = {'default': 'source %s/env.sh\n' % TOP, 'student': 'source ~/.bashrc\n'}
STUDENT_PACKAGES = ('my_robot', 'ball_chaser', 'simple_arm')
SUBMISSIONS = TOP / 'catkin_ws' / 'src' / 'chase_tools' / 'test' / 'fixtures' / 'submissions'
STUDENTS_DRIVE_BOT = "the student's drive_bot"
SHADOW_LINE = "this is the project's"
STARTUP_TIMEOUT_S = 90
STOP_TIMEOUT_S = 30
COMMANDS_TIMEOUT_S = 120
BUILD_TIMEOUT_S = 600


def bash(script, home, timeout=COMMANDS_TIMEOUT_S):
    """Run script in bash -e with a bare environment whose HOME is home; (exit status, output).
    A script still running after timeout is stopped with Ctrl-C, and its status is None."""
    terminal = Terminal(script, home, free_port())
    try:
        terminal.proc.wait(timeout)
    except subprocess.TimeoutExpired:
        pass
    finally:
        output = terminal.stop()
    return terminal.status, output


def bare_env(home, port):
    """A fresh terminal's: nothing of ROS, and a master port no other test uses."""
    return {'HOME': str(home), 'PATH': BARE_PATH, 'LANG': 'C.UTF-8',
            'ROS_MASTER_URI': 'http://localhost:%d' % port}


class Terminal(ReadAsItComes):
    """A command left running, its output read as it comes, stopped with Ctrl-C."""

    def __init__(self, script, home, port):
        super().__init__(['bash', '-ec', script], env=bare_env(home, port), cwd=str(home))
        self.port = port
        self.status = None

    def wait_for(self, text, timeout=STARTUP_TIMEOUT_S):
        found = wait_until(lambda: text in self.output or self.proc.poll() is not None, timeout)
        time.sleep(0.2)    # the rest of that burst of output
        assert found and text in self.output, self.output[-4000:]

    def wait_for_nodes(self, names, timeout=STARTUP_TIMEOUT_S):
        """Until each node has registered with the master (its start-up checks are behind it)."""
        master = xmlrpc.client.ServerProxy('http://localhost:%d' % self.port)

        def registered():
            try:
                return all(master.lookupNode('/test', name)[0] == 1 for name in names)
            except OSError:
                return False
        assert wait_until(registered, timeout), self.output[-4000:]

    def stop(self):
        self.status = self.proc.poll()
        if self.status is None:
            os.killpg(self.proc.pid, signal.SIGINT)
            try:
                self.proc.wait(STOP_TIMEOUT_S)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait()
        self.reader.join(5)
        return self.output


def bashrc_line():
    """The line docs/course.md's "Student mode" has students put in ~/.bashrc, for this checkout."""
    section = COURSE.read_text().split(STUDENT_MODE_HEADING + '\n', 1)[1].split('\n#', 1)[0]
    block = re.search(r'```bash\n(.*?)```', section, re.S).group(1).strip()
    assert block == 'source /path/to/checkout/env.sh --student', block
    return block.replace('/path/to/checkout', str(TOP))


def new_home(tmp_path_factory, name, packages=STUDENT_PACKAGES):
    """A HOME with the student's packages in ~/catkin_ws/src and the student mode's ~/.bashrc line."""
    home = tmp_path_factory.mktemp(name)
    (home / '.bashrc').write_text(bashrc_line() + '\n')
    src = home / 'catkin_ws' / 'src'
    src.mkdir(parents=True)
    for package in packages:
        shutil.copytree(FIXTURE / package, src / package)
    return home


def built_home(mode, tmp_path_factory):
    """A HOME with ~/catkin_ws built in that mode by the course's commands."""
    home = new_home(tmp_path_factory, 'home_%s' % mode)
    status, output = bash(ENTER[mode] + 'cd ~/catkin_ws\ncatkin_make\n', home, BUILD_TIMEOUT_S)
    assert status == 0, output[-6000:]
    return home


@pytest.fixture(scope='module')
def student_home(tmp_path_factory):
    return built_home('student', tmp_path_factory)


@pytest.fixture(scope='module')
def default_home(tmp_path_factory):
    return built_home('default', tmp_path_factory)


def shadow_lines(output):
    return [line for line in output.splitlines() if SHADOW_LINE in line]


@pytest.mark.parametrize('mode', sorted(ENTER))
def test_the_students_packages_run_once_devel_is_sourced(mode, request):
    home = request.getfixturevalue('%s_home' % mode)
    script = (ENTER[mode] + 'cd ~/catkin_ws\nsource devel/setup.bash\n'
              'rospack find my_robot\n'
              'rosrun ball_chaser drive_bot\n'
              # The student's drive_bot is required and ends at once, and the launch with it.
              'roslaunch ball_chaser ball_chaser.launch\n')
    status, output = bash(script, home)
    assert status == 0, output[-6000:]
    assert '%s\n' % (home / 'catkin_ws' / 'src' / 'my_robot') in output, output[-4000:]
    students_drive_bot = '%s (%s), its DriveToTarget from %s' % (
        STUDENTS_DRIVE_BOT, home / 'catkin_ws' / 'src' / 'ball_chaser' / 'scripts' / 'drive_bot',
        home / 'catkin_ws' / 'devel' / 'lib' / 'python3' / 'dist-packages' / 'ball_chaser' / 'srv' / '__init__.py')
    # Once from rosrun, once from roslaunch.
    assert output.count(students_drive_bot) == 2, output[-6000:]
    assert shadow_lines(output) == []


def test_student_mode_without_devel_sourced_finds_none_of_them(student_home):
    home = student_home
    status, output = bash(ENTER['student'] + 'cd ~/catkin_ws\n'
                          'rospack find my_robot || echo "exit $?"\n'
                          'rosrun ball_chaser drive_bot || echo "exit $?"\n'
                          'roslaunch ball_chaser ball_chaser.launch || echo "exit $?"\n', home)
    assert status == 0, output
    assert "[rospack] Error: package 'my_robot' not found\nexit 1\n" in output, output
    assert "[rospack] Error: package 'ball_chaser' not found\nexit 2\n" in output, output
    assert ('RLException: [ball_chaser.launch] is neither a launch file in package [ball_chaser] '
            'nor is [ball_chaser] a launch file name') in output, output
    assert STUDENTS_DRIVE_BOT not in output and SHADOW_LINE not in output
    assert "env.sh: student mode: the project's my_robot, ball_chaser and simple_arm are hidden" in output


def test_student_mode_hides_the_solutions_from_python_cmake_and_catkin_find(student_home):
    home = student_home
    status, output = bash(ENTER['student'] + '''
for pkg in my_robot ball_chaser simple_arm; do
  echo "catkin_find $pkg: $(catkin_find --libexec --share $pkg)"
  for prefix in ${CMAKE_PREFIX_PATH//:/ }; do
    [ ! -e "$prefix/share/$pkg/cmake" ] || echo "find_package finds $prefix/share/$pkg"
  done
done
python -c 'import ball_chaser.srv' 2>&1 | tail -n 1
python -c 'import simple_arm.srv' 2>&1 | tail -n 1
echo "platform: $(rospack find flatsim) $(rospack find gazebo_ros)" \\
     "$(rospack find turtlesim) $(rospack find chase_tools)"
python -c 'import flatsim, gazebo_msgs.srv, turtlesim.srv; print("platform imports")'
''', home)
    assert status == 0, output
    for pkg in STUDENT_PACKAGES:
        assert 'catkin_find %s: \n' % pkg in output, output
    assert 'find_package finds' not in output, output
    assert "ModuleNotFoundError: No module named 'ball_chaser'" in output, output
    assert "ModuleNotFoundError: No module named 'simple_arm'" in output, output
    assert 'platform: %s %s %s %s\n' % (REFERENCE / 'flatsim', REFERENCE / 'gazebo_compat' / 'gazebo_ros',
                                        REFERENCE / 'turtlesim', REFERENCE / 'chase_tools') in output, output
    assert 'platform imports' in output, output


def test_student_mode_grade_still_checks_against_the_courses_service(student_home):
    """grade compares a submission's service with the project's ball_chaser/DriveToTarget, which the
    student mode hides from the shell: the chase tools see it behind what the shell finds."""
    home = student_home
    reference_md5 = subprocess.run(
        ['python', '-c', 'from ball_chaser.srv import DriveToTarget; print(DriveToTarget._md5sum)'],
        stdout=subprocess.PIPE, text=True, check=True).stdout.strip()
    status, output = bash(ENTER['student'] + '''
grade_command=$(command -v grade)
echo "grade is $grade_command"
"$(dirname "$grade_command")/../with_reference" python -c \
  'from chase_tools.grading.course_service import course_drive_to_target as c; print("course md5", c()._md5sum)'
"$(dirname "$grade_command")/../with_reference" rospack find my_robot
''', home)
    assert status == 0, output
    assert 'grade is %s\n' % (TOP / 'catkin_ws' / 'devel_platform' / 'bin' / 'grade') in output, output
    assert 'course md5 %s\n' % reference_md5 in output, output
    assert '%s\n' % (REFERENCE / 'my_robot') in output, output


def test_student_mode_chase_tools_run_the_projects_chase_and_grade_a_submission(tmp_path_factory, tmp_path):
    """chase_demo runs the project's robot and chaser; grade builds a submission on the student
    mode's platform, runs it in its sandbox and checks it against the course's service."""
    if sandbox.check() is not None:
        pytest.skip('the grader needs bubblewrap: %s' % sandbox.check())
    home = new_home(tmp_path_factory, 'home_tools', packages=())
    status, output = bash(ENTER['student'] + 'rosrun chase_tools chase_demo --timeout 30 --port %d --output %s\n'
                          % (free_port(), tmp_path / 'demo'), home, BUILD_TIMEOUT_S)
    assert status == 0 and 'chase_demo: reached the ball' in output, output[-6000:]
    subprocess.run(['python', '-c', 'import variants, sys; variants.compose("py_correct", sys.argv[1])',
                    str(tmp_path)], cwd=str(SUBMISSIONS), check=True)
    status, output = bash(ENTER['student'] + 'grade %s --trials 1 --timeout 30 --output %s --json %s\n'
                          % (tmp_path / 'py_correct', tmp_path / 'report', tmp_path / 'grade.json'),
                          home, BUILD_TIMEOUT_S)
    assert status == 0 and 'Rubric items (7): 7 passed, 0 failed, 0 not judged.' in output, output[-6000:]


def test_default_mode_without_devel_sourced_runs_ours_and_says_so_once(default_home):
    home = default_home
    status, output = bash(ENTER['default'] + 'rospack find my_robot\n', home)
    assert status == 0 and output.endswith('%s\n' % (REFERENCE / 'my_robot')), output
    fix = 'to run yours: source %s' % (home / 'catkin_ws' / 'devel' / 'setup.bash')

    def expected(pkg):
        return ("%s: this is the project's %s (%s), not yours (%s): your workspace is not sourced; %s"
                % (pkg, pkg, REFERENCE / pkg, home / 'catkin_ws' / 'src' / pkg, fix))

    chaser = Terminal(ENTER['default'] + 'roslaunch ball_chaser ball_chaser.launch\n', home, free_port())
    try:
        chaser.wait_for(expected('ball_chaser'))
        # drive_bot and process_image have run their own checks by the time they register.
        chaser.wait_for_nodes(['/drive_bot', '/process_image'])
    finally:
        output = chaser.stop()
    assert shadow_lines(output) == [expected('ball_chaser')], output[-4000:]
    assert STUDENTS_DRIVE_BOT not in output

    node = Terminal(ENTER['default'] + 'rosrun ball_chaser drive_bot\n', home, free_port())
    try:
        node.wait_for(expected('ball_chaser'))
    finally:
        output = node.stop()
    assert shadow_lines(output) == [expected('ball_chaser')], output[-4000:]

    world = Terminal(ENTER['default'] + 'roslaunch my_robot world.launch gui:=false\n', home, free_port())
    try:
        world.wait_for(expected('my_robot'))
        world.wait_for_nodes(['/urdf_spawner'])
    finally:
        output = world.stop()
    assert shadow_lines(output) == [expected('my_robot')], output[-4000:]

    status, output = bash(ENTER['default'] + 'roslaunch --dump-params simple_arm robot_spawn.launch\n', home)
    assert status == 0, output[-4000:]
    assert shadow_lines(output) == [expected('simple_arm')], output[-4000:]
    assert re.search(r'/overlay_check/simple_arm: %s\n' % re.escape(str(REFERENCE / 'simple_arm')), output), output


def test_a_workspace_follows_the_mode_after_one_catkin_make(tmp_path_factory):
    """Built in the default mode, its devel/setup.bash brings the project's packages back; one
    catkin_make in the student mode chains it to the student mode's platform instead."""
    home = new_home(tmp_path_factory, 'home_switched', packages=('my_robot',))
    status, output = bash(ENTER['default'] + 'cd ~/catkin_ws\ncatkin_make\n', home, BUILD_TIMEOUT_S)
    assert status == 0, output[-6000:]
    status, output = bash(ENTER['student'] + 'cd ~/catkin_ws\ncatkin_make\nsource devel/setup.bash\n'
                          'echo "CMAKE_PREFIX_PATH=$CMAKE_PREFIX_PATH"\n'
                          'rospack find ball_chaser || echo "exit $?"\n', home, BUILD_TIMEOUT_S)
    assert status == 0, output[-6000:]
    assert 'catkin_make: the workspaces underneath changed' in output, output[-6000:]
    assert 'CMAKE_PREFIX_PATH=%s:%s\n' % (home / 'catkin_ws' / 'devel', TOP / 'catkin_ws' / 'devel_platform') \
        in output, output[-6000:]
    assert "[rospack] Error: package 'ball_chaser' not found\nexit 1\n" in output, output[-6000:]


def test_a_misspelt_mode_is_named_and_the_default_entered(tmp_path):
    status, output = bash('source %s/env.sh --studnet\nrospack find my_robot\n' % TOP, tmp_path)
    assert status == 0, output
    assert ('env.sh: unknown option --studnet (the one option is --student); entering the default '
            'environment\n') in output, output
    assert output.endswith('%s\n' % (REFERENCE / 'my_robot')), output
