"""Every command of docs/course.md, typed from the page's own text as a new student types
it: from lesson 1 to the finished project, in a fresh home folder, each code block in a
terminal of its own opened at the top of this checkout (after the workspace step its
~/.bashrc enters the environment), all in a network namespace of their own so that the
page's `roscore` and `roslaunch` use ROS's default port.

Each command is either run here or named in MAPPED with the test that types it (a
window, an editor, a network, root, two machines). A one-shot command must exit 0 and
print the words its "# →" comment lists; a command that keeps running (BACKGROUND) must
reach its stated readiness, and is stopped when the page starts another simulator, when
the same command is started again, or at the end of its section. Where the page has the
student write files (the course's code and launch files), HOOKS writes them, from the
fixtures of a course-shaped submission.
"""
import collections
import itertools
import os
import pathlib
import pty
import re
import shutil
import signal
import subprocess
import time

import pytest

from course_doc import parse
from course_shell import Namespace, Terminal
from rosproc import wait_until

TOP = pathlib.Path(__file__).resolve().parent.parent
DOC = TOP / 'docs' / 'course.md'
COMMANDS = parse(DOC.read_text())
BARE_PATH = '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'
SUBMISSION = TOP / 'catkin_ws' / 'src' / 'chase_tools' / 'test' / 'fixtures' / 'submissions' / 'base'
PROJECT_ARM = TOP / 'catkin_ws' / 'src' / 'simple_arm'
READY_S = 90

# Commands run by another test, which types them where this one cannot.
MAPPED = {
    'rosed geometry_msgs Twist.msg':
        'tests/test_shell.py::test_rosed_opens_a_message_definition',
    'rosrun image_view image_view image:=/turtlesim/image':
        'tests/test_student_packages.py::test_image_view_subscribes_to_the_camera_topic',
    'rosrun image_view image_view image:=/flatsim/overhead/image_raw':
        'tests/test_student_packages.py::test_image_view_subscribes_to_the_camera_topic',
    'source /path/to/checkout/env.sh --student':
        'tests/test_student_mode.py::test_the_students_packages_run_once_devel_is_sourced',
    './setup.sh --opt-ros':
        'tests/test_course_workspace.py::test_the_course_setup_line_enters_this_environment_when_opted_in',
    'git clone -b first_interaction https://github.com/udacity/RoboND-simple_arm/ simple_arm':
        'tests/test_course_simple_arm.py::test_catkin_make_builds_the_course_nodes_against_the_stand_ins',
    'rqt_image_view /rgb_camera/image_raw':
        'tests/test_rqt_image_view.py::test_rqt_image_view_subscribes_to_the_topic_in_a_window',
    'rosrun rqt_image_view rqt_image_view':
        'tests/test_rqt_image_view.py::test_rqt_image_view_subscribes_to_the_topic_in_a_window',
    # No ssh server nor Docker daemon here: the test serves the page as these do, on another
    # address (gazebo --listen 0.0.0.0:8080) and through a forwarded port.
    'ssh -L 8080:127.0.0.1:PORT you@lab-server':
        'tests/test_studio_listen.py::'
        'test_gazebo_listen_serves_the_page_to_another_host_with_a_warning_and_the_token',
    'docker build -f docker/Dockerfile -t go-chase-it .':
        'tests/test_studio_listen.py::'
        'test_gazebo_listen_serves_the_page_to_another_host_with_a_warning_and_the_token',
    "docker run --rm -it -p 127.0.0.1:8080:8080 go-chase-it bash -c 'source env.sh && gazebo --listen 0.0.0.0:8080'":
        'tests/test_studio_listen.py::'
        'test_gazebo_listen_serves_the_page_to_another_host_with_a_warning_and_the_token',
    'roslaunch my_robot world.launch world_file:=$HOME/catkin_ws/src/my_robot/worlds/yourname.world':
        'tests/test_studio_build_my_world.py::'
        'test_build_my_world_from_a_fresh_home_and_relaunch_it_with_the_robot',
    'rosrun rviz rviz -d $(rospack find my_robot)/rviz/my_robot.rviz':
        'tests/test_studio_course_path.py::'
        'test_my_ball_built_inserted_and_saved_in_the_studio_is_chased_once_dragged_in_view',
}
# Whole sections run by another test.
MAPPED_SECTIONS = {
    'Two machines':
        'tests/test_two_hosts.py::test_the_chase_works_with_the_world_and_the_chaser_on_different_hosts',
}
# Sections whose commands run against what the section before them left running.
CONTINUES = {'The world in rviz, click-to-place, and the view from above'}

ADDRESS = ('log', r'http://127\.0\.0\.1:\d+/\?token=')
# Commands that keep running: a pattern, and what shows they are ready.
BACKGROUND = [
    (r'roscore$', [('node', '/rosout')]),
    (r'rosrun turtlesim turtlesim_node$', [('node', '/turtlesim')]),
    (r'rosrun turtlesim turtle_teleop_key$', [('publisher', '/turtle1/cmd_vel')]),
    (r'rostopic echo /turtle1/cmd_vel$', [('subscriber', '/turtle1/cmd_vel')]),
    (r'roslaunch simple_arm robot_spawn.launch arm_mover:=false', [('publisher', '/rgb_camera/image_raw')]),
    (r'roslaunch simple_arm robot_spawn.launch', [('service', '/arm_mover/safe_move')]),
    (r'rosrun simple_arm simple_mover$',
     [('publisher', '/simple_arm/joint_1_position_controller/command')]),
    (r'gazebo\b', [('service', '/gazebo/get_model_state'), ADDRESS]),
    (r'roslaunch my_robot world.launch$', [('service', '/gazebo/get_model_state')]),
    (r'rostopic pub /cmd_vel ', [('publisher', '/cmd_vel')]),
    (r'rosrun ball_chaser drive_bot$', [('service', '/ball_chaser/command_robot')]),
    (r'roslaunch ball_chaser ball_chaser.launch',
     [('service', '/ball_chaser/command_robot'), ('subscriber', '/camera/rgb/image_raw')]),
]
# Commands that read their own terminal get one.
NEEDS_A_TERMINAL = {'rosrun turtlesim turtle_teleop_key'}
# Starting a simulator stops the one before, as the page says (Ctrl+C, then the next).
SIMULATOR = re.compile(r'(gazebo\b|roslaunch my_robot world\.launch|roslaunch simple_arm robot_spawn\.launch)')

# What the student writes between commands: the course's files.
COURSE_EMPTY_WORLD = '''<?xml version="1.0" ?>
<sdf version="1.4">
  <world name="default">
    <include><uri>model://ground_plane</uri></include>
    <include><uri>model://sun</uri></include>
  </world>
</sdf>
'''
COURSE_FIRST_WORLD_LAUNCH = '''<?xml version="1.0" encoding="UTF-8"?>
<launch>
  <arg name="world_file" default="$(find my_robot)/worlds/empty.world"/>
  <include file="$(find gazebo_ros)/launch/empty_world.launch">
    <arg name="use_sim_time" value="true"/>
    <arg name="debug" value="false"/>
    <arg name="gui" value="true" />
    <arg name="world_name" value="$(arg world_file)"/>
  </include>
</launch>
'''
RVIZ_NODE = re.compile(r'\s*<!-- launch rviz -->\s*<node name="rviz"[^>]*/>')


def _package(home, name):
    return home / 'catkin_ws' / 'src' / name


def write_arm_nodes(home):
    """The lesson 3 nodes, GoToPosition.srv and the build lines for them; the project's own
    (Python) here, as tests/test_course_simple_arm.py builds the course's C++ ones."""
    arm = _package(home, 'simple_arm')
    for name in ('CMakeLists.txt', 'package.xml', 'setup.py'):
        shutil.copy(PROJECT_ARM / name, arm / name)
    for folder in ('src', 'scripts', 'srv'):
        shutil.rmtree(arm / folder, ignore_errors=True)
        shutil.copytree(PROJECT_ARM / folder, arm / folder)


def write_empty_world(home):
    robot = _package(home, 'my_robot')
    (robot / 'worlds' / 'empty.world').write_text(COURSE_EMPTY_WORLD)
    (robot / 'launch' / 'world.launch').write_text(COURSE_FIRST_WORLD_LAUNCH)


def _world_launch(world):
    """The submission's world.launch, on the given world; its rviz needs a display, which
    tests/test_studio_course_path.py gives it."""
    text = (SUBMISSION / 'my_robot' / 'launch' / 'world.launch').read_text()
    text, found = RVIZ_NODE.subn('', text)
    assert found == 1, 'the submission fixture changed: no rviz node to leave out'
    return text.replace('worlds/office.world', 'worlds/%s' % world)


def write_robot(home):
    robot = _package(home, 'my_robot')
    for name in ('my_robot.xacro', 'my_robot.gazebo'):
        shutil.copy(SUBMISSION / 'my_robot' / 'urdf' / name, robot / 'urdf' / name)
    shutil.copy(SUBMISSION / 'my_robot' / 'launch' / 'robot_description.launch',
                robot / 'launch' / 'robot_description.launch')
    (robot / 'launch' / 'world.launch').write_text(_world_launch('empty.world'))


def house_the_robot(home):
    (_package(home, 'my_robot') / 'launch' / 'world.launch').write_text(_world_launch('yourname.world'))


def write_chaser(home):
    """drive_bot and process_image, in Python, under the names the course runs them by."""
    chaser = _package(home, 'ball_chaser')
    source = SUBMISSION / 'ball_chaser_py'
    for name in ('CMakeLists.txt', 'package.xml', 'launch/ball_chaser.launch', 'srv/DriveToTarget.srv'):
        text = (source / name).read_text().replace('.py', '')
        # rosrun finds a script both in src and as catkin_install_python's devel relay, and asks
        # which; a course student's C++ node has one executable, and so does this.
        text = re.sub(r'catkin_install_python\([^)]*\)', '', text)
        (chaser / name).write_text(text)
    (chaser / 'scripts').mkdir(exist_ok=True)
    for node in ('drive_bot', 'process_image'):
        shutil.copy(source / 'scripts' / ('%s.py' % node), chaser / 'scripts' / node)


# (step, command, its n-th time in that step): what the student has written by then.
HOOKS = {
    ('Simple mover', 'catkin_make', 1): write_arm_nodes,
    ('The my_robot package', 'catkin_make', 1): write_empty_world,
    ('The robot: URDF in xacro', 'roslaunch my_robot world.launch', 1): write_robot,
    ('House your robot', 'roslaunch my_robot world.launch', 1): house_the_robot,
    ('ball_chaser and drive_bot', 'catkin_make', 2): write_chaser,
}
def press_up_until_echoed(student, terminal):
    """The lesson's arrow key in turtle_teleop_key's terminal, until rostopic echo shows its Twist."""
    echo = next(job for job in student.running if job.command == 'rostopic echo /turtle1/cmd_vel')

    def echoed():
        os.write(student.tty_leader, b'\x1b[A')
        return 'x: 2.0' in echo.log()

    assert wait_until(echoed, READY_S, interval=0.2), echo.log()[-2000:]


def robot_chases_the_ball(_student, terminal):
    # The ball is put 1.5 m from where the robot starts; at 0.5 m the robot has reached it.
    status, output = terminal.run('python %s within my_robot white_ball 0.5 %d'
                                  % (TOP / 'tests' / 'course_ready.py', READY_S))
    assert status == 0, output


# (step, command, its n-th time in that step): what the page says happens after it.
AFTER = {
    ('Run turtlesim', 'rostopic echo /turtle1/cmd_vel', 1): press_up_until_echoed,
    ('process_image', 'rosrun flatsim move_model 1.5 0.3', 1): robot_chases_the_ball,
}


# The project's own answers to what the student writes: while the student types the course,
# none of them may run.
REFERENCE_PACKAGES = ('simple_arm', 'my_robot', 'ball_chaser')
REFERENCE_PATHS = tuple(str(TOP / 'catkin_ws' / space / package) + os.sep
                        for package in REFERENCE_PACKAGES
                        for space in ('src', os.path.join('devel', 'lib')))
_TITLES = list(dict.fromkeys(command.section for command in COMMANDS))
# The sections where the student's own packages run: after the workspace is made, up to the
# finished project.
STUDENT_SECTIONS = set(_TITLES[_TITLES.index('Your own catkin workspace') + 1:
                               _TITLES.index('The finished project: just watch it run')])


def descendants(pid):
    """[(pid, command line)] of a process and everything it started, from /proc."""
    children = collections.defaultdict(list)
    for entry in os.listdir('/proc'):
        if entry.isdigit():
            try:
                with open('/proc/%s/stat' % entry) as stat:
                    parent = int(stat.read().rsplit(')', 1)[1].split()[1])
            except (FileNotFoundError, ProcessLookupError):
                continue
            children[parent].append(int(entry))
    found, queue = [], [pid]
    while queue:
        current = queue.pop()
        try:
            with open('/proc/%d/cmdline' % current, 'rb') as cmdline:
                found.append((current, cmdline.read().replace(b'\0', b' ').decode(errors='replace')))
        except (FileNotFoundError, ProcessLookupError):
            continue
        queue.extend(children.get(current, []))
    return found


def background_spec(text):
    for pattern, ready in BACKGROUND:
        if re.match(pattern, text):
            return ready
    return None


class Student:
    """The student's home folder, their terminals, and what is running in the background."""

    def __init__(self, net, home, logs):
        self.net, self.home, self.logs = net, home, logs
        self.env = {'HOME': str(home), 'PATH': BARE_PATH, 'LANG': 'C.UTF-8', 'TERM': 'dumb'}
        self.running = []
        self.ran = set()
        self.durations = []
        self._seen = collections.Counter()
        self.tty_leader, self._tty_follower = pty.openpty()

    def run_section(self, title):
        commands = [command for command in COMMANDS if command.section == title]
        assert commands, 'docs/course.md has no commands under "## %s"' % title
        for _block, block_commands in itertools.groupby(commands, key=lambda command: command.block):
            terminal = Terminal(self.net, str(TOP), self.env)
            try:
                status, output = terminal.run('if [ -f ~/.bashrc ]; then source ~/.bashrc; fi')
                assert status == 0, output
                for command in block_commands:
                    self.type(terminal, command)
            finally:
                terminal.close()

    def type(self, terminal, command):
        started = time.monotonic()
        try:
            self._type(terminal, command)
        finally:
            self.durations.append((time.monotonic() - started, command.line, command.text.split('\n')[0]))

    def _type(self, terminal, command):
        self._seen[(command.step, command.text)] += 1
        hook = HOOKS.get((command.step, command.text, self._seen[(command.step, command.text)]))
        if hook:
            hook(self.home)
        if command.text in MAPPED:
            return
        ready = background_spec(command.text)
        if ready is None:
            status, output = terminal.run(command.text)
            assert status == 0, 'line %d: %s exited %d:\n%s' % (command.line, command.text, status,
                                                                 output[-4000:])
            for word in command.expected:
                assert word in output, 'line %d: %s never printed %r:\n%s' % (
                    command.line, command.text, word, output[-4000:])
        else:
            self.start(terminal, command, ready)
        self.ran.add(command)
        after = AFTER.get((command.step, command.text, self._seen[(command.step, command.text)]))
        if after:
            after(self, terminal)

    def start(self, terminal, command, ready):
        if SIMULATOR.match(command.text):
            first = next((index for index, job in enumerate(self.running) if SIMULATOR.match(job.command)), None)
        else:
            first = next((index for index, job in enumerate(self.running) if job.command == command.text), None)
        if first is not None:
            self.stop(self.running[first:])
        log = self.logs / ('line%d.log' % command.line)
        stdin = os.ttyname(self._tty_follower) if command.text in NEEDS_A_TERMINAL else '/dev/null'
        job = terminal.start(command.text, log, stdin)
        self.running.append(job)
        for kind, name in ready:
            if kind == 'log':
                shown = wait_until(lambda: re.search(name, job.log()), READY_S, interval=0.2)
                assert shown, 'line %d: %s never printed %s:\n%s' % (command.line, command.text, name,
                                                                      job.log()[-4000:])
            else:
                status, output = terminal.run('python %s %s %s %d' % (TOP / 'tests' / 'course_ready.py',
                                                                     kind, name, READY_S))
                assert status == 0, 'line %d: %s: %s\n%s' % (command.line, command.text, output,
                                                             job.log()[-4000:])
        if command.section in STUDENT_SECTIONS:
            reference = [line for _pid, line in descendants(job.pid)
                         if any(path in line for path in REFERENCE_PATHS)]
            assert not reference, 'line %d: %s runs the project\'s own package: %s' % (
                command.line, command.text, reference)
        for word in command.expected:
            assert wait_until(lambda: word in job.log(), READY_S, interval=0.2), \
                'line %d: %s never printed %r:\n%s' % (command.line, command.text, word, job.log()[-4000:])

    def stop(self, jobs=None):
        jobs = list(self.running if jobs is None else jobs)
        for job in reversed(jobs):
            job.stop()
            self.running.remove(job)

    def close(self):
        slowest = sorted(self.durations, reverse=True)[:12]
        print('slowest commands:\n' + '\n'.join('%6.1f s  line %d: %s' % entry for entry in slowest))
        self.stop()
        os.close(self.tty_leader)
        os.close(self._tty_follower)


@pytest.fixture(scope='module')
def student(tmp_path_factory):
    if not shutil.which('unshare') or not shutil.which('nsenter'):
        pytest.skip('needs unshare and nsenter (util-linux) for a network namespace')
    try:
        net = Namespace()
    except OSError as error:
        pytest.skip(str(error))
    home = tmp_path_factory.mktemp('home')
    logs = tmp_path_factory.mktemp('logs')
    someone = Student(net, home, logs)
    yield someone
    someone.close()
    net.close()


def _sections():
    titles = []
    for command in COMMANDS:
        if command.section not in titles and command.section not in MAPPED_SECTIONS:
            titles.append(command.section)
    return titles


@pytest.mark.parametrize('title', _sections())
def test_the_section_as_the_student_types_it(student, title):
    if title not in CONTINUES:
        student.stop()
    student.run_section(title)


def test_every_command_is_run_or_mapped(student):
    """Runs after the sections: each command of the page was run, or is mapped to a test."""
    unaccounted = [command for command in COMMANDS
                   if command.section not in MAPPED_SECTIONS and command.text not in MAPPED
                   and command not in student.ran]
    assert not unaccounted, '\n'.join('line %d: %s' % (command.line, command.text) for command in unaccounted)
    both = [command for command in student.ran if command.text in MAPPED]
    assert not both


def test_every_mapping_names_a_command_and_a_test_that_exist():
    texts = {command.text for command in COMMANDS}
    sections = {command.section for command in COMMANDS}
    assert not set(MAPPED) - texts, 'mapped, but not on the page: %s' % (set(MAPPED) - texts)
    assert not set(MAPPED_SECTIONS) - sections
    counts = collections.Counter((command.step, command.text) for command in COMMANDS)
    for step, text, nth in list(HOOKS) + list(AFTER):
        assert counts[(step, text)] >= nth, 'no %r the %d. time under "%s"' % (text, nth, step)
    for test_id in list(MAPPED.values()) + list(MAPPED_SECTIONS.values()):
        path, name = test_id.split('::')
        assert re.search(r'^def %s\(' % re.escape(name), (TOP / path).read_text(), re.M), test_id


def test_every_long_running_command_has_a_readiness():
    """A new command that keeps running needs a line in BACKGROUND; one-shot commands end."""
    keeps_running = re.compile(r'(roscore|roslaunch |rosrun \S+ \S+|gazebo|rostopic (echo|pub) )')
    one_shot = re.compile(r'(rosrun flatsim (inspect|move_model)|rosrun gazebo_ros spawn_model|rostopic pub -1 '
                          r'|rosrun chase_tools course_files)')
    missing = [command.text for command in COMMANDS
               if keeps_running.match(command.text) and not one_shot.match(command.text)
               and command.text not in MAPPED and command.section not in MAPPED_SECTIONS
               and background_spec(command.text) is None]
    assert not missing, missing


def _anchor(heading):
    """GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r'[^\w\- ]', '', heading.strip().lower()).replace(' ', '-')


def test_links_to_the_page_name_headings_it_has():
    anchors = {_anchor(line.lstrip('#')) for line in DOC.read_text().splitlines() if line.startswith('#')}
    links = re.findall(r'\]\((#[^)]+)\)', DOC.read_text())
    for other in [TOP / 'README.md'] + sorted((TOP / 'docs').glob('*.md')):
        links += ['#' + target for target in re.findall(r'course\.md#([^)\s]+)', other.read_text())]
    broken = sorted({link for link in links if link[1:] not in anchors})
    assert not broken, broken


def test_the_page_parser_joins_a_quoted_request_and_reads_the_printed_words():
    page = ('## Section\n\n**A step.** Text.\n\n```bash\n# an annotation\n'
            'rosservice call /x "a: 1\nb: 2"   # → ok: yes\n'
            "rosed x Twist.msg                 # the message's comments\n"
            'foo \\\n  --bar\n```\n')
    commands = parse(page)
    assert [command.text for command in commands] == ['rosservice call /x "a: 1\nb: 2"', 'rosed x Twist.msg',
                                                      'foo \\\n  --bar']
    assert commands[0].expected == ('ok:', 'yes') and commands[1].expected == ()
    assert {(command.section, command.step) for command in commands} == {('Section', 'A step')}
    with pytest.raises(ValueError, match='line 6: a command is not closed'):
        parse('## S\n\n```bash\nls\n\necho "open\n```\n')


def _runs_a_reference_node(pid):
    return any(path in line for _pid, line in descendants(pid) for path in REFERENCE_PATHS)


def test_a_node_of_the_projects_own_package_is_seen_among_what_a_command_started():
    node = str(TOP / 'catkin_ws' / 'src' / 'ball_chaser' / 'scripts' / 'drive_bot')
    students = '/home/student/catkin_ws/src/ball_chaser/scripts/drive_bot'
    # A shell that starts a process under that name, as rosrun starts a node.
    shells = {name: subprocess.Popen(['bash', '-c', '(exec -a %s sleep 30) & wait' % name],
                                     start_new_session=True) for name in (node, students)}
    try:
        assert wait_until(lambda: _runs_a_reference_node(shells[node].pid), 10.0)
        assert wait_until(lambda: len(descendants(shells[students].pid)) == 2, 10.0)
        assert not _runs_a_reference_node(shells[students].pid)
    finally:
        for shell in shells.values():
            os.killpg(shell.pid, signal.SIGKILL)
            shell.wait()
