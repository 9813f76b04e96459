"""Rigid transforms with SDF/URDF conventions: fixed-axis roll, pitch, yaw (Rz*Ry*Rx)."""
import math
from dataclasses import dataclass

import numpy as np

from flatsim.errors import FlatsimError


def rpy_to_matrix(roll, pitch, yaw):
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


def matrix_to_rpy(rot):
    pitch = math.atan2(-rot[2, 0], math.hypot(rot[0, 0], rot[1, 0]))
    if abs(math.cos(pitch)) < 1e-9:
        # Gimbal lock: put all of the rotation about z into yaw.
        return 0.0, pitch, math.atan2(-rot[0, 1], rot[1, 1])
    return math.atan2(rot[2, 1], rot[2, 2]), pitch, math.atan2(rot[1, 0], rot[0, 0])


@dataclass(frozen=True)
class Pose:
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0

    @classmethod
    def parse(cls, text):
        """Read SDF's "x y z roll pitch yaw" (or URDF's xyz/rpy pairs joined)."""
        try:
            values = [float(v) for v in (text or '').split()]
        except ValueError:
            raise FlatsimError('pose %r is not six numbers' % text) from None
        if not values:
            return cls()
        if len(values) != 6 or not all(math.isfinite(v) for v in values):
            raise FlatsimError('pose %r is not six finite numbers' % text)
        return cls(*values)

    @classmethod
    def from_matrix(cls, mat):
        roll, pitch, yaw = matrix_to_rpy(mat[:3, :3])
        return cls(float(mat[0, 3]), float(mat[1, 3]), float(mat[2, 3]), roll, pitch, yaw)

    def matrix(self):
        mat = np.eye(4)
        mat[:3, :3] = rpy_to_matrix(self.roll, self.pitch, self.yaw)
        mat[:3, 3] = (self.x, self.y, self.z)
        return mat

    def __mul__(self, child):
        """This pose composed with a child pose expressed in this pose's frame."""
        return Pose.from_matrix(self.matrix() @ child.matrix())
