"""What the sensors see: 2.5D boxes, cylinders and spheres in the world frame.

Each primitive is a 2D shape (a yawed rectangle or a circle) with a height
interval. The scene keeps them as packed numpy arrays, one entry per
primitive, so that a raycast handles all of them in a few array operations.
Indices returned by add() stay valid for the life of the scene: remove() only
marks a slot dead, so the handles held for dynamic things (the ball, other
robots) never shift.
"""
import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np

from flatsim.errors import FlatsimError

BOX, CYLINDER, SPHERE = 0, 1, 2
KINDS = {'box': BOX, 'cylinder': CYLINDER, 'sphere': SPHERE}

# Gazebo's default <scene><background> grey and a darker ground, so that
# nothing in an empty world renders pure white.
DEFAULT_SKY_COLOR = (0.7, 0.7, 0.7)
DEFAULT_FLOOR_COLOR = (0.45, 0.45, 0.45)


@dataclass
class Prim:
    """One primitive. x, y, yaw place its centre; z_min..z_max is its height span.

    A sphere's z_min and z_max are its centre height -/+ radius (see sphere()).
    collision: the lidar sees it; visual: the camera sees it.
    unlit_white: an emissive white surface, rendered as exactly (255, 255, 255).
    """
    name: str
    kind: str
    x: float
    y: float
    yaw: float = 0.0
    half_x: float = 0.0
    half_y: float = 0.0
    radius: float = 0.0
    z_min: float = 0.0
    z_max: float = 0.0
    color: Tuple[float, float, float] = (0.7, 0.7, 0.7)
    unlit_white: bool = False
    collision: bool = True
    visual: bool = True

    @classmethod
    def box(cls, name, x, y, yaw, size_x, size_y, z_min, z_max, **kwargs):
        return cls(name, 'box', x, y, yaw, half_x=size_x / 2.0, half_y=size_y / 2.0,
                   z_min=z_min, z_max=z_max, **kwargs)

    @classmethod
    def cylinder(cls, name, x, y, radius, z_min, z_max, **kwargs):
        return cls(name, 'cylinder', x, y, radius=radius, z_min=z_min, z_max=z_max, **kwargs)

    @classmethod
    def sphere(cls, name, x, y, z, radius, **kwargs):
        return cls(name, 'sphere', x, y, radius=radius, z_min=z - radius, z_max=z + radius,
                   **kwargs)

    def validate(self):
        """Raise FlatsimError naming the primitive if it cannot be raycast."""
        if self.kind not in KINDS:
            raise FlatsimError('primitive %r: kind %r is not one of %s'
                               % (self.name, self.kind, ', '.join(sorted(KINDS))))
        numbers = (self.x, self.y, self.yaw, self.half_x, self.half_y, self.radius,
                   self.z_min, self.z_max)
        if not all(math.isfinite(v) for v in numbers):
            raise FlatsimError('primitive %r has a non-finite pose or size' % self.name)
        if self.kind == 'box' and (self.half_x <= 0 or self.half_y <= 0):
            raise FlatsimError('box %r needs positive sizes, got half sizes %g x %g'
                               % (self.name, self.half_x, self.half_y))
        if self.kind != 'box' and self.radius <= 0:
            raise FlatsimError('%s %r needs a positive radius, got %g'
                               % (self.kind, self.name, self.radius))
        if self.z_max < self.z_min:
            raise FlatsimError('primitive %r: z_max %g is below z_min %g'
                               % (self.name, self.z_max, self.z_min))
        # Relative slack: far from the floor the centre -/+ radius rounds by more than 1e-9 m.
        slack = 1e-9 * max(1.0, abs(self.z_min), abs(self.z_max))
        if self.kind == 'sphere' and abs((self.z_max - self.z_min) - 2 * self.radius) > slack:
            raise FlatsimError('sphere %r: z_min..z_max must be its centre height -/+ radius'
                               % self.name)
        if len(self.color) != 3 or not all(0.0 <= c <= 1.0 for c in self.color):
            raise FlatsimError('primitive %r: color %r is not three values in 0..1'
                               % (self.name, self.color))


class Scene:
    """Packed arrays of primitives. Read the arrays; change them through the methods.

    Arrays (one entry per slot, dead slots included): kind, x, y, yaw, cos_yaw,
    sin_yaw, half_x, half_y, radius, z_min, z_max, color (n, 3), unlit_white,
    collision, visual, alive, bound (radius of a circle around the centre that
    holds the 2D shape).
    """

    _FLOAT_FIELDS = ('x', 'y', 'yaw', 'cos_yaw', 'sin_yaw', 'half_x', 'half_y', 'radius',
                     'z_min', 'z_max', 'bound')
    _BOOL_FIELDS = ('unlit_white', 'collision', 'visual', 'alive')

    def __init__(self, prims=(), sky_color=DEFAULT_SKY_COLOR, floor_color=DEFAULT_FLOOR_COLOR):
        self.sky_color = tuple(sky_color)
        self.floor_color = tuple(floor_color)
        self.names = []
        self.kind = np.zeros(0, dtype=np.int8)
        for field_name in self._FLOAT_FIELDS:
            setattr(self, field_name, np.zeros(0))
        for field_name in self._BOOL_FIELDS:
            setattr(self, field_name, np.zeros(0, dtype=bool))
        self.color = np.zeros((0, 3))
        self.extend(prims)

    def __len__(self):
        """The number of live primitives."""
        return int(np.count_nonzero(self.alive))

    def extend(self, prims):
        """Add many primitives at once; returns their indices."""
        prims = list(prims)
        for prim in prims:
            prim.validate()
        first = len(self.names)
        if not prims:
            return []
        columns = {
            'x': [p.x for p in prims], 'y': [p.y for p in prims], 'yaw': [p.yaw for p in prims],
            'cos_yaw': [math.cos(p.yaw) for p in prims],
            'sin_yaw': [math.sin(p.yaw) for p in prims],
            'half_x': [p.half_x for p in prims], 'half_y': [p.half_y for p in prims],
            'radius': [p.radius for p in prims],
            'z_min': [p.z_min for p in prims], 'z_max': [p.z_max for p in prims],
            'bound': [math.hypot(p.half_x, p.half_y) if p.kind == 'box' else p.radius
                      for p in prims],
            'unlit_white': [p.unlit_white for p in prims],
            'collision': [p.collision for p in prims], 'visual': [p.visual for p in prims],
            'alive': [True] * len(prims),
        }
        for field_name, values in columns.items():
            old = getattr(self, field_name)
            setattr(self, field_name, np.concatenate([old, np.asarray(values, dtype=old.dtype)]))
        self.kind = np.concatenate([self.kind, [KINDS[p.kind] for p in prims]]).astype(np.int8)
        self.color = np.concatenate([self.color, [p.color for p in prims]])
        self.names.extend(p.name for p in prims)
        return list(range(first, first + len(prims)))

    def add(self, prim):
        """Add one primitive; returns its index."""
        return self.extend([prim])[0]

    def remove(self, index):
        self._check(index)
        self.alive[index] = False

    def set_pose(self, index, x, y, yaw):
        """Move a primitive; cheap enough to call for every dynamic one every frame."""
        self._check(index)
        self.x[index] = x
        self.y[index] = y
        self.yaw[index] = yaw
        self.cos_yaw[index] = math.cos(yaw)
        self.sin_yaw[index] = math.sin(yaw)

    def set_height(self, index, z_min, z_max):
        """Raise or lower a primitive: its new height span (a sphere's centre -/+ radius)."""
        self._check(index)
        self.z_min[index] = z_min
        self.z_max[index] = z_max

    def replace(self, index, prim):
        """Put prim in the slot at index (a static model moved by hand), keeping the index."""
        self._check(index)
        prim.validate()
        for field_name, value in (('x', prim.x), ('y', prim.y), ('yaw', prim.yaw),
                                  ('cos_yaw', math.cos(prim.yaw)), ('sin_yaw', math.sin(prim.yaw)),
                                  ('half_x', prim.half_x), ('half_y', prim.half_y),
                                  ('radius', prim.radius), ('z_min', prim.z_min),
                                  ('z_max', prim.z_max), ('collision', prim.collision),
                                  ('visual', prim.visual)):
            getattr(self, field_name)[index] = value
        self.bound[index] = math.hypot(prim.half_x, prim.half_y) if prim.kind == 'box' else prim.radius
        self.kind[index] = KINDS[prim.kind]
        if tuple(self.color[index]) != tuple(prim.color) or self.unlit_white[index] != prim.unlit_white:
            # New arrays: the camera keeps its shades for as long as the colour array is the same.
            self.color = self.color.copy()
            self.unlit_white = self.unlit_white.copy()
            self.color[index] = prim.color
            self.unlit_white[index] = prim.unlit_white
        self.names[index] = prim.name

    def set_poses(self, indices, x, y, yaw):
        """Move many primitives at once (arrays of one length); for the shapes of a body."""
        indices = np.asarray(indices, dtype=np.intp)
        if indices.size and (indices.min() < 0 or indices.max() >= len(self.names)
                             or not self.alive[indices].all()):
            raise FlatsimError('no primitive with one of the indices %r in the scene'
                               % (indices.tolist(),))
        yaw = np.asarray(yaw, dtype=float)
        self.x[indices] = x
        self.y[indices] = y
        self.yaw[indices] = yaw
        self.cos_yaw[indices] = np.cos(yaw)
        self.sin_yaw[indices] = np.sin(yaw)

    def prim(self, index):
        """The primitive at index as a Prim (a copy)."""
        self._check(index)
        kind = {v: k for k, v in KINDS.items()}[int(self.kind[index])]
        return Prim(self.names[index], kind, float(self.x[index]), float(self.y[index]),
                    float(self.yaw[index]), float(self.half_x[index]),
                    float(self.half_y[index]), float(self.radius[index]),
                    float(self.z_min[index]), float(self.z_max[index]),
                    tuple(float(c) for c in self.color[index]),
                    bool(self.unlit_white[index]), bool(self.collision[index]),
                    bool(self.visual[index]))

    def select(self, collision=None, visual=None, height=None, near=None, exclude=None):
        """Indices of live primitives that pass every filter given.

        collision/visual: required flag value. height: only those whose
        z_min..z_max contains it. near: (x, y, distance), only those whose
        bounding circle comes within distance of (x, y). exclude: indices (or a
        boolean mask) to leave out, such as a robot's own shapes.
        """
        mask = self.alive.copy()
        if collision is not None:
            mask &= self.collision == collision
        if visual is not None:
            mask &= self.visual == visual
        if height is not None:
            mask &= (self.z_min <= height) & (height <= self.z_max)
        if near is not None:
            near_x, near_y, distance = near
            reach = distance + self.bound
            mask &= (self.x - near_x) ** 2 + (self.y - near_y) ** 2 <= reach * reach
        if exclude is not None:
            excluded = np.asarray(exclude)
            if excluded.dtype == bool:
                mask[:excluded.size] &= ~excluded
            else:
                mask[excluded.astype(int)] = False
        return np.flatnonzero(mask)

    def _check(self, index):
        if not 0 <= index < len(self.names) or not self.alive[index]:
            raise FlatsimError('no primitive with index %r in the scene' % (index,))
