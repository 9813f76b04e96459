"""The canvas the turtles draw on, and the picture of it with the turtles.

The canvas is an RGB image, CANVAS_PIXELS on a side. Pens draw aliased lines,
so a pixel under a pen stroke has exactly the pen's colour: that is what each
turtle's color_sensor reads back.
"""
import math
from dataclasses import dataclass

import cv2
import numpy as np

from turtlesim.motion import CANVAS_PIXELS, METER_PIXELS

DEFAULT_BACKGROUND = (0x45, 0x56, 0xff)


@dataclass(frozen=True)
class Pen:
    r: int = 0xb3
    g: int = 0xb8
    b: int = 0xff
    width: int = 3

    @classmethod
    def from_request(cls, r, g, b, width):
        """The pen a set_pen request gives; width 0 keeps Qt's default pen width, 1."""
        return cls(r, g, b, width if width != 0 else 1)

    @property
    def rgb(self):
        return (self.r, self.g, self.b)


def to_pixel(position):
    """Canvas metres (y downwards) to the nearest pixel (column, row)."""
    x, y = position
    return (int(math.floor(x * METER_PIXELS + 0.5)), int(math.floor(y * METER_PIXELS + 0.5)))


class Canvas:
    def __init__(self, background=DEFAULT_BACKGROUND, size=CANVAS_PIXELS):
        self.pixels = np.empty((size, size, 3), dtype=np.uint8)
        self.clear(background)

    def clear(self, background):
        self.pixels[:] = background

    def draw_line(self, start, end, pen):
        """A stroke between two positions in canvas metres."""
        cv2.line(self.pixels, to_pixel(start), to_pixel(end), pen.rgb, pen.width, cv2.LINE_8)

    def color_at(self, position):
        """(r, g, b) of the pixel under a position in canvas metres."""
        column, row = to_pixel(position)
        size = self.pixels.shape[0]
        column = min(max(column, 0), size - 1)
        row = min(max(row, 0), size - 1)
        return tuple(int(c) for c in self.pixels[row, column])

    def picture(self, turtles):
        """A copy of the canvas with each turtle drawn on it; turtles are
        (position in canvas metres, heading theta) pairs."""
        frame = self.pixels.copy()
        for position, theta in turtles:
            draw_turtle(frame, position, theta)
        return frame


# The turtle, drawn in pixels in its own frame: +u ahead, +v to its left.
_SHELL = (17.0, 13.0)
_HEAD_CENTRE, _HEAD_RADIUS = (21.0, 0.0), 6.0
_FEET = [((10.0, 12.0), 5.0), ((10.0, -12.0), 5.0), ((-10.0, 12.0), 5.0), ((-10.0, -12.0), 5.0)]
_TAIL = [(-15.0, 3.5), (-24.0, 0.0), (-15.0, -3.5)]
_SKIN = (126, 200, 80)
_SHELL_COLOUR = (46, 110, 40)
_SHELL_RIM = (24, 64, 22)
_SUBPIXEL_BITS = 4


def _ellipse(centre, radii, points=24):
    angles = np.linspace(0.0, 2.0 * math.pi, points, endpoint=False)
    return np.stack([centre[0] + radii[0] * np.cos(angles), centre[1] + radii[1] * np.sin(angles)], axis=1)


# Drawn in this order, each over the last; only where and which way the turtle faces changes.
_BODY = ([(_ellipse(c, (r, r)), _SKIN) for c, r in _FEET]
         + [(np.array(_TAIL), _SKIN),
            (_ellipse(_HEAD_CENTRE, (_HEAD_RADIUS, _HEAD_RADIUS)), _SKIN),
            (_ellipse((0.0, 0.0), _SHELL), _SHELL_RIM),
            (_ellipse((0.0, 0.0), (_SHELL[0] - 3.0, _SHELL[1] - 3.0)), _SHELL_COLOUR)])


def _to_screen(body_points, position, theta):
    """Body-frame pixel offsets to fixed-point screen points (y downwards)."""
    cx, cy = position[0] * METER_PIXELS, position[1] * METER_PIXELS
    cos, sin = math.cos(theta), math.sin(theta)
    u, v = body_points[:, 0], body_points[:, 1]
    screen = np.stack([cx + u * cos - v * sin, cy - u * sin - v * cos], axis=1)
    return np.round(screen * (1 << _SUBPIXEL_BITS)).astype(np.int32)


def draw_turtle(frame, position, theta):
    """A turtle seen from above at `position` (canvas metres), facing `theta`."""
    for points, colour in _BODY:
        cv2.fillPoly(frame, [_to_screen(points, position, theta)], colour, cv2.LINE_AA, _SUBPIXEL_BITS)
