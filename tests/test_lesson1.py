"""Lesson 1 of the course, typed as the course gives it: roscore, then
`rosrun turtlesim turtlesim_node` and `rosrun turtlesim turtle_teleop_key`
(in a terminal of its own), then `rosnode list`, `rostopic list`,
`rostopic info /turtle1/cmd_vel`, `rosmsg info geometry_msgs/Twist` and
`rostopic echo /turtle1/cmd_vel` while an arrow key is pressed. Everything the
lesson shows must appear. turtle_teleop_key's terminal is a pseudo-terminal:
its keys become Twists, and its terminal settings come back on 'q' and on Ctrl-C.
"""
import os
import pty
import select
import signal
import subprocess
import termios
import time

from rosproc import RosSystem, wait_until

WAIT_S = 30.0
BANNER = (b"Reading from keyboard\r\n---------------------------\r\n"
          b"Use arrow keys to move the turtle. 'q' to quit.\r\n")
UP, LEFT = b'\x1b[A', b'\x1b[D'
TWIST_UP = 'linear: \n  x: 2.0\n  y: 0.0\n  z: 0.0\nangular: \n  x: 0.0\n  y: 0.0\n  z: 0.0\n'
TWIST_LEFT = 'linear: \n  x: 0.0\n  y: 0.0\n  z: 0.0\nangular: \n  x: 0.0\n  y: 0.0\n  z: 2.0\n'


class Terminal:
    """A command run by a user at a terminal: a pseudo-terminal is its standard input and output."""

    def __init__(self, ros, name, command):
        self.leader, self.follower = pty.openpty()
        self.cooked = termios.tcgetattr(self.follower)
        self.output = b''
        self.process = subprocess.Popen(command, env=ros.env, stdin=self.follower, stdout=self.follower,
                                        stderr=self.follower, start_new_session=True)
        ros.procs[name] = self.process

    def read_until(self, text):
        deadline = time.monotonic() + WAIT_S
        while text not in self.output:
            remaining = deadline - time.monotonic()
            assert remaining > 0 and self.process.poll() is None, \
                'never printed %r; printed %r' % (text, self.output)
            if select.select([self.leader], [], [], remaining)[0]:
                self.output += os.read(self.leader, 4096)

    def raw(self):
        return not termios.tcgetattr(self.follower)[3] & (termios.ICANON | termios.ECHO)

    def restored(self):
        return termios.tcgetattr(self.follower) == self.cooked

    def close(self):
        os.close(self.leader)
        os.close(self.follower)


def run_at_once(ros, *commands):
    """Each command's output, as from several terminals at once."""
    processes = [subprocess.Popen(command.split(), env=ros.env, stdout=subprocess.PIPE, text=True)
                 for command in commands]
    outputs = [process.communicate(timeout=WAIT_S)[0] for process in processes]
    for command, process in zip(commands, processes):
        assert process.returncode == 0, command
    return outputs


def echo_while_pressing(ros, terminal, keys):
    """What `rostopic echo -n 2 /turtle1/cmd_vel` prints while the keys are pressed in turn, over and over."""
    echo = subprocess.Popen(['rostopic', 'echo', '-n', '2', '/turtle1/cmd_vel'], env=ros.env,
                            stdout=subprocess.PIPE, text=True)
    deadline = time.monotonic() + WAIT_S
    presses = 0
    while echo.poll() is None and time.monotonic() < deadline:
        os.write(terminal.leader, keys[presses % len(keys)])
        presses += 1
        time.sleep(0.1)
    return echo.communicate(timeout=WAIT_S)[0]


def meet_on(ros, topic, publisher, subscriber):
    published, subscribed, _ = ros.graph.master().getSystemState()
    return publisher in dict(published).get(topic, []) and subscriber in dict(subscribed).get(topic, [])


def ctrl_c_restores_the_terminal(teleop):
    teleop.read_until(BANNER)
    assert teleop.raw()
    os.killpg(teleop.process.pid, signal.SIGINT)
    assert teleop.process.wait(WAIT_S) == 0
    assert teleop.restored()
    assert b'Traceback' not in teleop.output


def test_lesson_1_as_the_course_types_it(tmp_path):
    with RosSystem(tmp_path) as ros:
        ros.run('turtlesim', ['rosrun', 'turtlesim', 'turtlesim_node'])
        teleop = Terminal(ros, 'teleop', ['rosrun', 'turtlesim', 'turtle_teleop_key'])
        second = None
        try:
            teleop.read_until(BANNER)
            assert teleop.output == BANNER
            assert teleop.raw()
            assert wait_until(lambda: meet_on(ros, '/turtle1/cmd_vel', '/teleop_turtle', '/turtlesim'),
                              WAIT_S), 'teleop_turtle and turtlesim never met on /turtle1/cmd_vel'

            nodes, topics, info, twist = run_at_once(
                ros, 'rosnode list', 'rostopic list', 'rostopic info /turtle1/cmd_vel',
                'rosmsg info geometry_msgs/Twist')
            assert nodes == '/rosout\n/teleop_turtle\n/turtlesim\n'
            assert {'/rosout', '/rosout_agg', '/turtle1/cmd_vel', '/turtle1/color_sensor',
                    '/turtle1/pose'} <= set(topics.split())
            lines = info.splitlines()
            assert lines[0] == 'Type: geometry_msgs/Twist'
            publishers = lines[lines.index('Publishers: '):lines.index('Subscribers: ')]
            subscribers = lines[lines.index('Subscribers: '):]
            # " * /teleop_turtle (http://localhost:PORT/)": one of each, as the lesson says.
            assert [line.split()[1] for line in publishers if line.startswith(' * ')] == ['/teleop_turtle']
            assert [line.split()[1] for line in subscribers if line.startswith(' * ')] == ['/turtlesim']
            assert twist == ('geometry_msgs/Vector3 linear\n  float64 x\n  float64 y\n  float64 z\n'
                             'geometry_msgs/Vector3 angular\n  float64 x\n  float64 y\n  float64 z\n\n')

            # A second teleop, in a terminal of its own, to stop with Ctrl-C; it starts while the first is used.
            second = Terminal(ros, 'teleop_ctrl_c',
                              ['rosrun', 'turtlesim', 'turtle_teleop_key', '__name:=teleop_ctrl_c'])
            # Up and left in turn: two messages in a row are one of each.
            printed = echo_while_pressing(ros, teleop, [UP, LEFT])
            assert sorted(printed.split('---\n')) == ['', TWIST_LEFT, TWIST_UP]

            os.write(teleop.leader, b'q')
            assert teleop.process.wait(WAIT_S) == 0
            assert teleop.restored()
            ctrl_c_restores_the_terminal(second)
        finally:
            teleop.close()
            if second is not None:
                second.close()


def test_headless_turtlesim_says_so_in_one_whole_line(tmp_path):
    with RosSystem(tmp_path) as ros:
        ros.env.pop('DISPLAY', None)
        node = Terminal(ros, 'turtlesim', ['rosrun', 'turtlesim', 'turtlesim_node'])
        try:
            notice = b'turtlesim runs headless; the canvas is published on /turtlesim/image'
            # The line ends where the notice does: the next output starts on a line of its own.
            node.read_until(notice + b'\r\n')
            start = node.output.rindex(b'\r\n', 0, node.output.index(notice)) + 2
            line = node.output[start:].split(b'\r\n', 1)[0]
            assert line.startswith(b'[INFO] [') and line.endswith(b'No window (DISPLAY is not set): ' + notice)
        finally:
            node.close()
