"""2D rays against a Scene's boxes and circles, all rays and primitives at once.

A ray is an origin shared by all rays plus a unit direction (cos, sin) per ray.
Results are (rays, prims) arrays of distances along the ray. A ray that starts
inside a primitive does not hit it: sensors sit inside their own housing, and
a robot's body must not blind its own sensors.
"""
from dataclasses import dataclass

import numpy as np

from flatsim.scene import BOX


@dataclass
class RayHits:
    """Where each ray meets each primitive.

    prims: (P,) scene indices, the columns of every other array.
    entry: (R, P) distance to where the ray enters the primitive; inf for a miss.
    exit: (R, P) distance to where it leaves (meaningful where entry is finite).
    """
    prims: np.ndarray
    entry: np.ndarray
    exit: np.ndarray


def directions(angles):
    """Unit ray directions (cos, sin) for world-frame angles."""
    angles = np.asarray(angles, dtype=float)
    return np.cos(angles), np.sin(angles)


def box_hits(origin_x, origin_y, cos_rays, sin_rays, centre_x, centre_y, cos_yaw, sin_yaw,
             half_x, half_y):
    """Slab test in each box's own frame: (entry, exit) with rays along axis 0."""
    rel_x = origin_x - centre_x
    rel_y = origin_y - centre_y
    local_x = rel_x * cos_yaw + rel_y * sin_yaw
    local_y = rel_y * cos_yaw - rel_x * sin_yaw
    cos_r = cos_rays[:, None]
    sin_r = sin_rays[:, None]
    dir_x = cos_r * cos_yaw + sin_r * sin_yaw
    dir_y = sin_r * cos_yaw - cos_r * sin_yaw
    # An exactly axis-parallel ray through the centre would make 0 * inf = nan below.
    dir_x[dir_x == 0.0] = 1e-300
    dir_y[dir_y == 0.0] = 1e-300
    with np.errstate(divide='ignore', over='ignore', invalid='ignore'):
        inv_x = 1.0 / dir_x
        inv_y = 1.0 / dir_y
        mid_x = local_x * inv_x
        reach_x = np.abs(inv_x) * half_x
        mid_y = local_y * inv_y
        reach_y = np.abs(inv_y) * half_y
        near = np.maximum(-mid_x - reach_x, -mid_y - reach_y)
        far = np.minimum(reach_x - mid_x, reach_y - mid_y)
    hit = (near <= far) & (near >= 0.0)
    return np.where(hit, near, np.inf), far


def circle_hits(origin_x, origin_y, cos_rays, sin_rays, centre_x, centre_y, radius):
    """Rays against circles: (entry, exit) with rays along axis 0, circles along axis 1."""
    rel_x = centre_x - origin_x
    rel_y = centre_y - origin_y
    outside = rel_x * rel_x + rel_y * rel_y - radius * radius
    along = cos_rays[:, None] * rel_x + sin_rays[:, None] * rel_y
    discriminant = along * along - outside
    with np.errstate(invalid='ignore'):
        half_chord = np.sqrt(discriminant)
    near = along - half_chord
    far = along + half_chord
    hit = (discriminant >= 0.0) & (near >= 0.0) & (outside >= 0.0)
    return np.where(hit, near, np.inf), far


def cast(scene, origin_x, origin_y, cos_rays, sin_rays, prims, radius=None):
    """Rays from one origin against the scene primitives listed in prims.

    Spheres count as circles; radius, if given, is a (len(prims),) array that
    replaces each circle's radius (a sphere's cross-section at the sensor
    height, say). Box columns come first in the result, then circles.
    """
    prims = np.asarray(prims, dtype=int)
    cos_rays = np.asarray(cos_rays, dtype=float)
    sin_rays = np.asarray(sin_rays, dtype=float)
    is_box = scene.kind[prims] == BOX
    boxes = prims[is_box]
    circles = prims[~is_box]
    circle_radius = scene.radius[circles] if radius is None else np.asarray(radius)[~is_box]
    parts = []
    if boxes.size:
        parts.append(box_hits(origin_x, origin_y, cos_rays, sin_rays, scene.x[boxes],
                              scene.y[boxes], scene.cos_yaw[boxes], scene.sin_yaw[boxes],
                              scene.half_x[boxes], scene.half_y[boxes]))
    if circles.size:
        parts.append(circle_hits(origin_x, origin_y, cos_rays, sin_rays, scene.x[circles],
                                 scene.y[circles], circle_radius))
    order = np.concatenate([boxes, circles])
    if not parts:
        empty = np.empty((cos_rays.size, 0))
        return RayHits(order, empty, empty)
    if len(parts) == 1:
        return RayHits(order, *parts[0])
    return RayHits(order, *(np.concatenate([p[i] for p in parts], axis=1) for i in range(2)))


def surface_normals(scene, prims, hit_x, hit_y):
    """Outward unit normals (world frame) at points on the primitives' 2D outlines.

    prims, hit_x and hit_y broadcast together; each point is taken to lie on
    its primitive's outline. A box point gets the normal of the face it is
    nearest to relative to the box's size.
    """
    rel_x = hit_x - scene.x[prims]
    rel_y = hit_y - scene.y[prims]
    cos_yaw = scene.cos_yaw[prims]
    sin_yaw = scene.sin_yaw[prims]
    local_x = rel_x * cos_yaw + rel_y * sin_yaw
    local_y = rel_y * cos_yaw - rel_x * sin_yaw
    on_x_face = np.abs(local_x) * scene.half_y[prims] >= np.abs(local_y) * scene.half_x[prims]
    local_nx = np.where(on_x_face, np.sign(local_x), 0.0)
    local_ny = np.where(on_x_face, 0.0, np.sign(local_y))
    box_nx = local_nx * cos_yaw - local_ny * sin_yaw
    box_ny = local_nx * sin_yaw + local_ny * cos_yaw
    is_box = scene.kind[prims] == BOX
    with np.errstate(divide='ignore', invalid='ignore'):
        radius = np.where(is_box, 1.0, scene.radius[prims])
        return (np.where(is_box, box_nx, rel_x / radius),
                np.where(is_box, box_ny, rel_y / radius))


def nearest(scene, origin_x, origin_y, cos_rays, sin_rays, prims, radius=None):
    """Per ray: distance to the nearest entry (inf for none) and its scene index (-1)."""
    hits = cast(scene, origin_x, origin_y, cos_rays, sin_rays, prims, radius)
    if hits.prims.size == 0:
        return np.full(np.shape(cos_rays), np.inf), np.full(np.shape(cos_rays), -1)
    column = np.argmin(hits.entry, axis=1)
    distance = np.take_along_axis(hits.entry, column[:, None], axis=1)[:, 0]
    index = np.where(np.isfinite(distance), hits.prims[column], -1)
    return distance, index
