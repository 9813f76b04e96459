"""The course's simple_arm scene, for tests: where its number blocks are, where
the arm's camera is, and what a camera image shows of the blocks.

The blocks' poses are those of the <state> block of the course's
willow_garage.world (tests/fixtures/course_simple_arm holds a world of that
shape); the arm's sizes are those of the course's URDF.
"""
import math
import os

import numpy as np

from flatsim.loading.stand_ins import DIGIT_HEIGHT

FIXTURE = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'fixtures', 'course_simple_arm')
BLOCK_CENTRES = {1: (-1.0, 3.34, 1.115), 2: (0.0, 3.34, 1.11504), 3: (1.0, 3.34, 1.115)}
BLOCK_SIDE = 0.8 * 0.5                   # number.dae's cube at the world's mesh scale
WIDTH, HEIGHT, HFOV = 640, 480, 1.4
DARK = 60                                # the black digit, however lit, stays below this
# joint_2 sits 0.2 m beside link_1 and 1.1 m up; the camera is 0.75 m up link_2.
JOINT_2_OFFSET = np.array([0.0, 0.2, 1.1])
CAMERA_ON_LINK_2 = np.array([0.0, 0.0, 0.75])
HALF_PI_AS_WRITTEN = 3.14159 / 2         # the course's camera pitch


def _rot_z(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rot_y(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def arm_camera(joint_1, joint_2):
    """The camera's position and (forward, left, up) world axes at these joint angles."""
    link_2 = _rot_z(joint_1) @ _rot_y(joint_2)
    eye = _rot_z(joint_1) @ JOINT_2_OFFSET + link_2 @ CAMERA_ON_LINK_2
    camera = link_2 @ _rot_y(-HALF_PI_AS_WRITTEN)
    return eye, (camera[:, 0], camera[:, 1], camera[:, 2])


def project(point, eye, axes):
    """Pixel (column, row) of a world point, by the pinhole model of the arm's camera."""
    forward, left, up = axes
    offset = np.asarray(point, dtype=float) - eye
    depth = forward @ offset
    focal = WIDTH / (2.0 * math.tan(HFOV / 2.0))
    return ((WIDTH - 1) / 2.0 - focal * (left @ offset) / depth,
            (HEIGHT - 1) / 2.0 - focal * (up @ offset) / depth)


def _pixel(image, point, eye, axes):
    column, row = project(point, eye, axes)
    return image[int(round(row)), int(round(column))]


def front_glyph(image, digit, eye, axes):
    """The 3 x 5 glyph on the block's face towards the arm (-y), read where each font cell projects."""
    x, y, z = BLOCK_CENTRES[digit]
    cell = DIGIT_HEIGHT * BLOCK_SIDE / 5.0
    face_y = y - BLOCK_SIDE / 2.0
    return tuple(''.join('X' if _pixel(image, (x + (col - 1) * cell, face_y, z + (2 - row) * cell),
                                       eye, axes).max() < DARK else '.'
                         for col in range(3))
                 for row in range(5))


def face_corner(image, digit, eye, axes):
    """The colour near the top left corner of the block's face towards the arm (no digit there)."""
    x, y, z = BLOCK_CENTRES[digit]
    inset = BLOCK_SIDE * 0.4
    return _pixel(image, (x - inset, y - BLOCK_SIDE / 2.0, z + inset), eye, axes)
