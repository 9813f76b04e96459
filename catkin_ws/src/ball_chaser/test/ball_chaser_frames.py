"""Synthetic camera frames for the detection and control tests.

A frame is a grey room (walls of a given grey over a darker floor) with an
optional disc of a given colour, packed as a sensor_msgs/Image would carry it.
"""
import types

import numpy as np

from ball_chaser.detect import CHANNELS

WALL = (200, 200, 200)
FLOOR = (90, 90, 90)


def rgb_scene(width=120, height=90, ball_centre=None, radius=10, ball_rgb=(255, 255, 255), wall_rgb=WALL):
    """(height, width, 3) uint8 RGB frame; ball_centre is (column, row) in pixels, may lie outside."""
    scene = np.empty((height, width, 3), dtype=np.uint8)
    scene[:height // 2] = wall_rgb
    scene[height // 2:] = FLOOR
    if ball_centre is not None:
        rows, columns = np.mgrid[0:height, 0:width]
        inside = (columns - ball_centre[0]) ** 2 + (rows - ball_centre[1]) ** 2 <= radius ** 2
        scene[inside] = ball_rgb
    return scene


def encode(rgb, encoding, padding=0, alpha=255):
    """Pack an RGB frame into an Image-like object in encoding, with padding bytes after each row."""
    height, width, _ = rgb.shape
    if encoding == 'rgb8':
        pixels = rgb
    elif encoding == 'bgr8':
        pixels = rgb[:, :, ::-1]
    elif encoding == 'rgba8':
        pixels = np.dstack([rgb, np.full((height, width), alpha, np.uint8)])
    elif encoding == 'bgra8':
        pixels = np.dstack([rgb[:, :, ::-1], np.full((height, width), alpha, np.uint8)])
    elif encoding == 'mono8':
        pixels = np.rint(rgb @ np.array([0.299, 0.587, 0.114])).astype(np.uint8)[:, :, None]
    else:
        raise ValueError(encoding)
    row_bytes = width * CHANNELS[encoding]
    step = row_bytes + padding
    # Padding bytes are 255 so that reading them as pixels would show up as white ball pixels.
    rows = np.full((height, step), 255, dtype=np.uint8)
    rows[:, :row_bytes] = pixels.reshape(height, row_bytes)
    return types.SimpleNamespace(height=height, width=width, encoding=encoding, step=step, data=rows.tobytes())
