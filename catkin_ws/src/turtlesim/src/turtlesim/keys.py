"""turtle_teleop_key's keyboard: its key codes and its terminal mode.

The original reads its terminal one byte at a time and acts on the last byte
of each arrow key's escape sequence (ESC [ A for up, and so on): the ESC and
'[' bytes do nothing, and a capital A, B, C or D typed alone moves the turtle
too. This module keeps that behaviour.
"""
import os
import termios
from dataclasses import dataclass

KEYCODE_UP = 0x41
KEYCODE_DOWN = 0x42
KEYCODE_RIGHT = 0x43
KEYCODE_LEFT = 0x44
KEYCODE_Q = 0x71

# (linear, angular) in units of the scales, for each key that drives.
_DRIVES = {
    KEYCODE_UP: (1.0, 0.0),
    KEYCODE_DOWN: (-1.0, 0.0),
    KEYCODE_LEFT: (0.0, 1.0),
    KEYCODE_RIGHT: (0.0, -1.0),
}

BANNER = ("Reading from keyboard\n"
          "---------------------------\n"
          "Use arrow keys to move the turtle. 'q' to quit.")


class NotATerminalError(RuntimeError):
    pass


@dataclass(frozen=True)
class KeyAction:
    """What a byte from the keyboard asks for: quit, or drive at (linear_x, angular_z)."""
    quit: bool = False
    linear_x: float = 0.0
    angular_z: float = 0.0


QUIT = KeyAction(quit=True)


def decode_key(byte, linear_scale=2.0, angular_scale=2.0):
    """The KeyAction for one byte (an int), or None for a byte that does nothing."""
    if byte == KEYCODE_Q:
        return QUIT
    drive = _DRIVES.get(byte)
    if drive is None:
        return None
    return KeyAction(linear_x=linear_scale * drive[0], angular_z=angular_scale * drive[1])


class RawTerminal:
    """The terminal on `fd` without line buffering or echo while inside the
    `with` block, as the original sets it; its settings come back on exit,
    whatever ends the block."""

    def __init__(self, fd):
        if not os.isatty(fd):
            raise NotATerminalError('standard input is not a terminal')
        self.fd = fd
        self.cooked = termios.tcgetattr(fd)

    def __enter__(self):
        raw = termios.tcgetattr(self.fd)
        raw[3] &= ~(termios.ICANON | termios.ECHO)
        raw[6][termios.VEOL] = 1
        raw[6][termios.VEOF] = 2
        termios.tcsetattr(self.fd, termios.TCSANOW, raw)
        return self

    def __exit__(self, *exc):
        termios.tcsetattr(self.fd, termios.TCSANOW, self.cooked)
        return False
