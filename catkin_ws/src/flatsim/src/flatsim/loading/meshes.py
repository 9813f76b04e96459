"""Mesh files (STL, OBJ, Collada) as flatsim draws and collides them: a few upright boxes.

flatsim's scene holds upright boxes, cylinders and spheres (flatsim.world.scene),
so a mesh becomes the boxes that cover it, layer by layer:

  - the file is read with trimesh (pycollada for Collada), every part of it
    with its own transform, a Collada file's <unit> and the <scale> applied,
    then turned into the frame the caller gives (the model's or the link's),
    so "up" is the world's up;
  - its height is cut into layers: at the heights its vertices lie at when
    there are at most SLABS + 1 of them (a table: the floor, the underside and
    the top of its top), else into SLABS equal layers. In each layer, the
    triangles that reach into it are grouped into pieces that share vertices
    there, and each piece becomes the smallest rectangle (any yaw) around its
    points, with the piece's height within the layer;
  - a rectangle that repeats in the layer above grows upwards instead of
    starting a new box.

So a table mesh becomes its legs (or pedestal) and its top, and a robot
reaching the table between its legs meets the legs only, as in Gazebo; a box
mesh becomes exactly that box. Each box keeps its height span, which the
camera draws, and a box that cuts the working height collides, as any box
does (flatsim.world.model_geometry). A mesh of more pieces than MAX_BOXES is covered by
fewer, larger boxes: first one per piece over the whole height, then one.

URIs resolve as Gazebo and gazebo_ros resolve them: `model://NAME/...` in the
folder NAME on Gazebo's model path (flatsim.loading.model_path), then in the
ROS package NAME (gazebo_ros puts packages on the model path when they export
it); `package://PKG/...` in the ROS package PKG, then on the model path;
`file://PATH` and plain paths as files, relative ones beside the file that
names them. What cannot be found raises MeshNotFound, what cannot be read
MeshError, each with the reason. No ROS here (rospkg only finds packages).
"""
import functools
import math
import os
import re
import threading
from dataclasses import dataclass
from typing import Optional, Tuple

import cv2
import numpy as np

from flatsim.errors import FlatsimError
from flatsim.pose import Pose

MESH_TYPES = {'.stl': 'stl', '.obj': 'obj', '.dae': 'dae'}
# Layers a mesh's height is cut into: enough to part a table's top from its legs and to
# follow a chair or a person, few enough that the camera's per-box cost stays small.
SLABS = 8
# Boxes per mesh beyond which it is covered more coarsely.
MAX_BOXES = 48
# The thinnest box made (m): a flat mesh (a sign, a floor tile) still has a side to see.
MIN_THICKNESS = 1e-3
# Files larger than this are not read: a mesh of hundreds of megabytes would hold the
# simulator up for minutes, and no course model comes near it.
MAX_MESH_BYTES = 256 << 20
# Vertices closer than this (m, before scaling) are one vertex: STL repeats each vertex
# per triangle, and pieces are found through shared vertices.
WELD = 1e-7
_UNIT = re.compile(rb'<unit\b[^>]*\bmeter\s*=\s*["\']([^"\']*)["\']')


class MeshError(FlatsimError):
    """A mesh that cannot be used; the message is the reason."""


class MeshNotFound(MeshError):
    """A mesh whose file is not where its URI points."""


@dataclass(frozen=True)
class MeshData:
    vertices: np.ndarray          # (n, 3) float64, welded
    faces: np.ndarray             # (m, 3) int64
    color: Optional[Tuple[float, float, float, float]]  # the file's own main colour, if any


@dataclass(frozen=True)
class MeshBox:
    """One box covering part of a mesh, in the caller's frame: upright, turned by yaw."""
    pose: Pose
    size: Tuple[float, float, float]


# -- finding the file --------------------------------------------------------------

_packages_lock = threading.Lock()
_packages = {}


def package_path(name):
    """The folder of ROS package name on ROS_PACKAGE_PATH, or None."""
    key = os.environ.get('ROS_PACKAGE_PATH', '')
    with _packages_lock:
        if key not in _packages:
            try:
                import rospkg
                # One crawl of the package path per path, however many meshes ask.
                _packages[key] = rospkg.RosPack()
            except Exception:  # noqa: BLE001 - rospkg raises its own errors, OS errors alike
                _packages[key] = None
        packages = _packages[key]
        try:
            return packages.get_path(name) if packages is not None else None
        except Exception:  # noqa: BLE001 - rospkg's ResourceNotFound for a package that is not there
            return None


def _split_authority(rest):
    name, _, inner = rest.partition('/')
    return name, inner


def mesh_candidates(uri, base_dir=None, model_paths=None):
    """The files a mesh URI may name, in the order they are tried."""
    from flatsim.loading.model_path import model_path
    text = (uri or '').strip()
    folders = list(model_path() if model_paths is None else model_paths)
    if text.startswith('model://') or text.startswith('package://'):
        name, inner = _split_authority(text.split('://', 1)[1])
        if not name or not inner:
            return []
        in_models = [os.path.join(folder, name, inner) for folder in folders]
        package = package_path(name)
        in_package = [os.path.join(package, inner)] if package else []
        return in_models + in_package if text.startswith('model://') else in_package + in_models
    if text.startswith('file://'):
        text = text[len('file://'):]
    if not text:
        return []
    if os.path.isabs(text):
        return [text]
    return [os.path.join(base_dir, text)] if base_dir else [os.path.abspath(text)]


def find_mesh(uri, base_dir=None, model_paths=None):
    """The file a mesh URI names; MeshNotFound when none is there."""
    if not (uri or '').strip():
        raise MeshNotFound('names no file')
    for candidate in mesh_candidates(uri, base_dir, model_paths):
        if os.path.isfile(candidate):
            return os.path.normpath(candidate)
    raise MeshNotFound('file not found')


# -- reading it -------------------------------------------------------------------

_read_lock = threading.Lock()
_read_cache = {}
_box_cache = {}


def _file_key(path):
    try:
        stat = os.stat(path)
    except OSError as error:
        raise MeshNotFound('cannot be opened (%s)' % (error.strerror or error)) from None
    return (path, stat.st_mtime_ns, stat.st_size)


def read_mesh(path) -> MeshData:
    """The triangles of a mesh file (kept while the file stays as it is); MeshError if unusable."""
    key = _file_key(path)
    with _read_lock:
        found = _read_cache.get(key)
    if found is None:
        found = _read_file(path, key[2])
        with _read_lock:
            _read_cache[key] = found
    return found


def _read_file(path, size):
    kind = MESH_TYPES.get(os.path.splitext(path)[1].lower())
    if kind is None:
        raise MeshError('is not an STL, OBJ or Collada (.dae) file')
    if size > MAX_MESH_BYTES:
        raise MeshError('is %d MB, more than the %d MB flatsim reads' % (size >> 20, MAX_MESH_BYTES >> 20))
    unit = 1.0
    if kind == 'dae':
        try:
            with open(path, 'rb') as stream:
                text = stream.read()
        except OSError as error:
            raise MeshError('cannot be read (%s)' % (error.strerror or error)) from None
        # The XML parser would expand entities without bound (the grader runs as root).
        if b'<!ENTITY' in text:
            raise MeshError('declares XML entities, which flatsim does not expand')
        # Gazebo scales a Collada scene by its <unit meter>, which trimesh leaves to the caller
        # (a SketchUp export in inches says meter="0.0254").
        found = _UNIT.search(text)
        if found:
            try:
                unit = float(found.group(1))
            except ValueError:
                unit = 1.0
            if not (math.isfinite(unit) and unit > 0):
                raise MeshError('gives a unit of %r m, not a positive number' % found.group(1).decode())
    try:
        import trimesh
        loaded = trimesh.load(path, file_type=kind, force='mesh', process=False)
    except Exception as error:  # noqa: BLE001 - each format's reader raises its own errors on a broken file
        raise MeshError('cannot be read as %s (%s)' % (kind.upper(), str(error) or type(error).__name__)) \
            from None
    vertices = np.asarray(getattr(loaded, 'vertices', ()), dtype=float).reshape(-1, 3)
    faces = np.asarray(getattr(loaded, 'faces', ()), dtype=np.int64).reshape(-1, 3)
    if not len(faces):
        raise MeshError('holds no triangles')
    if not np.all(np.isfinite(vertices)) or faces.min() < 0 or faces.max() >= len(vertices):
        raise MeshError('holds vertices that are not finite numbers or faces that name no vertex')
    vertices, faces = _weld(vertices * unit, faces)
    return MeshData(vertices, faces, _main_color(loaded))


def _weld(vertices, faces):
    """Vertices within WELD of each other become one, so that pieces share them."""
    keys = np.round(vertices / WELD).astype(np.int64)
    unique, inverse = np.unique(keys, axis=0, return_inverse=True)
    welded = np.zeros((len(unique), 3))
    welded[inverse.reshape(-1)] = vertices
    return welded, inverse.reshape(-1)[faces]


def _main_color(loaded):
    """The file's own colour (its material's or its faces'), RGBA in 0..1, or None."""
    try:
        visual = loaded.visual
        if visual.kind == 'texture':
            color = visual.material.main_color
        elif visual.kind in ('face', 'vertex'):
            color = visual.main_color
        else:
            return None
        rgba = tuple(float(c) / 255.0 for c in np.asarray(color).reshape(-1)[:4])
    except Exception:  # noqa: BLE001 - a material trimesh cannot make sense of: the caller's colour stands
        return None
    return rgba if len(rgba) == 4 else None


# -- covering it with boxes ---------------------------------------------------------

def mesh_boxes(path, scale=(1.0, 1.0, 1.0), frame=None):
    """The boxes covering the mesh in path, scaled, then placed by frame (a 4x4 matrix that
    takes the mesh's frame into the caller's; identity when None). Kept while the file is."""
    frame = np.eye(4) if frame is None else np.asarray(frame, dtype=float)
    scale = tuple(float(s) for s in scale)
    key = (_file_key(path), scale, frame.tobytes())
    with _read_lock:
        boxes = _box_cache.get(key)
    if boxes is None:
        mesh = read_mesh(path)
        vertices = (mesh.vertices * np.asarray(scale)) @ frame[:3, :3].T + frame[:3, 3]
        boxes = cover(vertices, mesh.faces)
        with _read_lock:
            _box_cache[key] = boxes
    return boxes


def cover(vertices, faces, slabs=SLABS, max_boxes=MAX_BOXES):
    """Upright boxes covering triangles (vertices (n, 3), faces (m, 3)) layer by layer."""
    vertices = np.asarray(vertices, dtype=float)
    faces = np.asarray(faces, dtype=np.int64)
    for layers in (slabs, 1):
        boxes = _cover(vertices, faces, layers, max_boxes)
        if boxes is not None:
            return boxes
    return (_box(vertices[:, :2], vertices[:, 2].min(), vertices[:, 2].max()),)


def _cover(vertices, faces, layers, max_boxes):
    face_z = vertices[faces, 2]
    low, high = face_z.min(axis=1), face_z.max(axis=1)
    edges = _layer_edges(vertices[faces].reshape(-1, 3)[:, 2], layers)
    extent = float(np.ptp(vertices[:, :2], axis=0).max())
    tolerance = max(1e-6, 1e-4 * extent)
    z_tolerance = 1e-6 * float(edges[-1] - edges[0])
    flat = high - low <= z_tolerance
    growing = []                  # [corners (4, 2), z_min, z_max, box]
    done = []
    for below, above in zip(edges[:-1], edges[1:]):
        # A flat face on the line between two layers belongs to the one above it (the
        # underside of a table top is part of the top, not of the legs), the very top to the last.
        flat_here = flat & (low >= below - z_tolerance) & ((low < above - z_tolerance)
                                                           | (above == edges[-1]))
        chosen = np.flatnonzero(((high > below + z_tolerance) & (low < above - z_tolerance))
                                | flat_here)
        if not chosen.size:
            continue
        pieces = _pieces(faces[chosen], len(vertices))
        order = np.argsort(pieces, kind='stable')
        starts = np.flatnonzero(np.r_[True, np.diff(pieces[order]) != 0])
        if len(starts) + len(done) > max_boxes:
            return None
        still = []
        for group in np.split(chosen[order], starts[1:]):
            points = vertices[faces[group]].reshape(-1, 3)
            z_min = max(below, float(low[group].min()))
            z_max = min(above, float(high[group].max()))
            corners, rect = _rectangle(points[:, :2])
            match = next((index for index, entry in enumerate(growing)
                          if _same_corners(entry[0], corners, tolerance)
                          and entry[2] >= z_min - tolerance), None)
            if match is not None:
                match = growing.pop(match)
                match[2] = max(match[2], z_max)
                still.append(match)
            else:
                still.append([corners, z_min, z_max, rect])
        done.extend(entry for entry in growing)
        growing = still
        if len(growing) + len(done) > max_boxes:
            return None
    done.extend(growing)
    return tuple(_from_rect(rect, z_min, z_max) for _, z_min, z_max, rect in done)


def _layer_edges(heights, layers):
    """Where the layers meet: at the heights the mesh's vertices lie at when there are no
    more of them than layers (a table: the floor, the underside and the top of its top),
    else at equal steps."""
    bottom, top = float(heights.min()), float(heights.max())
    if top <= bottom:
        return np.array([bottom, top])
    _, first = np.unique(np.round((heights - bottom) / (top - bottom) * 1e6), return_index=True)
    if len(first) <= layers + 1:
        return np.sort(heights[first])
    return np.linspace(bottom, top, layers + 1)


def _roots(faces, vertex_count):
    """A label per face: faces that share vertices (directly or through others) share it."""
    parent = np.arange(vertex_count)
    for face in range(faces.shape[0]):
        a = faces[face, 0]
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        for corner in range(1, 3):
            b = faces[face, corner]
            while parent[b] != b:
                parent[b] = parent[parent[b]]
                b = parent[b]
            if a != b:
                if a < b:
                    parent[b] = a
                else:
                    parent[a] = b
                    a = b
    labels = np.empty(faces.shape[0], dtype=np.int64)
    for face in range(faces.shape[0]):
        a = faces[face, 0]
        while parent[a] != a:
            a = parent[a]
        labels[face] = a
    return labels


@functools.lru_cache(maxsize=None)
def piece_finder():
    """_roots compiled by numba (cached beside this file), at its first use: a process that
    covers no mesh, as `gazebo WORLD` checking the world beside the simulator, does not pay
    for numba's import (a fifth of a second)."""
    import numba
    return numba.njit(cache=True, nogil=True)(_roots)


def _pieces(faces, vertex_count):
    return piece_finder()(np.ascontiguousarray(faces), vertex_count)


def _rectangle(points):
    """(corners (4, 2), rect) of the smallest rectangle around 2D points; rect is
    (centre x, centre y, size x, size y, yaw)."""
    centre = points.mean(axis=0)
    _, _, angle = cv2.minAreaRect(np.ascontiguousarray(points - centre, dtype=np.float32))
    # OpenCV finds the direction in float32; the extents along it are taken in float64.
    yaw = math.radians(angle)
    axes = np.array([[math.cos(yaw), math.sin(yaw)], [-math.sin(yaw), math.cos(yaw)]])
    along = (points - centre) @ axes.T
    low, high = along.min(axis=0), along.max(axis=0)
    middle = centre + ((low + high) / 2.0) @ axes
    half = (high - low) / 2.0
    signs = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]])
    corners = middle + (signs * half) @ axes
    return corners, (float(middle[0]), float(middle[1]), float(2 * half[0]), float(2 * half[1]), yaw)


def _same_corners(first, second, tolerance):
    distance = np.linalg.norm(first[:, None, :] - second[None, :, :], axis=2)
    return bool(np.all(distance.min(axis=1) <= tolerance))


def _box(points, z_min, z_max):
    return _from_rect(_rectangle(points)[1], float(z_min), float(z_max))


def _from_rect(rect, z_min, z_max):
    cx, cy, size_x, size_y, yaw = rect
    height = max(z_max - z_min, MIN_THICKNESS)
    return MeshBox(Pose(float(cx), float(cy), (z_min + z_max) / 2.0, 0.0, 0.0, yaw),
                   (max(size_x, MIN_THICKNESS), max(size_y, MIN_THICKNESS), height))


def describe(uri, error):
    """'mesh URI: reason', as a report names a mesh it leaves out."""
    return 'mesh %s %s' % (uri or '(no uri)', error)
