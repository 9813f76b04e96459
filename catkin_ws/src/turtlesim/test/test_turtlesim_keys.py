"""turtle_teleop_key's keys and terminal, without ROS."""
import os
import pty
import subprocess
import sys
import termios

import pytest

from turtlesim.keys import QUIT, KeyAction, NotATerminalError, RawTerminal, decode_key


@pytest.mark.parametrize('keys, expected', [
    (b'\x1b[A', KeyAction(linear_x=2.0)),
    (b'\x1b[B', KeyAction(linear_x=-2.0)),
    (b'\x1b[D', KeyAction(angular_z=2.0)),
    (b'\x1b[C', KeyAction(angular_z=-2.0)),
    (b'q', QUIT),
    # The original acts on single bytes: a capital A is "up" too, other keys do nothing.
    (b'A', KeyAction(linear_x=2.0)),
    (b'x', None),
    (b'Q', None),
])
def test_each_arrow_key_gives_one_command_at_the_default_scales(keys, expected):
    actions = [decode_key(byte) for byte in keys]
    assert actions[-1] == expected
    assert all(action is None for action in actions[:-1])


def test_scales_multiply_the_unit_commands():
    assert decode_key(0x41, 0.5, 3.0) == KeyAction(linear_x=0.5)
    assert decode_key(0x43, 0.5, 3.0) == KeyAction(angular_z=-3.0)


def test_raw_terminal_turns_off_line_buffering_and_echo_and_restores_them():
    leader, follower = pty.openpty()
    try:
        before = termios.tcgetattr(follower)
        assert before[3] & termios.ICANON and before[3] & termios.ECHO
        with pytest.raises(RuntimeError):
            with RawTerminal(follower):
                raw = termios.tcgetattr(follower)
                assert not raw[3] & (termios.ICANON | termios.ECHO)
                raise RuntimeError('the block ends with an error')
        assert termios.tcgetattr(follower) == before
    finally:
        os.close(leader)
        os.close(follower)


def test_a_pipe_is_not_a_terminal():
    read_end, write_end = os.pipe()
    try:
        with pytest.raises(NotATerminalError):
            RawTerminal(read_end)
    finally:
        os.close(read_end)
        os.close(write_end)


def test_teleop_without_a_terminal_exits_with_a_clear_message_and_no_traceback():
    result = subprocess.run([sys.executable, '-c', 'from turtlesim.nodes.teleop_key import main; main()'],
                            stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=60,
                            env=dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path)))
    assert result.returncode == 1
    assert 'standard input is not a terminal' in result.stderr
    assert 'Traceback' not in result.stderr
