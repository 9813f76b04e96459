"""A top-down picture of the simulation: world, balls, robots, lidar hits, camera cones.

No ROS here. MapFrame is the world-to-pixel mapping, reusable by anything
that draws on the same picture (tests, trajectory plots). render() draws a
scene and what is passed to it; OverheadView draws a Simulation and keeps the
static world as a cached background.

Image convention: rgb8, x to the right, y up; row 0 is the top (largest y).
Pixel (col, row) covers x in [x_min + col * res, x_min + (col + 1) * res) and
y in (y_max - (row + 1) * res, y_max - row * res].
"""
import math
from dataclasses import dataclass

import cv2
import numpy as np

from flatsim.errors import FlatsimError
from flatsim.world.scene import BOX

# cv2 draws with sub-pixel accuracy on coordinates with this many fraction bits.
_SHIFT = 4
_SCALE = 1 << _SHIFT

ROBOT_COLORS = ((40, 110, 230), (230, 120, 20), (150, 60, 200), (20, 160, 120))
HEADING_COLOR = (255, 230, 0)
OUTLINE_COLOR = (20, 20, 20)
SCAN_HIT_COLOR = (230, 20, 20)
CONE_COLOR = (255, 240, 120)
CONE_OPACITY = 0.35
# Room around the world so that walls are not cut by the image edge.
DEFAULT_MARGIN = 0.5
# The extent drawn around robots in a world with nothing else in it.
EMPTY_WORLD_HALF_SIZE = 3.0


@dataclass(frozen=True)
class MapFrame:
    """World (x, y) in metres to image (col, row) for an axis-aligned area at a resolution."""
    x_min: float
    y_min: float
    x_max: float
    y_max: float
    resolution: float                          # m per pixel

    def __post_init__(self):
        values = (self.x_min, self.y_min, self.x_max, self.y_max, self.resolution)
        if not all(math.isfinite(v) for v in values) or self.resolution <= 0:
            raise FlatsimError('map frame needs finite bounds and a positive resolution, got %r'
                               % (values,))
        if self.x_max <= self.x_min or self.y_max <= self.y_min:
            raise FlatsimError('map frame bounds are empty: x %g..%g, y %g..%g'
                               % (self.x_min, self.x_max, self.y_min, self.y_max))

    @classmethod
    def around(cls, x_min, y_min, x_max, y_max, resolution, margin=DEFAULT_MARGIN,
               max_pixels=None):
        """The frame holding these bounds plus margin; coarser than resolution if that
        would make either side longer than max_pixels."""
        x_min, y_min, x_max, y_max = x_min - margin, y_min - margin, x_max + margin, y_max + margin
        if max_pixels:
            longest = max(x_max - x_min, y_max - y_min)
            resolution = max(resolution, longest / max_pixels)
        return cls(x_min, y_min, x_max, y_max, resolution)

    @property
    def width(self):
        return int(math.ceil((self.x_max - self.x_min) / self.resolution - 1e-9))

    @property
    def height(self):
        return int(math.ceil((self.y_max - self.y_min) / self.resolution - 1e-9))

    @property
    def shape(self):
        """(height, width, 3): the shape of an rgb image of this frame."""
        return self.height, self.width, 3

    def to_pixel(self, points):
        """Continuous (col, row) of world points (..., 2); pixel centres are at +0.5."""
        points = np.asarray(points, dtype=float)
        cols = (points[..., 0] - self.x_min) / self.resolution
        rows = (self.y_max - points[..., 1]) / self.resolution
        return np.stack([cols, rows], axis=-1)

    def pixel_of(self, x, y):
        """(col, row) of the pixel that holds the world point (x, y)."""
        col, row = np.floor(self.to_pixel([x, y])).astype(int)
        return int(col), int(row)

    def to_world(self, col, row):
        """World (x, y) of a pixel's centre."""
        return (self.x_min + (col + 0.5) * self.resolution,
                self.y_max - (row + 0.5) * self.resolution)

    def contains_pixel(self, col, row):
        return 0 <= col < self.width and 0 <= row < self.height

    def blank(self, color):
        image = np.empty(self.shape, dtype=np.uint8)
        image[:] = color
        return image

    def _cv_points(self, points):
        # cv2's pixel centres are at integer coordinates, ours at +0.5.
        return np.round((self.to_pixel(points) - 0.5) * _SCALE).astype(np.int32)


def rgb8(color):
    """A colour in 0..1 as a tuple of 0..255 ints."""
    return tuple(int(round(min(max(float(c), 0.0), 1.0) * 255)) for c in color[:3])


def footprint_points(footprint, x, y, yaw):
    """A body-frame outline (N, 2) placed at the pose (x, y, yaw), in the world."""
    local = np.asarray(footprint, dtype=float).reshape(-1, 2)
    c, s = math.cos(yaw), math.sin(yaw)
    return np.column_stack([x + c * local[:, 0] - s * local[:, 1],
                            y + s * local[:, 0] + c * local[:, 1]])


def scan_hits(ranges, angles, x, y, yaw):
    """World points of the finite ranges of a scan from a sensor at (x, y) facing yaw."""
    ranges = np.asarray(ranges, dtype=float)
    angles = np.asarray(angles, dtype=float)
    hit = np.isfinite(ranges) & (ranges > 0)
    beam = angles[hit] + yaw
    return np.column_stack([x + ranges[hit] * np.cos(beam), y + ranges[hit] * np.sin(beam)])


def cone_points(x, y, yaw, hfov, length, arc_points=16):
    """The outline of a camera's horizontal view wedge: apex, then its far arc."""
    angles = yaw + np.linspace(-hfov / 2.0, hfov / 2.0, arc_points)
    arc = np.column_stack([x + length * np.cos(angles), y + length * np.sin(angles)])
    return np.vstack([[x, y], arc])


def moving_indices(sim):
    """Scene indices of the primitives of models that move (balls)."""
    return sorted(i for model in sim.models.values() if model.handle is not None
                  for i in model.prim_ids)



def scene_bounds(scene, indices):
    """(x_min, y_min, x_max, y_max) of the given primitives' footprints, or None."""
    indices = np.asarray(indices, dtype=int)
    if indices.size == 0:
        return None
    reach_x, reach_y = _reach(scene, indices)
    x, y = scene.x[indices], scene.y[indices]
    return (float(np.min(x - reach_x)), float(np.min(y - reach_y)),
            float(np.max(x + reach_x)), float(np.max(y + reach_y)))


def _reach(scene, indices):
    """Half extents along x and y of the primitives' footprints."""
    cos_yaw, sin_yaw = np.abs(scene.cos_yaw[indices]), np.abs(scene.sin_yaw[indices])
    half_x, half_y = scene.half_x[indices], scene.half_y[indices]
    box = scene.kind[indices] == BOX
    return (np.where(box, cos_yaw * half_x + sin_yaw * half_y, scene.radius[indices]),
            np.where(box, sin_yaw * half_x + cos_yaw * half_y, scene.radius[indices]))


def draw_prims(image, frame, scene, indices, color=None):
    """Draw primitives in place, lowest top first, so a table top covers what is under it.

    A pixel takes a primitive's colour (or color, rgb8, for all of them) when its centre lies
    inside the primitive's footprint, so edges land on exact pixels for measurements.
    """
    indices = np.asarray(indices, dtype=int)
    indices = indices[np.argsort(scene.z_max[indices], kind='stable')]
    reach_x, reach_y = _reach(scene, indices)
    for index, across, along in zip(indices, reach_x, reach_y):
        x, y = scene.x[index], scene.y[index]
        col_min, row_min = np.floor(frame.to_pixel([x - across, y + along])).astype(int)
        col_max, row_max = np.floor(frame.to_pixel([x + across, y - along])).astype(int)
        col_min, row_min = max(col_min, 0), max(row_min, 0)
        col_max, row_max = min(col_max, frame.width - 1), min(row_max, frame.height - 1)
        if col_min > col_max or row_min > row_max:
            continue
        dx = frame.x_min + (np.arange(col_min, col_max + 1) + 0.5) * frame.resolution - x
        dy = frame.y_max - (np.arange(row_min, row_max + 1) + 0.5) * frame.resolution - y
        dx, dy = dx[None, :], dy[:, None]
        if scene.kind[index] == BOX:
            cos_yaw, sin_yaw = scene.cos_yaw[index], scene.sin_yaw[index]
            inside = ((np.abs(cos_yaw * dx + sin_yaw * dy) <= scene.half_x[index])
                      & (np.abs(-sin_yaw * dx + cos_yaw * dy) <= scene.half_y[index]))
        else:
            inside = dx * dx + dy * dy <= scene.radius[index] ** 2
        image[row_min:row_max + 1, col_min:col_max + 1][inside] = (
            rgb8(scene.color[index]) if color is None else color)


def draw_cones(image, frame, cones):
    """Blend camera view wedges (x, y, yaw, hfov, length) over the image, in place."""
    if not cones:
        return
    mask = np.zeros(image.shape[:2], dtype=np.uint8)
    for x, y, yaw, hfov, length in cones:
        cv2.fillPoly(mask, [frame._cv_points(cone_points(x, y, yaw, hfov, length))], 255,
                     cv2.LINE_8, _SHIFT)
    inside = mask > 0
    blended = (image[inside] * (1.0 - CONE_OPACITY)
               + np.array(CONE_COLOR, dtype=float) * CONE_OPACITY)
    image[inside] = np.round(blended).astype(np.uint8)


def draw_points(image, frame, points, color, radius_px=1):
    """Mark world points (N, 2) as squares of side 2 * radius_px + 1, in place."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if points.size == 0:
        return
    cols, rows = np.floor(frame.to_pixel(points)).astype(int).T
    offsets = np.arange(-radius_px, radius_px + 1)
    cols = (cols[:, None, None] + offsets[None, None, :]).repeat(offsets.size, axis=1).ravel()
    rows = (rows[:, None, None] + offsets[None, :, None]).repeat(offsets.size, axis=2).ravel()
    keep = (cols >= 0) & (cols < frame.width) & (rows >= 0) & (rows < frame.height)
    image[rows[keep], cols[keep]] = color


def draw_robot(image, frame, outline, x, y, yaw, color):
    """A robot's footprint (world points) filled in its colour, with a heading mark.

    The heading mark runs from 40 % of the way to the front edge out to it, so
    the pixel at the robot's pose keeps the robot's colour.
    """
    outline = np.asarray(outline, dtype=float)
    cv_outline = frame._cv_points(outline)
    cv2.fillPoly(image, [cv_outline], color, cv2.LINE_8, _SHIFT)
    cv2.polylines(image, [cv_outline], True, OUTLINE_COLOR, 1, cv2.LINE_AA, _SHIFT)
    heading = np.array([math.cos(yaw), math.sin(yaw)])
    reach = float(np.max((outline - (x, y)) @ heading))
    if reach <= 0:
        return
    start = frame._cv_points([x + 0.4 * reach * heading[0], y + 0.4 * reach * heading[1]])
    end = frame._cv_points([x + reach * heading[0], y + reach * heading[1]])
    thickness = max(1, int(round(0.03 / frame.resolution)))
    cv2.line(image, tuple(int(v) for v in start), tuple(int(v) for v in end), HEADING_COLOR,
             thickness, cv2.LINE_AA, _SHIFT)


def render(scene, frame=None, robots=(), scans=(), cameras=(), moving=(), background=None,
           resolution=0.02):
    """Draw the scene from above; returns (image, frame).

    robots: (world outline (N, 2), (x, y, yaw)) per robot, coloured from ROBOT_COLORS in order.
    scans: world points (N, 2) of lidar hits. cameras: (x, y, yaw, hfov, length) wedges.
    moving: scene indices drawn over everything else in the world (balls).
    background: an image of the static world in this frame (from render_static); without
    it every live visual primitive is drawn. frame: None fits the scene and the robots.
    """
    robots = list(robots)
    moving = np.asarray(list(moving), dtype=int)
    if frame is None:
        frame = fit_frame(scene, [outline for outline, _ in robots], resolution)
    if background is None:
        visual = scene.select(visual=True)
        image = render_static(scene, frame, np.setdiff1d(visual, moving))
    else:
        image = background.copy()
    draw_cones(image, frame, list(cameras))
    draw_prims(image, frame, scene, np.intersect1d(scene.select(visual=True), moving))
    for hits in scans:
        draw_points(image, frame, hits, SCAN_HIT_COLOR)
    for number, (outline, (x, y, yaw)) in enumerate(robots):
        draw_robot(image, frame, outline, x, y, yaw, ROBOT_COLORS[number % len(ROBOT_COLORS)])
    return image, frame


def render_static(scene, frame, indices):
    """The floor with the given primitives on it: the cacheable part of a picture."""
    image = frame.blank(rgb8(scene.floor_color))
    draw_prims(image, frame, scene, indices)
    return image


def fit_frame(scene, outlines=(), resolution=0.02, margin=DEFAULT_MARGIN, max_pixels=2000):
    """A frame holding every live primitive and the given outlines, plus margin."""
    boxes = []
    bounds = scene_bounds(scene, scene.select())
    if bounds is not None:
        boxes.append(bounds)
    for outline in outlines:
        outline = np.asarray(outline, dtype=float).reshape(-1, 2)
        if outline.size:
            boxes.append((*outline.min(axis=0), *outline.max(axis=0)))
    if not boxes:
        half = EMPTY_WORLD_HALF_SIZE
        boxes.append((-half, -half, half, half))
    boxes = np.array(boxes, dtype=float)
    if bounds is None:
        centre = (boxes[:, :2].min(axis=0) + boxes[:, 2:].max(axis=0)) / 2.0
        half = EMPTY_WORLD_HALF_SIZE
        boxes = np.vstack([boxes, [centre[0] - half, centre[1] - half,
                                   centre[0] + half, centre[1] + half]])
    x_min, y_min = boxes[:, :2].min(axis=0)
    x_max, y_max = boxes[:, 2:].max(axis=0)
    return MapFrame.around(float(x_min), float(y_min), float(x_max), float(y_max), resolution,
                           margin, max_pixels)


class OverheadView:
    """Renders a flatsim Simulation from above, keeping the static world as a background.

    The frame is fitted to the world and the robots the first time, and again
    whenever the set of static primitives changes (a model spawned or deleted),
    so the image keeps its size while robots drive around.
    """

    def __init__(self, resolution=0.02, cone_length=3.0, max_pixels=2000, margin=DEFAULT_MARGIN):
        if not resolution > 0:
            raise FlatsimError('overhead resolution must be positive metres per pixel, got %r'
                               % resolution)
        self.resolution = float(resolution)
        self.cone_length = float(cone_length)
        self.max_pixels = max_pixels
        self.margin = margin
        self.frame = None
        self._background = None
        self._static_key = None
        self._layout = None

    def render(self, sim, scans=()):
        """The picture of sim now. scans: (ranges, angles, (x, y, yaw) of the sensor) per laser."""
        scene = sim.scene
        sim.sync_moving_prims()
        moving = moving_indices(sim)
        robots = []
        cameras = []
        for robot in sim.robots():
            pose = sim.model_pose(robot.name)
            robots.append((footprint_points(robot.spec.footprint, pose.x, pose.y, pose.yaw),
                           (pose.x, pose.y, pose.yaw)))
            for slot in robot.sensors:
                if slot.kind == 'camera':
                    eye = sim.sensor_pose(slot)
                    length = min(self.cone_length, slot.config.far)
                    cameras.append((eye.x, eye.y, eye.yaw, slot.config.hfov, length))
        static = np.setdiff1d(scene.select(visual=True), moving)
        key = tuple(static.tolist())
        if key != self._static_key:
            self.frame = fit_frame(scene, [outline for outline, _ in robots], self.resolution,
                                   self.margin, self.max_pixels)
        # A static model moved by hand keeps its primitives' indices: the background is drawn
        # again, in the same frame.
        layout = getattr(sim, 'layout_version', 0)
        if key != self._static_key or layout != self._layout:
            self._background = render_static(scene, self.frame, static)
            self._static_key, self._layout = key, layout
        hits = [scan_hits(ranges, angles, *pose) for ranges, angles, pose in scans]
        image, _ = render(scene, self.frame, robots, hits, cameras, moving, self._background)
        return image
