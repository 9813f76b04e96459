"""2D rays against a Scene's boxes and circles, compiled with numba.

A ray is an origin shared by all rays plus a unit direction (cos, sin) per ray.
A ray that starts inside a primitive does not hit it: sensors sit inside their
own housing, and a robot's body must not blind its own sensors.

The per-ray loops are compiled (and cached on disk) because a sensor casts
hundreds of rays against tens of primitives many times per simulated second;
as numpy expressions they spend most of their time building (rays, prims)
intermediates.
"""
import math

import numba
import numpy as np

from flatsim.world.scene import BOX

# Compiled code is cached beside this module, so only the first run on a machine compiles.
jit = numba.njit(cache=True, nogil=True, error_model='numpy')


@jit
def ray_box(origin_x, origin_y, cos_ray, sin_ray, centre_x, centre_y, cos_yaw, sin_yaw,
            half_x, half_y):
    """Slab test in the box's own frame: (entry, exit) distances; entry is inf for a miss."""
    rel_x = origin_x - centre_x
    rel_y = origin_y - centre_y
    local_x = rel_x * cos_yaw + rel_y * sin_yaw
    local_y = rel_y * cos_yaw - rel_x * sin_yaw
    dir_x = cos_ray * cos_yaw + sin_ray * sin_yaw
    dir_y = sin_ray * cos_yaw - cos_ray * sin_yaw
    # An exactly axis-parallel ray through the centre would make 0 * inf = nan below.
    if dir_x == 0.0:
        dir_x = 1e-300
    if dir_y == 0.0:
        dir_y = 1e-300
    inv_x = 1.0 / dir_x
    inv_y = 1.0 / dir_y
    mid_x = local_x * inv_x
    reach_x = abs(inv_x) * half_x
    mid_y = local_y * inv_y
    reach_y = abs(inv_y) * half_y
    near = max(-mid_x - reach_x, -mid_y - reach_y)
    far = min(reach_x - mid_x, reach_y - mid_y)
    if near <= far and near >= 0.0:
        return near, far
    return math.inf, far


@jit
def ray_circle(origin_x, origin_y, cos_ray, sin_ray, centre_x, centre_y, radius):
    """(entry, exit) distances of a ray through a circle; entry is inf for a miss."""
    rel_x = centre_x - origin_x
    rel_y = centre_y - origin_y
    outside = rel_x * rel_x + rel_y * rel_y - radius * radius
    along = cos_ray * rel_x + sin_ray * rel_y
    discriminant = along * along - outside
    if discriminant < 0.0 or outside < 0.0:
        return math.inf, math.inf
    half_chord = math.sqrt(discriminant)
    near = along - half_chord
    if near < 0.0:
        return math.inf, along + half_chord
    return near, along + half_chord


@jit
def ray_prim(origin_x, origin_y, cos_ray, sin_ray, kind, x, y, cos_yaw, sin_yaw, half_x,
             half_y, radius):
    """(entry, exit) of a ray through one primitive; spheres count as circles."""
    if kind == BOX:
        return ray_box(origin_x, origin_y, cos_ray, sin_ray, x, y, cos_yaw, sin_yaw,
                       half_x, half_y)
    return ray_circle(origin_x, origin_y, cos_ray, sin_ray, x, y, radius)


@jit
def surface_normal(kind, x, y, cos_yaw, sin_yaw, half_x, half_y, radius, hit_x, hit_y):
    """Outward unit normal (world frame) at a point taken to lie on a primitive's 2D outline.

    A box point gets the normal of the face it is nearest to relative to the box's size.
    """
    rel_x = hit_x - x
    rel_y = hit_y - y
    if kind != BOX:
        return rel_x / radius, rel_y / radius
    local_x = rel_x * cos_yaw + rel_y * sin_yaw
    local_y = rel_y * cos_yaw - rel_x * sin_yaw
    if abs(local_x) * half_y >= abs(local_y) * half_x:
        local_nx, local_ny = np.sign(local_x), 0.0
    else:
        local_nx, local_ny = 0.0, np.sign(local_y)
    return local_nx * cos_yaw - local_ny * sin_yaw, local_nx * sin_yaw + local_ny * cos_yaw


@jit
def _nearest(origin_x, origin_y, cos_rays, sin_rays, kind, x, y, cos_yaw, sin_yaw, half_x,
             half_y, radius, distance, column):
    for ray in range(cos_rays.size):
        best, best_column = math.inf, -1
        for prim in range(kind.size):
            entry, _ = ray_prim(origin_x, origin_y, cos_rays[ray], sin_rays[ray], kind[prim],
                                x[prim], y[prim], cos_yaw[prim], sin_yaw[prim],
                                half_x[prim], half_y[prim], radius[prim])
            if entry < best:
                best, best_column = entry, prim
        distance[ray] = best
        column[ray] = best_column


def directions(angles):
    """Unit ray directions (cos, sin) for world-frame angles."""
    angles = np.asarray(angles, dtype=float)
    return np.cos(angles), np.sin(angles)


def prim_arrays(scene, prims, radius=None):
    """The scene fields the compiled casts read, for the listed primitives, in order.

    radius, if given, replaces each primitive's radius (a sphere's cross-section
    at the sensor height, say).
    """
    prims = np.asarray(prims, dtype=np.intp)
    return (scene.kind[prims], scene.x[prims], scene.y[prims], scene.cos_yaw[prims],
            scene.sin_yaw[prims], scene.half_x[prims], scene.half_y[prims],
            scene.radius[prims] if radius is None else np.asarray(radius, dtype=float))


def nearest(scene, origin_x, origin_y, cos_rays, sin_rays, prims, radius=None):
    """Per ray: distance to the nearest entry (inf for none) and its scene index (-1).

    prims lists the scene indices to test; radius is as in prim_arrays.
    """
    prims = np.asarray(prims, dtype=np.intp)
    cos_rays = np.ascontiguousarray(cos_rays, dtype=float)
    sin_rays = np.ascontiguousarray(sin_rays, dtype=float)
    distance = np.empty(cos_rays.shape)
    column = np.empty(cos_rays.shape, dtype=np.intp)
    _nearest(float(origin_x), float(origin_y), cos_rays.ravel(), sin_rays.ravel(),
             *prim_arrays(scene, prims, radius), distance.ravel(), column.ravel())
    index = np.where(column >= 0, prims[np.maximum(column, 0)] if prims.size else -1, -1)
    return distance, index
