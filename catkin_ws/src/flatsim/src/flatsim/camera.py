"""A pinhole camera over the 2.5D scene: one 2D ray per image column.

The camera looks along +x of its own frame with a vertical image plane (no
pitch or roll); image left is the camera's +y (REP 103). The image is
symmetric about its centre, (w - 1) / 2 and (h - 1) / 2 in 0-based pixel
coordinates, as Gazebo renders it; camera_info carries Gazebo's own
cx = (w + 1) / 2, cy = (h + 1) / 2, one pixel off that centre, so that nodes see
the same numbers they see under Gazebo.

Per column, each box or cylinder the ray enters fills the rows between the
projections of its top and bottom at the entry depth (depth along the optical
axis, so walls stay straight). Looking down on a top face or up at a bottom
face extends the span to the exit depth. A sphere is a filled disc centred on
the projection of its centre with radius f r / sqrt(d^2 - r^2). The nearest
layers of each column occlude farther ones row by row; sky fills what is left
above the horizon, floor what is left below.

Lit surfaces are shaded like Gazebo's default sun (ambient 0.4 plus diffuse
0.8 times the Lambert term) with a mild distance falloff, quantised to
SHADE_LEVELS steps per primitive colour, and every channel is capped at 254. Only unlit_white primitives render as exactly (255, 255, 255).
"""
import ctypes
import ctypes.util
import math

import cv2
import numpy as np

from flatsim.errors import FlatsimError
from flatsim.raycast import cast, surface_normals
from flatsim.scene import SPHERE

ENCODINGS = {'R8G8B8': 'rgb8', 'B8G8R8': 'bgr8', 'L8': 'mono8'}
_CONVERSIONS = {'rgb8': cv2.COLOR_RGBA2RGB, 'bgr8': cv2.COLOR_RGBA2BGR,
                'mono8': cv2.COLOR_RGBA2GRAY}

# Gazebo's default sun shines along (-0.5, 0.1, -0.9); walls are vertical, so
# only the horizontal part of the direction towards the light matters.
_TO_LIGHT = np.array([0.5, -0.1, 0.9]) / np.linalg.norm([0.5, -0.1, 0.9])
AMBIENT = 0.4
DIFFUSE = 0.8
FALLOFF_PER_METRE = 0.02
MAX_SHADE = AMBIENT + DIFFUSE
SHADE_LEVELS = 256
MAX_LIT = 254
UNLIT_WHITE = 0x00FFFFFF
# Events are sorted as row << _EVENT_ID_BITS | event id, and each layer owns one
# bit of an int64 cover set, so a column can hold at most MAX_LAYERS layers.
_EVENT_ID_BITS = 6
_EVENT_ID_MASK = (1 << _EVENT_ID_BITS) - 1
MAX_LAYERS = 31


def keep_freed_memory(limit=64 << 20):
    """Let glibc reuse freed blocks of up to limit bytes instead of unmapping them.

    A render allocates a few megabytes of arrays. With glibc's defaults each
    frame maps fresh pages and faults them in, which costs about as much as
    the rendering itself. This is process-wide, so a long-running simulator
    calls it once at start-up. Returns False where the C library has no
    mallopt (not glibc).
    """
    try:
        libc = ctypes.CDLL(ctypes.util.find_library('c'))
        mallopt = libc.mallopt
    except (OSError, AttributeError, TypeError):
        return False
    m_trim_threshold, m_mmap_threshold = -1, -3
    return bool(mallopt(m_trim_threshold, limit * 2)) and bool(mallopt(m_mmap_threshold, limit))


def _pack(red, green, blue):
    """Colours as uint32 whose little-endian bytes are R, G, B, 0."""
    return (red.astype(np.uint32) | (green.astype(np.uint32) << 8)
            | (blue.astype(np.uint32) << 16))


def _lit_color(color, shade):
    """Packed colour of a lit surface: base colour (..., 3) in 0..1 times shade (...)."""
    channels = np.minimum(np.rint(color * (255.0 * shade[..., None])), MAX_LIT)
    return _pack(channels[..., 0], channels[..., 1], channels[..., 2])


def _shade(normal_x, normal_y, depth):
    lambert = np.maximum(normal_x * _TO_LIGHT[0] + normal_y * _TO_LIGHT[1], 0.0)
    return (AMBIENT + DIFFUSE * lambert) / (1.0 + FALLOFF_PER_METRE * depth)


class PinholeCamera:
    """Renders a Scene as rgb8, bgr8 or mono8 for a flatsim.config.CameraConfig.

    layers: how many of the nearest hits per column take part in occlusion;
    anything farther than the layers-th hit in a column is not drawn.
    """

    def __init__(self, config, layers=8):
        if config.image_format not in ENCODINGS:
            raise FlatsimError(
                'camera %r: image format %r is not supported; flatsim renders %s'
                % (config.sensor_name, config.image_format,
                   ', '.join('%s (%s)' % item for item in ENCODINGS.items())))
        if int(config.width) != config.width or int(config.height) != config.height \
                or config.width < 1 or config.height < 1:
            raise FlatsimError('camera %r: image size %r x %r is not two positive integers'
                               % (config.sensor_name, config.width, config.height))
        if not 0.0 < config.hfov < math.pi:
            raise FlatsimError('camera %r: horizontal_fov %r must lie between 0 and pi'
                               % (config.sensor_name, config.hfov))
        if not 0.0 < config.near < config.far:
            raise FlatsimError('camera %r: clip near %r and far %r need 0 < near < far'
                               % (config.sensor_name, config.near, config.far))
        if not 1 <= layers <= MAX_LAYERS:
            raise FlatsimError('camera: layers must be between 1 and %d, got %r'
                               % (MAX_LAYERS, layers))
        self.config = config
        self.width = int(config.width)
        self.height = int(config.height)
        self.focal = self.width / (2.0 * math.tan(config.hfov / 2.0))
        self.centre_u = (self.width - 1) / 2.0
        self.centre_v = (self.height - 1) / 2.0
        self.layers = int(layers)
        self._encoding = ENCODINGS[config.image_format]
        self._columns = np.arange(self.width, dtype=float)
        column_angle = np.arctan2(self.centre_u - self._columns, self.focal)
        self._cos_column = np.cos(column_angle)
        self._sin_column = np.sin(column_angle)
        self._half_fov = config.hfov / 2.0
        self._rgba = np.empty((self.height, self.width, 4), dtype=np.uint8)
        self._palette_source = None
        self._palette_colors = None

    def encoding(self):
        return self._encoding

    def info(self):
        """sensor_msgs/CameraInfo fields as gazebo_ros_camera fills them."""
        f = self.focal
        cx = (self.width + 1) / 2.0
        cy = (self.height + 1) / 2.0
        return {
            'width': self.width,
            'height': self.height,
            'distortion_model': 'plumb_bob',
            'D': [float(k) for k in self.config.distortion],
            'K': [f, 0.0, cx, 0.0, f, cy, 0.0, 0.0, 1.0],
            'R': [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            'P': [f, 0.0, cx, -f * self.config.hack_baseline, 0.0, f, cy, 0.0,
                  0.0, 0.0, 1.0, 0.0],
        }

    def render(self, scene, x, y, z, yaw, exclude=None, out=None):
        """The image seen from (x, y, z) looking along yaw.

        exclude: scene indices (or a mask) not to draw, such as the robot's own
        visuals. out: an optional array of the result's shape and dtype uint8
        to render into. Returns (h, w, 3) uint8 for rgb8/bgr8, (h, w) for mono8.
        """
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        prims = self._in_view(scene, x, y, cos_yaw, sin_yaw, exclude)
        is_sphere = scene.kind[prims] == SPHERE
        layers = [self._solid_layers(scene, prims[~is_sphere], x, y, z, cos_yaw, sin_yaw)]
        if is_sphere.any():
            layers.append(self._sphere_layers(scene, prims[is_sphere], x, y, z,
                                              cos_yaw, sin_yaw))
        depth, start, end, color = (np.concatenate([layer[i] for layer in layers], axis=1)
                                    for i in range(4))
        if depth.shape[1] > MAX_LAYERS:
            keep = np.argpartition(depth, MAX_LAYERS - 1, axis=1)[:, :MAX_LAYERS]
            depth, start, end, color = (np.take_along_axis(a, keep, axis=1)
                                        for a in (depth, start, end, color))
        order = np.argsort(depth, axis=1)
        start, end, color = (np.take_along_axis(a, order, axis=1) for a in (start, end, color))
        columns = self._compose(z, scene, start, end, color)
        return self._to_image(columns, out)

    def _in_view(self, scene, x, y, cos_yaw, sin_yaw, exclude):
        """Visual primitives whose bounding circle reaches into the view wedge."""
        prims = scene.select(visual=True, exclude=exclude)
        rel_x = scene.x[prims] - x
        rel_y = scene.y[prims] - y
        forward = rel_x * cos_yaw + rel_y * sin_yaw
        left = rel_y * cos_yaw - rel_x * sin_yaw
        bound = scene.bound[prims]
        cos_half, sin_half = math.cos(self._half_fov), math.sin(self._half_fov)
        keep = ((forward + bound >= self.config.near)
                & (rel_x * rel_x + rel_y * rel_y <= (self.config.far + bound) ** 2)
                & (left * cos_half - forward * sin_half <= bound)
                & (-left * cos_half - forward * sin_half <= bound))
        return prims[keep]

    def _rows(self, height_above_camera, depth):
        """Image row (0-based, fractional) where a height relative to the camera projects."""
        return self.centre_v - self.focal * height_above_camera / depth

    def _row_span(self, top_row, bottom_row, visible):
        """Half-open integer row range [start, end) of the pixel centres in a span."""
        start = np.clip(np.ceil(top_row), 0, self.height)
        end = np.clip(np.floor(bottom_row) + 1, 0, self.height)
        return (np.where(visible, start, 0).astype(np.int32),
                np.where(visible, end, 0).astype(np.int32))

    def _solid_layers(self, scene, prims, x, y, z, cos_yaw, sin_yaw):
        """Depth, row span and packed colour of the nearest box/cylinder hits per column."""
        cos_rays = self._cos_column * cos_yaw - self._sin_column * sin_yaw
        sin_rays = self._sin_column * cos_yaw + self._cos_column * sin_yaw
        hits = cast(scene, x, y, cos_rays, sin_rays, prims)
        to_depth = self._cos_column[:, None]
        depth = hits.entry * to_depth
        depth[(depth < self.config.near) | (depth > self.config.far)] = np.inf
        column = np.broadcast_to(np.arange(hits.prims.size), depth.shape)
        if hits.prims.size > self.layers:
            # Only the nearest few per column can show; shade and occlude just those.
            keep = np.argpartition(depth, self.layers - 1, axis=1)[:, :self.layers]
            depth = np.take_along_axis(depth, keep, axis=1)
            column = keep
        visible = np.isfinite(depth)
        prim = hits.prims[column] if hits.prims.size else np.zeros(depth.shape, dtype=int)
        exit_depth = np.take_along_axis(hits.exit, column, axis=1) * to_depth
        safe_depth = np.where(visible, depth, 1.0)
        top = scene.z_max[prim] - z
        bottom = scene.z_min[prim] - z
        # Looking down on a top face (or up at a bottom face) shows it out to the exit.
        top_row = self._rows(top, np.where(top < 0.0, exit_depth, safe_depth))
        bottom_row = self._rows(bottom, np.where(bottom > 0.0, exit_depth, safe_depth))
        start, end = self._row_span(top_row, bottom_row, visible)
        distance = safe_depth / to_depth
        normal_x, normal_y = surface_normals(scene, prim, x + distance * cos_rays[:, None],
                                             y + distance * sin_rays[:, None])
        color = self._colors(scene, prim, normal_x, normal_y, safe_depth)
        return depth, start, end, color

    def _sphere_layers(self, scene, prims, x, y, z, cos_yaw, sin_yaw):
        """Each sphere as a disc: per column its depth, row span and packed colour."""
        rel_x = scene.x[prims] - x
        rel_y = scene.y[prims] - y
        forward = rel_x * cos_yaw + rel_y * sin_yaw
        left = rel_y * cos_yaw - rel_x * sin_yaw
        radius = scene.radius[prims]
        above = 0.5 * (scene.z_min[prims] + scene.z_max[prims]) - z
        drawable = (forward > radius) & (forward - radius <= self.config.far)
        safe_forward = np.where(drawable, forward, radius + 1.0)
        centre_u = self.centre_u - self.focal * left / safe_forward
        centre_v = self._rows(above, safe_forward)
        disc_radius = self.focal * radius / np.sqrt(safe_forward ** 2 - radius ** 2)
        offset = (self._columns[:, None] - centre_u) / disc_radius
        inside = (np.abs(offset) <= 1.0) & drawable
        bulge = np.sqrt(np.maximum(1.0 - offset * offset, 0.0))
        half_height = disc_radius * bulge
        start, end = self._row_span(centre_v - half_height, centre_v + half_height, inside)
        depth = np.where(inside, forward - radius * bulge, np.inf)
        # Surface normal at the disc's middle row in this column, camera frame then world.
        normal_forward = -bulge
        normal_left = -np.clip(offset, -1.0, 1.0)
        normal_x = normal_forward * cos_yaw - normal_left * sin_yaw
        normal_y = normal_forward * sin_yaw + normal_left * cos_yaw
        prim = np.broadcast_to(prims, depth.shape)
        color = self._colors(scene, prim, normal_x, normal_y, np.where(inside, depth, 1.0))
        return depth, start, end, color

    def _colors(self, scene, prim, normal_x, normal_y, depth):
        """Packed colours from a per-primitive palette of SHADE_LEVELS shades."""
        palette = self._palette(scene)
        level = np.rint(_shade(normal_x, normal_y, depth) * (SHADE_LEVELS - 1) / MAX_SHADE)
        # Columns a primitive does not cover get a stand-in hit point off its outline,
        # where a cylinder's normal is longer than 1; their colour is never drawn.
        np.clip(level, 0, SHADE_LEVELS - 1, out=level)
        return palette[prim, level.astype(np.intp)]

    def _palette(self, scene):
        """(primitives, SHADE_LEVELS) packed colours, rebuilt when the scene's colours change."""
        if self._palette_source is not scene.color:
            shades = np.linspace(0.0, MAX_SHADE, SHADE_LEVELS)
            palette = _lit_color(scene.color[:, None, :], np.broadcast_to(
                shades, (len(scene.color), SHADE_LEVELS)))
            palette[scene.unlit_white] = UNLIT_WHITE
            self._palette_source, self._palette_colors = scene.color, palette
        return self._palette_colors

    def _background(self, scene, z):
        sky = np.asarray(scene.sky_color, dtype=float)[None, :]
        floor = np.asarray(scene.floor_color, dtype=float)[None, :]
        colors = _lit_color(np.concatenate([sky, floor]), np.ones(2))
        first_floor_row = self.height if z <= 0 else min(
            int(math.floor(self.centre_v)) + 1, self.height)
        return colors[0], colors[1], first_floor_row

    def _compose(self, z, scene, start, end, color):
        """Column-major packed image: per column, runs of rows and the colour each shows.

        Layers come nearest first. Every span start and end is an event that
        toggles its layer's bit; once the events are sorted down each column, a
        running XOR gives the set of layers covering each run of rows, and the
        lowest bit of that set is the nearest of them.
        """
        sky, floor, first_floor_row = self._background(scene, z)
        width, layers = start.shape
        horizon = np.full((width, 1), first_floor_row, dtype=np.int64)
        events = np.concatenate([start, end, horizon], axis=1).astype(np.int64)
        events <<= _EVENT_ID_BITS
        events |= np.arange(events.shape[1])
        events.sort(axis=1)
        position = events >> _EVENT_ID_BITS
        toggles = np.ones(layers, dtype=np.int64) << np.arange(layers)
        layer_bit = np.concatenate([toggles, toggles, [0]])
        covering = np.bitwise_xor.accumulate(layer_bit[events & _EVENT_ID_MASK], axis=1)
        nearest_bit = covering & -covering
        nearest = np.frexp(nearest_bit.astype(float))[1] - 1
        background = np.where(position < first_floor_row, layers, layers + 1)
        palette = np.concatenate([color, np.full((width, 1), sky, dtype=np.uint32),
                                  np.full((width, 1), floor, dtype=np.uint32)], axis=1)
        run_color = np.take_along_axis(
            palette, np.where(nearest_bit == 0, background, nearest), axis=1)
        first_run = np.full((width, 1), sky if first_floor_row > 0 else floor, dtype=np.uint32)
        run_color = np.concatenate([first_run, run_color], axis=1)
        run_end = np.concatenate([position, np.full((width, 1), self.height)], axis=1)
        run_length = np.diff(run_end, axis=1, prepend=0)
        return np.repeat(run_color.ravel(), run_length.ravel())

    def _to_image(self, columns, out):
        packed = columns.astype('<u4', copy=False).view(np.uint8).reshape(
            self.width, self.height, 4)
        cv2.transpose(packed, dst=self._rgba)
        conversion = _CONVERSIONS[self._encoding]
        if out is None:
            return cv2.cvtColor(self._rgba, conversion)
        return cv2.cvtColor(self._rgba, conversion, dst=out)
