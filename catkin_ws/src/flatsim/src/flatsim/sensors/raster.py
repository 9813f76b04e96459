"""A pinhole camera at any orientation: the 2.5D primitives rasterised face by face.

A camera that is pitched or rolled no longer sees a whole column of the image
along one 2D ray, so the column raycast of flatsim.sensors.camera does not
apply. Here each primitive becomes what it is in 3D: a box is six faces, a
cylinder a prism of CYLINDER_SIDES faces with two caps, a sphere a sphere.
Faces turned towards the camera are clipped at the near plane, projected and
filled row by row; the inverse depth along the optical axis is affine in the
pixel coordinates for a plane, so the depth test costs two multiply-adds per
pixel. Spheres are intersected pixel by pixel inside their projected bounds.

Before any primitive, every pixel gets the floor (its ray points down and the
camera is above the floor) or the sky: the horizon is a straight line in the
image. Geometry below the floor is cut off at the floor.

Shading matches the level camera: ambient plus diffuse under Gazebo's default
sun with the same distance falloff, quantised into the same palette, with the
full 3D normal (a level camera sees only side faces, whose normals are
horizontal, so both agree there; a top face here gets the light from above).
"""
import math

import numpy as np

from flatsim.pose import rpy_to_matrix
from flatsim.sensors.raycast import jit
from flatsim.world.scene import BOX, SPHERE

CYLINDER_SIDES = 32
# A polygon has at most this many vertices after clipping (a cylinder cap plus one).
_MAX_VERTICES = CYLINDER_SIDES + 8

AMBIENT = 0.4
DIFFUSE = 0.8
FALLOFF_PER_METRE = 0.02
MAX_SHADE = AMBIENT + DIFFUSE
# Gazebo's default sun shines along (-0.5, 0.1, -0.9).
TO_LIGHT = np.array([0.5, -0.1, 0.9]) / np.linalg.norm([0.5, -0.1, 0.9])


def camera_axes(roll, pitch, yaw):
    """World directions of the camera's forward (+x), left (+y) and up (+z) axes: the
    columns of its rotation."""
    forward, left, up = np.ascontiguousarray(rpy_to_matrix(roll, pitch, yaw).T)
    return forward, left, up


def in_frustum(scene, prims, eye, axes, focal, centre_u, centre_v, near, far):
    """The primitives whose bounding sphere reaches into the view frustum."""
    forward, left, up = axes
    mid_z = 0.5 * (scene.z_min[prims] + scene.z_max[prims])
    half_h = 0.5 * (scene.z_max[prims] - scene.z_min[prims])
    reach = np.sqrt(scene.bound[prims] ** 2 + half_h ** 2)
    rel = np.stack([scene.x[prims] - eye[0], scene.y[prims] - eye[1], mid_z - eye[2]])
    depth = forward @ rel
    across = left @ rel
    above = up @ rel
    keep = (depth + reach >= near) & (depth - reach <= far)
    # Each side plane of the frustum passes through the eye: offset <= tan * depth inside.
    for offset, half_extent in ((across, centre_u + 0.5), (-across, centre_u + 0.5),
                                (above, centre_v + 0.5), (-above, centre_v + 0.5)):
        tan = half_extent / focal
        keep &= (offset - tan * depth) / math.sqrt(1.0 + tan * tan) <= reach
    return prims[keep]


@jit
def _shade_scale(normal_x, normal_y, normal_z):
    """Ambient plus diffuse of a surface with this world normal, before distance falloff."""
    lambert = max(normal_x * TO_LIGHT[0] + normal_y * TO_LIGHT[1] + normal_z * TO_LIGHT[2], 0.0)
    return AMBIENT + DIFFUSE * lambert


@jit
def _level(shade, inverse_depth, levels):
    """Palette level of a surface of this shade seen at depth 1 / inverse_depth."""
    value = shade * inverse_depth / (inverse_depth + FALLOFF_PER_METRE) * (levels - 1) / MAX_SHADE
    level = int(value + 0.5)
    return min(max(level, 0), levels - 1)


@jit
def _background(out, depth, eye_z, forward, left, up, focal, centre_u, centre_v, sky, floor):
    """Sky and floor for every pixel, and an empty depth buffer."""
    height, width = out.shape
    above_floor = eye_z > 0.0
    for row in range(height):
        # The ray's z is base + slope * column; it points down (floor) where that is negative.
        base = focal * forward[2] + centre_u * left[2] + (centre_v - row) * up[2]
        slope = -left[2]
        for column in range(width):
            down = base + slope * column < 0.0
            out[row, column] = floor if (down and above_floor) else sky
            depth[row, column] = 0.0


@jit
def _fill_polygon(us, vs, count, inv_a, inv_b, inv_c, shade, owner, palette, inv_far,
                  out, depth):
    """Fill the pixels whose centres the projected convex polygon covers, nearer ones only.

    The inverse depth at pixel (column, row) is inv_a * column + inv_b * row + inv_c.
    """
    height, width = out.shape
    levels = palette.shape[1]
    top, bottom = 1e300, -1e300
    for i in range(count):
        top = min(top, vs[i])
        bottom = max(bottom, vs[i])
    first_row = max(int(math.ceil(top)), 0)
    last_row = min(int(math.floor(bottom)), height - 1)
    for row in range(first_row, last_row + 1):
        low, high = 1e300, -1e300
        for i in range(count):
            j = i + 1 if i + 1 < count else 0
            v0, v1 = vs[i], vs[j]
            if (v0 <= row <= v1) or (v1 <= row <= v0):
                if v0 == v1:
                    low = min(low, us[i], us[j])
                    high = max(high, us[i], us[j])
                else:
                    u = us[i] + (row - v0) * (us[j] - us[i]) / (v1 - v0)
                    low = min(low, u)
                    high = max(high, u)
        first_column = max(int(math.ceil(low)), 0)
        last_column = min(int(math.floor(high)), width - 1)
        inverse = inv_a * first_column + inv_b * row + inv_c
        for column in range(first_column, last_column + 1):
            if inverse > depth[row, column] and inverse >= inv_far:
                depth[row, column] = inverse
                out[row, column] = palette[owner, _level(shade, inverse, levels)]
            inverse += inv_a


@jit
def _draw_face(corners, count, normal_x, normal_y, normal_z, eye, forward, left, up, focal,
               centre_u, centre_v, near, inv_far, shade, owner, palette, out, depth,
               cam_x, cam_y, cam_z, us, vs):
    """Clip a planar convex face (world corners) at the near plane, project it and fill it."""
    # Faces seen from behind are hidden by the front faces of the same convex solid.
    to_face = ((corners[0, 0] - eye[0]) * normal_x + (corners[0, 1] - eye[1]) * normal_y
               + (corners[0, 2] - eye[2]) * normal_z)
    if to_face >= 0.0:
        return
    for i in range(count):
        rel_x = corners[i, 0] - eye[0]
        rel_y = corners[i, 1] - eye[1]
        rel_z = corners[i, 2] - eye[2]
        cam_x[i] = rel_x * forward[0] + rel_y * forward[1] + rel_z * forward[2]
        cam_y[i] = rel_x * left[0] + rel_y * left[1] + rel_z * left[2]
        cam_z[i] = rel_x * up[0] + rel_y * up[1] + rel_z * up[2]
    kept = 0
    for i in range(count):
        j = i + 1 if i + 1 < count else 0
        inside_i = cam_x[i] >= near
        inside_j = cam_x[j] >= near
        if inside_i:
            us[kept] = centre_u - focal * cam_y[i] / cam_x[i]
            vs[kept] = centre_v - focal * cam_z[i] / cam_x[i]
            kept += 1
        if inside_i != inside_j:
            t = (near - cam_x[i]) / (cam_x[j] - cam_x[i])
            y = cam_y[i] + t * (cam_y[j] - cam_y[i])
            z = cam_z[i] + t * (cam_z[j] - cam_z[i])
            us[kept] = centre_u - focal * y / near
            vs[kept] = centre_v - focal * z / near
            kept += 1
    if kept < 3:
        return
    # The face's plane n . p = d in the camera frame gives 1/depth affine in (u, v).
    n_forward = normal_x * forward[0] + normal_y * forward[1] + normal_z * forward[2]
    n_left = normal_x * left[0] + normal_y * left[1] + normal_z * left[2]
    n_up = normal_x * up[0] + normal_y * up[1] + normal_z * up[2]
    plane = n_forward * cam_x[0] + n_left * cam_y[0] + n_up * cam_z[0]
    inv_a = -n_left / (focal * plane)
    inv_b = -n_up / (focal * plane)
    inv_c = (n_forward + n_left * centre_u / focal + n_up * centre_v / focal) / plane
    _fill_polygon(us, vs, kept, inv_a, inv_b, inv_c, shade, owner, palette, inv_far, out, depth)


@jit
def _draw_sphere(centre_x, centre_y, centre_z, radius, owner, eye, forward, left, up, focal,
                 centre_u, centre_v, near, far, palette, out, depth):
    """Intersect the pixel rays inside the sphere's projected bounds with the sphere."""
    height, width = out.shape
    levels = palette.shape[1]
    rel_x, rel_y, rel_z = centre_x - eye[0], centre_y - eye[1], centre_z - eye[2]
    c_forward = rel_x * forward[0] + rel_y * forward[1] + rel_z * forward[2]
    c_left = rel_x * left[0] + rel_y * left[1] + rel_z * left[2]
    c_up = rel_x * up[0] + rel_y * up[1] + rel_z * up[2]
    if c_forward + radius < near or c_forward - radius > far:
        return
    first_column, last_column, first_row, last_row = 0, width - 1, 0, height - 1
    nearest = c_forward - radius
    if nearest > near:
        # The sphere's bounding box projects within these bounds: each extreme is
        # reached at its nearest or its farthest depth.
        low_u, high_u, low_v, high_v = 1e300, -1e300, 1e300, -1e300
        for box_depth in (nearest, c_forward + radius):
            for sign in (-1.0, 1.0):
                u = centre_u - focal * (c_left + sign * radius) / box_depth
                v = centre_v - focal * (c_up + sign * radius) / box_depth
                low_u, high_u = min(low_u, u), max(high_u, u)
                low_v, high_v = min(low_v, v), max(high_v, v)
        first_column = max(int(math.floor(low_u)), 0)
        last_column = min(int(math.ceil(high_u)), width - 1)
        first_row = max(int(math.floor(low_v)), 0)
        last_row = min(int(math.ceil(high_v)), height - 1)
    centre_sq = c_forward * c_forward + c_left * c_left + c_up * c_up - radius * radius
    for row in range(first_row, last_row + 1):
        ray_up = (centre_v - row) / focal
        for column in range(first_column, last_column + 1):
            ray_left = (centre_u - column) / focal
            # The ray is s * (1, ray_left, ray_up); s is the depth along the optical axis.
            ray_sq = 1.0 + ray_left * ray_left + ray_up * ray_up
            along = c_forward + ray_left * c_left + ray_up * c_up
            disc = along * along - ray_sq * centre_sq
            if disc < 0.0:
                continue
            s = (along - math.sqrt(disc)) / ray_sq
            if s < near or s > far:
                continue
            inverse = 1.0 / s
            if inverse <= depth[row, column]:
                continue
            hit_z = eye[2] + s * (forward[2] + ray_left * left[2] + ray_up * up[2])
            if hit_z < 0.0 and eye[2] > 0.0:
                continue
            depth[row, column] = inverse
            n_forward = (s - c_forward) / radius
            n_left = (s * ray_left - c_left) / radius
            n_up = (s * ray_up - c_up) / radius
            normal_x = n_forward * forward[0] + n_left * left[0] + n_up * up[0]
            normal_y = n_forward * forward[1] + n_left * left[1] + n_up * up[1]
            normal_z = n_forward * forward[2] + n_left * left[2] + n_up * up[2]
            shade = _shade_scale(normal_x, normal_y, normal_z)
            out[row, column] = palette[owner, _level(shade, inverse, levels)]


@jit
def render_tilted(eye, forward, left, up, focal, centre_u, centre_v, near, far, scene_index,
                  kind, prim_x, prim_y, prim_cos, prim_sin, half_x, half_y, radius, z_min, z_max,
                  palette, sky, floor, out, depth):
    """Render the listed primitives into out, (h, w) packed colours, row-major."""
    _background(out, depth, eye[2], forward, left, up, focal, centre_u, centre_v, sky, floor)
    inv_far = 1.0 / far
    corners = np.empty((_MAX_VERTICES, 3))
    cam_x = np.empty(_MAX_VERTICES)
    cam_y = np.empty(_MAX_VERTICES)
    cam_z = np.empty(_MAX_VERTICES)
    us = np.empty(_MAX_VERTICES)
    vs = np.empty(_MAX_VERTICES)
    ring_x = np.empty(CYLINDER_SIDES)
    ring_y = np.empty(CYLINDER_SIDES)
    for prim in range(kind.size):
        owner = scene_index[prim]
        low = z_min[prim]
        if eye[2] > 0.0:
            low = max(low, 0.0)
        high = z_max[prim]
        if kind[prim] == SPHERE:
            _draw_sphere(prim_x[prim], prim_y[prim], 0.5 * (z_min[prim] + z_max[prim]),
                         radius[prim], owner, eye, forward, left, up, focal, centre_u, centre_v,
                         near, far, palette, out, depth)
            continue
        if not low < high:
            continue
        if kind[prim] == BOX:
            sides = 4
            c, s = prim_cos[prim], prim_sin[prim]
            hx, hy = half_x[prim], half_y[prim]
            for k in range(4):
                ax = hx if k == 0 or k == 3 else -hx
                ay = hy if k < 2 else -hy
                ring_x[k] = prim_x[prim] + c * ax - s * ay
                ring_y[k] = prim_y[prim] + s * ax + c * ay
        else:
            sides = CYLINDER_SIDES
            for k in range(sides):
                angle = 2.0 * math.pi * k / sides
                ring_x[k] = prim_x[prim] + radius[prim] * math.cos(angle)
                ring_y[k] = prim_y[prim] + radius[prim] * math.sin(angle)
        # The ring runs counter-clockwise, so each side's outward normal is its edge turned right.
        for k in range(sides):
            m = k + 1 if k + 1 < sides else 0
            edge_x, edge_y = ring_x[m] - ring_x[k], ring_y[m] - ring_y[k]
            length = math.sqrt(edge_x * edge_x + edge_y * edge_y)
            normal_x, normal_y = edge_y / length, -edge_x / length
            corners[0, 0], corners[0, 1], corners[0, 2] = ring_x[k], ring_y[k], low
            corners[1, 0], corners[1, 1], corners[1, 2] = ring_x[m], ring_y[m], low
            corners[2, 0], corners[2, 1], corners[2, 2] = ring_x[m], ring_y[m], high
            corners[3, 0], corners[3, 1], corners[3, 2] = ring_x[k], ring_y[k], high
            _draw_face(corners, 4, normal_x, normal_y, 0.0, eye, forward, left, up, focal,
                       centre_u, centre_v, near, inv_far, _shade_scale(normal_x, normal_y, 0.0),
                       owner, palette, out, depth, cam_x, cam_y, cam_z, us, vs)
        for k in range(sides):
            corners[k, 0], corners[k, 1], corners[k, 2] = ring_x[k], ring_y[k], high
        _draw_face(corners, sides, 0.0, 0.0, 1.0, eye, forward, left, up, focal, centre_u,
                   centre_v, near, inv_far, _shade_scale(0.0, 0.0, 1.0), owner, palette, out,
                   depth, cam_x, cam_y, cam_z, us, vs)
        for k in range(sides):
            corners[k, 0], corners[k, 1], corners[k, 2] = (ring_x[sides - 1 - k],
                                                           ring_y[sides - 1 - k], low)
        _draw_face(corners, sides, 0.0, 0.0, -1.0, eye, forward, left, up, focal, centre_u,
                   centre_v, near, inv_far, _shade_scale(0.0, 0.0, -1.0), owner, palette, out,
                   depth, cam_x, cam_y, cam_z, us, vs)
