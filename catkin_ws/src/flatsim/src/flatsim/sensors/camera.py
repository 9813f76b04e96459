"""A pinhole camera over the 2.5D scene: one 2D ray per image column when level.

The camera looks along +x of its own frame; image left is the camera's +y and
image up its +z (REP 103). A level camera (no pitch or roll, the chase robot's)
renders here, column by column; a pitched or rolled one is handed to
flatsim.sensors.raster, which draws the same scene face by face. The image is
symmetric about its centre, (w - 1) / 2 and (h - 1) / 2 in 0-based pixel
coordinates, as Gazebo renders it; camera_info carries Gazebo's own
cx = (w + 1) / 2, cy = (h + 1) / 2, one pixel off that centre, so that nodes see
the same numbers they see under Gazebo.

Per column, each box or cylinder the ray enters fills the rows between the
projections of its top and bottom at the entry depth (depth along the optical
axis, so walls stay straight). Looking down on a top face or up at a bottom
face extends the span to the exit depth. A box or cylinder the camera stands
over (inside its footprint, above its top: a floor slab under the robot) shows
its top from the bottom of the image out to its far edge, lit as the floor is,
and at the depth of that edge, so that what stands on it is drawn in front.
A sphere is a filled disc centred on the projection of its centre with radius
f r / sqrt(d^2 - r^2). The nearest layers of each column occlude farther ones
row by row; sky fills what is left above the horizon, floor what is left below.

Lit surfaces are shaded like Gazebo's default sun (ambient 0.4 plus diffuse
0.8 times the Lambert term) with a mild distance falloff, quantised to
SHADE_LEVELS steps per primitive colour, and every channel is capped at 254.
Only unlit_white primitives render as exactly (255, 255, 255).

The per-column work is one numba-compiled kernel (_render_columns); OpenCV
then turns its column-major packed colours into the requested encoding.
"""
import ctypes
import ctypes.util
import math

import cv2
import numpy as np

from flatsim.errors import FlatsimError
from flatsim.sensors import raster
# Shading is shared with the tilted renderer: Gazebo's default sun, of which a
# level camera needs only the horizontal part, as the walls it sees are vertical.
from flatsim.sensors.raster import AMBIENT, DIFFUSE, FALLOFF_PER_METRE, MAX_SHADE, TO_LIGHT
from flatsim.sensors.raycast import jit, prim_arrays, ray_box, ray_prim, surface_normal
from flatsim.world.scene import BOX, SPHERE

ENCODINGS = {'R8G8B8': 'rgb8', 'B8G8R8': 'bgr8', 'L8': 'mono8'}
_CONVERSIONS = {'rgb8': cv2.COLOR_RGBA2RGB, 'bgr8': cv2.COLOR_RGBA2BGR,
                'mono8': cv2.COLOR_RGBA2GRAY}

SHADE_LEVELS = 256
MAX_LIT = 254
UNLIT_WHITE = 0x00FFFFFF
# The most layers a column may keep (each costs a little per column).
MAX_LAYERS = 64
# Pitch and roll below this (rad) render as a level camera: at 640 pixels the
# horizon would move by well under a thousandth of a pixel.
LEVEL_TOLERANCE = 1e-9


def keep_freed_memory(limit=64 << 20):
    """Let glibc reuse freed blocks of up to limit bytes instead of unmapping them.

    A render returns a fresh image of a few megabytes, and a message holding
    it is as large again. With glibc's defaults each frame maps fresh pages and
    faults them in; kept, the freed blocks serve the next frame. This is
    process-wide, so a long-running simulator calls it once at start-up.
    Returns False where the C library has no mallopt (not glibc).
    """
    try:
        libc = ctypes.CDLL(ctypes.util.find_library('c'))
        mallopt = libc.mallopt
    except (OSError, AttributeError, TypeError):
        return False
    m_trim_threshold, m_mmap_threshold = -1, -3
    return bool(mallopt(m_trim_threshold, limit * 2)) and bool(mallopt(m_mmap_threshold, limit))


def _pack(red, green, blue):
    """Colours as little-endian uint32 whose bytes are R, G, B, 0."""
    return (red.astype('<u4') | (green.astype('<u4') << 8) | (blue.astype('<u4') << 16))


def _lit_color(color, shade):
    """Packed colour of a lit surface: base colour (..., 3) in 0..1 times shade (...)."""
    channels = np.minimum(np.rint(color * (255.0 * shade[..., None])), MAX_LIT)
    return _pack(channels[..., 0], channels[..., 1], channels[..., 2])


class PinholeCamera:
    """Renders a Scene as rgb8, bgr8 or mono8 for a flatsim.loading.config.CameraConfig.

    layers: how many of the nearest hits per column take part in occlusion;
    anything farther than the layers-th hit in a column is not drawn.
    """

    def __init__(self, config, layers=16):
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
        column_angle = np.arctan2(self.centre_u - np.arange(self.width), self.focal)
        self._cos_column = np.cos(column_angle)
        self._sin_column = np.sin(column_angle)
        self._half_fov = config.hfov / 2.0
        self._rgba = np.empty((self.height, self.width, 4), dtype=np.uint8)
        self._packed_columns = np.empty((self.width, self.height), dtype='<u4')
        self._packed_rows = None
        self._inverse_depth = None
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

    def render(self, scene, x, y, z, yaw, exclude=None, out=None, pitch=0.0, roll=0.0):
        """The image seen from (x, y, z) with the camera turned by roll, pitch and yaw.

        exclude: scene indices (or a mask) not to draw, such as the robot's own
        visuals. out: an optional C-contiguous uint8 array of the result's shape
        to render into. Returns (h, w, 3) uint8 for rgb8/bgr8, (h, w) for mono8.
        """
        shape = (self.height, self.width) if self._encoding == 'mono8' \
            else (self.height, self.width, 3)
        if out is None:
            out = np.empty(shape, dtype=np.uint8)
        elif out.shape != shape or out.dtype != np.uint8 or not out.flags.c_contiguous:
            raise FlatsimError('camera %r: render buffer must be C-contiguous uint8 of shape %r, '
                               'got %s %r' % (self.config.sensor_name, shape, out.dtype, out.shape))
        if abs(pitch) > LEVEL_TOLERANCE or abs(roll) > LEVEL_TOLERANCE:
            return self._render_tilted(scene, x, y, z, roll, pitch, yaw, exclude, out)
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        prims = self._in_view(scene, x, y, cos_yaw, sin_yaw, exclude)
        palette, sky, floor = self._colors(scene)
        first_floor_row = self.height if z <= 0 else min(
            int(math.floor(self.centre_v)) + 1, self.height)
        _render_columns(
            float(x), float(y), float(z), cos_yaw, sin_yaw,
            self._cos_column * cos_yaw - self._sin_column * sin_yaw,
            self._sin_column * cos_yaw + self._cos_column * sin_yaw, self._cos_column,
            prims, *prim_arrays(scene, prims), scene.z_min[prims], scene.z_max[prims],
            _stood_over(scene, prims, x, y, z),
            palette, sky, floor, first_floor_row, self.focal, self.centre_u, self.centre_v,
            float(self.config.near), float(self.config.far), self.layers,
            self._packed_columns)
        # The kernel fills whole columns, which lie contiguous only column-major.
        cv2.transpose(self._packed_columns.view(np.uint8).reshape(self.width, self.height, 4),
                      dst=self._rgba)
        return cv2.cvtColor(self._rgba, _CONVERSIONS[self._encoding], dst=out)

    def _render_tilted(self, scene, x, y, z, roll, pitch, yaw, exclude, out):
        if self._packed_rows is None:
            self._packed_rows = np.empty((self.height, self.width), dtype='<u4')
            self._inverse_depth = np.empty((self.height, self.width), dtype=np.float32)
        eye = np.array([x, y, z], dtype=float)
        axes = raster.camera_axes(roll, pitch, yaw)
        near, far = float(self.config.near), float(self.config.far)
        prims = raster.in_frustum(scene, scene.select(visual=True, exclude=exclude), eye, axes,
                                  self.focal, self.centre_u, self.centre_v, near, far)
        palette, sky, floor = self._colors(scene)
        raster.render_tilted(eye, *axes, self.focal, self.centre_u, self.centre_v, near, far,
                             prims, *prim_arrays(scene, prims), scene.z_min[prims],
                             scene.z_max[prims], palette, sky, floor, self._packed_rows,
                             self._inverse_depth)
        rgba = self._packed_rows.view(np.uint8).reshape(self.height, self.width, 4)
        return cv2.cvtColor(rgba, _CONVERSIONS[self._encoding], dst=out)

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

    def _colors(self, scene):
        """(palette, sky, floor) as packed colours (see _pack).

        palette: (primitives, SHADE_LEVELS), the shades of each primitive's
        colour; rebuilt when the scene's colours change.
        """
        if self._palette_source is not scene.color:
            shades = np.linspace(0.0, MAX_SHADE, SHADE_LEVELS)
            palette = _lit_color(scene.color[:, None, :], np.broadcast_to(
                shades, (len(scene.color), SHADE_LEVELS)))
            palette[scene.unlit_white] = UNLIT_WHITE
            sky, floor = _lit_color(np.array([scene.sky_color, scene.floor_color], dtype=float),
                                    np.ones(2))
            self._palette_source, self._palette_colors = scene.color, (palette, sky, floor)
        return self._palette_colors


@jit
def _row_span(top_row, bottom_row, height):
    """Half-open integer row range [start, end) of the pixel centres between two rows."""
    if not top_row <= bottom_row:  # also a NaN from a degenerate grazing hit
        return 0, 0
    top_row = min(max(top_row, -1.0), height + 1.0)
    bottom_row = min(max(bottom_row, -1.0), height + 1.0)
    start = min(max(int(math.ceil(top_row)), 0), height)
    end = min(max(int(math.floor(bottom_row)) + 1, 0), height)
    return start, end


def _stood_over(scene, prims, x, y, z):
    """Which of the boxes and cylinders prims the camera at (x, y, z) stands over: inside
    their footprint, above their top."""
    rel_x = x - scene.x[prims]
    rel_y = y - scene.y[prims]
    cos_yaw, sin_yaw = scene.cos_yaw[prims], scene.sin_yaw[prims]
    local_x = np.abs(rel_x * cos_yaw + rel_y * sin_yaw)
    local_y = np.abs(rel_y * cos_yaw - rel_x * sin_yaw)
    kind = scene.kind[prims]
    inside = np.where(kind == BOX,
                      (local_x < scene.half_x[prims]) & (local_y < scene.half_y[prims]),
                      rel_x * rel_x + rel_y * rel_y < scene.radius[prims] ** 2)
    return inside & (kind != SPHERE) & (scene.z_max[prims] < z)


@jit
def _exit_from_inside(origin_x, origin_y, cos_ray, sin_ray, kind, x, y, cos_yaw, sin_yaw,
                      half_x, half_y, radius):
    """How far a ray from inside a box's or circle's outline runs before it leaves it."""
    if kind == BOX:
        return ray_box(origin_x, origin_y, cos_ray, sin_ray, x, y, cos_yaw, sin_yaw,
                       half_x, half_y)[1]
    rel_x = x - origin_x
    rel_y = y - origin_y
    along = cos_ray * rel_x + sin_ray * rel_y
    return along + math.sqrt(max(along * along - (rel_x * rel_x + rel_y * rel_y - radius * radius),
                                 0.0))


# The palette level of a surface lit as the floor is (full light).
FLOOR_LEVEL = int(np.rint((SHADE_LEVELS - 1) / MAX_SHADE))


@jit
def _shade_level(normal_x, normal_y, depth):
    """Palette level of a lit surface: Lambert term under the sun, dimmed with distance."""
    lambert = max(normal_x * TO_LIGHT[0] + normal_y * TO_LIGHT[1], 0.0)
    shade = (AMBIENT + DIFFUSE * lambert) / (1.0 + FALLOFF_PER_METRE * depth)
    level = np.rint(shade * (SHADE_LEVELS - 1) / MAX_SHADE)
    return int(min(max(level, 0.0), SHADE_LEVELS - 1))


@jit
def _render_columns(x, y, z, cos_yaw, sin_yaw, cos_rays, sin_rays, to_depth, scene_index,
                    kind, prim_x, prim_y, prim_cos, prim_sin, half_x, half_y, radius, z_min,
                    z_max, stood_over, palette, sky, floor, first_floor_row, focal, centre_u,
                    centre_v, near, far, layers, out):
    """Render every column of out, (w, h) packed colours, from the primitives listed.

    Per column, the nearest `layers` surfaces are kept in depth order (depth
    along the optical axis), each with its row span and palette level; then
    the rows are walked top to bottom, each run taking the colour of the
    nearest layer that covers it, else sky above the horizon and floor below.
    """
    width, height = out.shape
    depth = np.empty(layers)
    start = np.empty(layers, dtype=np.int64)
    end = np.empty(layers, dtype=np.int64)
    owner = np.empty(layers, dtype=np.int64)
    level = np.empty(layers, dtype=np.int64)
    for column in range(width):
        cos_ray, sin_ray, axis = cos_rays[column], sin_rays[column], to_depth[column]
        count = 0
        for prim in range(kind.size):
            if kind[prim] == SPHERE:
                # A sphere is a disc centred on the projection of its centre.
                rel_x, rel_y = prim_x[prim] - x, prim_y[prim] - y
                forward = rel_x * cos_yaw + rel_y * sin_yaw
                left = rel_y * cos_yaw - rel_x * sin_yaw
                r = radius[prim]
                if not (forward > r and forward - r <= far):
                    continue
                disc_radius = focal * r / math.sqrt(forward * forward - r * r)
                offset = (column - (centre_u - focal * left / forward)) / disc_radius
                if abs(offset) > 1.0:
                    continue
                bulge = math.sqrt(max(1.0 - offset * offset, 0.0))
                hit_depth = forward - r * bulge
                if count == layers and hit_depth >= depth[count - 1]:
                    continue
                disc_row = centre_v - focal * (0.5 * (z_min[prim] + z_max[prim]) - z) / forward
                half_rows = disc_radius * bulge
                span_start, span_end = _row_span(disc_row - half_rows, disc_row + half_rows,
                                                 height)
                # Surface normal at the disc's middle row in this column.
                normal_forward, normal_left = -bulge, -offset
                shade = _shade_level(normal_forward * cos_yaw - normal_left * sin_yaw,
                                     normal_forward * sin_yaw + normal_left * cos_yaw,
                                     hit_depth)
            elif stood_over[prim]:
                exit_ = _exit_from_inside(x, y, cos_ray, sin_ray, kind[prim], prim_x[prim],
                                          prim_y[prim], prim_cos[prim], prim_sin[prim],
                                          half_x[prim], half_y[prim], radius[prim])
                hit_depth = min(exit_ * axis, far)
                if not hit_depth >= near:
                    continue
                if count == layers and hit_depth >= depth[count - 1]:
                    continue
                top_row = centre_v - focal * (z_max[prim] - z) / hit_depth
                span_start, span_end = _row_span(top_row, height + 1.0, height)
                shade = FLOOR_LEVEL
            else:
                entry, exit_ = ray_prim(x, y, cos_ray, sin_ray, kind[prim], prim_x[prim],
                                        prim_y[prim], prim_cos[prim], prim_sin[prim],
                                        half_x[prim], half_y[prim], radius[prim])
                hit_depth = entry * axis
                if not (near <= hit_depth <= far):
                    continue
                if count == layers and hit_depth >= depth[count - 1]:
                    continue
                top = z_max[prim] - z
                bottom = z_min[prim] - z
                # Looking down on a top face (or up at a bottom face) shows it out to the exit.
                top_row = centre_v - focal * top / (exit_ * axis if top < 0.0 else hit_depth)
                bottom_row = centre_v - focal * bottom / (
                    exit_ * axis if bottom > 0.0 else hit_depth)
                span_start, span_end = _row_span(top_row, bottom_row, height)
                normal_x, normal_y = surface_normal(
                    kind[prim], prim_x[prim], prim_y[prim], prim_cos[prim], prim_sin[prim],
                    half_x[prim], half_y[prim], radius[prim], x + entry * cos_ray,
                    y + entry * sin_ray)
                shade = _shade_level(normal_x, normal_y, hit_depth)
            slot = count if count < layers else layers - 1
            while slot > 0 and depth[slot - 1] > hit_depth:
                depth[slot], start[slot], end[slot] = (depth[slot - 1], start[slot - 1],
                                                       end[slot - 1])
                owner[slot], level[slot] = owner[slot - 1], level[slot - 1]
                slot -= 1
            depth[slot], start[slot], end[slot] = hit_depth, span_start, span_end
            owner[slot], level[slot] = scene_index[prim], shade
            count = min(count + 1, layers)

        row = 0
        while row < height:
            cover = -1
            for layer in range(count):
                if start[layer] <= row < end[layer]:
                    cover = layer
                    break
            if cover >= 0:
                stop, nearer = end[cover], cover
            else:
                stop = first_floor_row if row < first_floor_row else height
                nearer = count
            # A nearer layer that starts further down takes over from there.
            for layer in range(nearer):
                if row < start[layer] < stop and start[layer] < end[layer]:
                    stop = start[layer]
            if cover >= 0:
                color = palette[owner[cover], level[cover]]
            else:
                color = sky if row < first_floor_row else floor
            out[column, row:stop] = color
            row = stop
