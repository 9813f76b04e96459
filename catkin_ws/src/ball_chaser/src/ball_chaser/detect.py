"""Find a ball of one colour in a camera image, without ROS.

image_to_array() reads the fields of a sensor_msgs/Image (height, width,
encoding, step, data) into a numpy view without copying. Rows may be padded:
step is the byte length of a row and may exceed width * channels.

find_ball() marks the pixels whose colour is within a tolerance of the target
colour. The course's rule is the default: a pixel belongs to the ball when all
three channels are exactly 255.
"""
import dataclasses

import cv2
import numpy as np

CHANNELS = {'rgb8': 3, 'bgr8': 3, 'rgba8': 4, 'bgra8': 4, 'mono8': 1}
"""Supported encodings and their channel counts (one byte per channel)."""

WHITE = (255, 255, 255)

# ITU-R BT.601 luma weights: a target colour becomes this grey level in a mono8 image.
_LUMA_WEIGHTS = (0.299, 0.587, 0.114)


class ImageFormatError(ValueError):
    """An image that cannot be read: bad size, step shorter than a row, or too little data."""


class UnsupportedEncodingError(ImageFormatError):
    """An encoding other than those in CHANNELS (16-bit, float, Bayer, YUV...)."""

    def __init__(self, encoding):
        super().__init__('unsupported image encoding %r; supported encodings are %s'
                         % (encoding, ', '.join(sorted(CHANNELS))))
        self.encoding = encoding


def image_to_array(height, width, encoding, step, data):
    """Return a read-only uint8 view of shape (height, width, channels) over data.

    data is bytes-like (bytes, bytearray, memoryview, uint8 array). Padding at
    the end of each row is skipped through the view's strides, not copied.
    Raises UnsupportedEncodingError or ImageFormatError.
    """
    channels = CHANNELS.get(encoding)
    if channels is None:
        raise UnsupportedEncodingError(encoding)
    if height <= 0 or width <= 0:
        raise ImageFormatError('image size must be positive, got %dx%d (width x height)' % (width, height))
    row_bytes = width * channels
    if step < row_bytes:
        raise ImageFormatError('step %d is shorter than a %s row of %d pixels (%d bytes)'
                               % (step, encoding, width, row_bytes))
    try:
        buffer = np.frombuffer(data, dtype=np.uint8)
    except TypeError:
        raise ImageFormatError('image data must be bytes-like, got %s' % type(data).__name__) from None
    needed = height * step
    if buffer.size < needed:
        raise ImageFormatError('image data holds %d bytes, a %dx%d %s image with step %d needs %d'
                               % (buffer.size, width, height, encoding, step, needed))
    view = np.lib.stride_tricks.as_strided(buffer, shape=(height, width, channels),
                                           strides=(step, channels, 1), writeable=False)
    return view


def image_msg_to_array(msg):
    """image_to_array() for any object with sensor_msgs/Image's fields."""
    return image_to_array(msg.height, msg.width, msg.encoding, msg.step, msg.data)


def target_in_encoding(target_rgb, encoding):
    """The target colour as the channel values it has in encoding (alpha left out)."""
    red, green, blue = (int(c) for c in target_rgb)
    if encoding in ('rgb8', 'rgba8'):
        return (red, green, blue)
    if encoding in ('bgr8', 'bgra8'):
        return (blue, green, red)
    if encoding == 'mono8':
        return (int(round(np.dot(_LUMA_WEIGHTS, (red, green, blue)))),)
    raise UnsupportedEncodingError(encoding)


@dataclasses.dataclass(frozen=True)
class BallDetection:
    """Where the target-coloured pixels are in an image.

    Columns and rows are pixel indices from the image's left and top edges.
    When no pixel matched, pixel_count is 0 and the positions are None.
    """

    image_width: int
    image_height: int
    pixel_count: int
    centroid_column: float = None
    centroid_row: float = None
    left: int = None
    top: int = None
    bounding_width: int = 0
    bounding_height: int = 0

    @property
    def found(self):
        return self.pixel_count > 0

    @property
    def area_fraction(self):
        """Matched pixels over all pixels, 0..1."""
        return self.pixel_count / float(self.image_width * self.image_height)

    @property
    def width_fraction(self):
        """Width of the matched pixels' bounding box over the image width, 0..1."""
        return self.bounding_width / float(self.image_width)

    @property
    def horizontal_offset(self):
        """Centroid column relative to the image centre: -1 at the left edge, +1 at the right edge."""
        if not self.found:
            return None
        centre = (self.image_width - 1) / 2.0
        return (self.centroid_column - centre) / (self.image_width / 2.0)

    @property
    def touches_side(self):
        """True when the matched pixels reach the left or right image edge (ball partly out of frame)."""
        return self.found and (self.left == 0 or self.left + self.bounding_width == self.image_width)


def validate_target(target_rgb, tolerance):
    """Check a target colour (three ints 0..255) and tolerance (int 0..255); return them as ints."""
    try:
        values = [int(c) for c in target_rgb]
    except (TypeError, ValueError):
        raise ValueError('target_color must be three integers 0..255, got %r' % (target_rgb,)) from None
    if len(values) != 3 or any(v < 0 or v > 255 or v != c for v, c in zip(values, target_rgb)):
        raise ValueError('target_color must be three integers 0..255, got %r' % (target_rgb,))
    if not isinstance(tolerance, (int, float)) or tolerance != int(tolerance) or not 0 <= tolerance <= 255:
        raise ValueError('color_tolerance must be an integer 0..255, got %r' % (tolerance,))
    return tuple(values), int(tolerance)


def ball_mask(image, encoding, target_rgb=WHITE, tolerance=0):
    """uint8 mask (255 = ball) of the pixels within tolerance of target_rgb in every colour channel."""
    target = target_in_encoding(target_rgb, encoding)
    channels = image.shape[2]
    # Alpha takes any value: the ranges cover it fully.
    lower = [max(0, c - tolerance) for c in target] + [0] * (channels - len(target))
    upper = [min(255, c + tolerance) for c in target] + [255] * (channels - len(target))
    if channels == 1:
        image = image[:, :, 0]
    return cv2.inRange(image, np.array(lower, dtype=np.uint8), np.array(upper, dtype=np.uint8))


def detect_in_mask(mask):
    """BallDetection for a uint8 mask whose non-zero pixels are the ball."""
    height, width = mask.shape
    left, top, box_width, box_height = cv2.boundingRect(mask)
    if box_width == 0:
        return BallDetection(width, height, 0)
    # Sums over the bounding box only: the ball is usually a small part of the frame.
    box = mask[top:top + box_height, left:left + box_width]
    column_counts = box.sum(axis=0, dtype=np.uint32) // 255
    row_counts = box.sum(axis=1, dtype=np.uint32) // 255
    count = int(column_counts.sum())
    centroid_column = left + float(np.dot(column_counts, np.arange(box_width))) / count
    centroid_row = top + float(np.dot(row_counts, np.arange(box_height))) / count
    return BallDetection(width, height, count, centroid_column, centroid_row,
                         left, top, box_width, box_height)


def find_ball(image, encoding, target_rgb=WHITE, tolerance=0, min_pixels=1):
    """BallDetection of the target colour in an image from image_to_array().

    Fewer than min_pixels matching pixels count as no ball.
    """
    detection = detect_in_mask(ball_mask(image, encoding, target_rgb, tolerance))
    if detection.pixel_count < min_pixels:
        return BallDetection(detection.image_width, detection.image_height, 0)
    return detection
