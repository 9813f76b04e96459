"""The course's shell habits in a real interactive bash after `source env.sh`:
roscd, rosls, rosed, and tab completion of packages, message and service bodies.

Each test types into bash running on a pseudo-terminal, as in a terminal
window, starting from a bare environment (no ROS variables, a fresh HOME).
"""
import fcntl
import os
import pathlib
import pty
import re
import select
import signal
import struct
import termios
import time

import pytest

from rosproc import RosSystem

TOP = pathlib.Path(__file__).resolve().parent.parent
TAB = '\t'
_ANSI = re.compile(r'\x1b\[[0-9;?]*[A-Za-z]|\x1b[()][A-Z0-9]|\r')


class Terminal:
    """bash -i on a pseudo-terminal 200 columns wide; type() keys, expect() what appears."""

    def __init__(self, home, env=None):
        base = {'HOME': str(home), 'TERM': 'xterm', 'LANG': 'C.UTF-8',
                'PATH': '/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin'}
        self.pid, self.fd = pty.fork()
        if self.pid == 0:
            os.chdir(str(home))
            os.execve('/bin/bash', ['bash', '--noprofile', '--norc', '-i'], dict(base, **(env or {})))
        fcntl.ioctl(self.fd, termios.TIOCSWINSZ, struct.pack('HHHH', 50, 200, 0, 0))
        self.screen = ''

    def type(self, keys):
        os.write(self.fd, keys.encode())

    def expect(self, pattern, timeout=30.0):
        """Read output until pattern (a regex) matches what came since the last expect()."""
        seen = ''
        deadline = time.monotonic() + timeout
        while True:
            match = re.search(pattern, _ANSI.sub('', seen))
            if match:
                return match
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError('no %r within %g s; the terminal showed:\n%s'
                                     % (pattern, timeout, _ANSI.sub('', seen)[-3000:]))
            ready, _, _ = select.select([self.fd], [], [], min(left, 0.5))
            if ready:
                try:
                    chunk = os.read(self.fd, 65536).decode(errors='replace')
                except OSError:
                    chunk = ''
                seen += chunk
                self.screen += chunk

    def clear_line(self):
        """Ctrl-U: drop what is on the command line (several lines, for a completed body)."""
        self.type('\x15')
        assert self.run('echo cleared').split() == ['cleared']

    def run(self, command, timeout=60.0):
        """Type a command line and wait until it has finished; returns what it printed."""
        marker = 'done-%d' % time.monotonic_ns()
        self.type('%s; echo "%s $?"\n' % (command, marker))
        # The echoed command line ends in the marker and "$?", its last output line in a number.
        return self.expect(r'(?s)%s \$\?"\n(.*)%s \d+\n' % (marker, marker), timeout).group(1)

    def close(self):
        try:
            os.kill(self.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        os.waitpid(self.pid, 0)
        os.close(self.fd)


@pytest.fixture
def terminal(tmp_path):
    term = Terminal(tmp_path)
    try:
        term.run('source %s/env.sh' % TOP)
        yield term
    finally:
        term.close()


def test_roscd_and_rosls_find_the_projects_packages(terminal):
    assert terminal.run('roscd my_robot/launch && pwd').strip().endswith('catkin_ws/src/my_robot/launch')
    listing = terminal.run('rosls ball_chaser').split()
    assert 'srv' in listing and 'launch' in listing


def test_rosed_opens_a_message_definition(terminal):
    shown = terminal.run('EDITOR=cat rosed geometry_msgs Twist.msg')
    assert 'Vector3  linear' in shown and 'Vector3  angular' in shown, shown


def test_tab_completes_packages_and_their_executables(terminal):
    terminal.type('rosrun ball_cha' + TAB)
    terminal.expect(r'rosrun ball_chaser $')
    terminal.type(TAB + TAB)
    terminal.expect(r'drive_bot\s+process_image|process_image\s+drive_bot')
    terminal.clear_line()
    terminal.type('roscd my_rob' + TAB)
    terminal.expect(r'roscd my_robot/$')
    terminal.clear_line()


def test_tab_completes_a_message_body(terminal):
    terminal.type('rostopic pub /cmd_vel geometry_msgs/Twist ' + TAB)
    body = terminal.expect(r'"linear:\s+x: 0\.0\s+y: 0\.0\s+z: 0\.0\s+angular:\s+x: 0\.0')
    assert body
    terminal.clear_line()


def test_tab_completes_the_course_topic_type_and_service_request(tmp_path):
    """With the robot's drive_bot running: `rostopic pub /cmd_vel <TAB><TAB>` fills in the
    type and the message, and `rosservice call /ball_chaser/command_robot <TAB>` the request."""
    with RosSystem(tmp_path) as ros:
        ros.run('drive_bot', ['rosrun', 'ball_chaser', 'drive_bot'])
        ros.graph.wait_for_service('/ball_chaser/command_robot')
        term = Terminal(tmp_path, env={'ROS_MASTER_URI': ros.master_uri})
        try:
            term.run('source %s/env.sh' % TOP)
            # The course: type up to `rostopic pub /cmd_vel`, then TAB twice.
            term.type('rostopic pub /cmd_vel ' + TAB + TAB)
            term.expect(r'rostopic pub /cmd_vel geometry_msgs/Twist "linear:\s+x: 0\.0')
            term.clear_line()
            term.type('rosservice call /ball_chaser/command_robot ' + TAB)
            term.expect(r'"linear_x: 0\.0\s+angular_z: 0\.0"')
            term.clear_line()
        finally:
            term.close()
