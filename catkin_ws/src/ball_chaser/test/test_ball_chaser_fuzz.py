"""Property tests: any sensor_msgs/Image fields either decode to exactly the
bytes they describe or raise ImageFormatError, and detection on a decoded
image always gives a detection inside the frame. Any drive request is refused
with DriveRequestError or applied finite and within the limits.

    HYPOTHESIS_PROFILE=long python -m pytest catkin_ws/src/ball_chaser/test/test_ball_chaser_fuzz.py
"""
import math
import os
import types

import numpy as np
from hypothesis import HealthCheck, event, given, settings, strategies as st

from ball_chaser.detect import CHANNELS, ImageFormatError, find_ball, image_msg_to_array
from ball_chaser.drive_logic import DriveLimits, DriveRequestError, apply_limits
from ball_chaser_frames import encode, rgb_scene

settings.register_profile('fuzz', max_examples=60, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile('long', max_examples=5000, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
FUZZ = settings.get_profile('long' if os.environ.get('HYPOTHESIS_PROFILE') == 'long' else 'fuzz')

ENCODINGS = st.sampled_from(sorted(CHANNELS)) | st.sampled_from(
    ['mono16', '16UC1', 'rgb16', '32FC1', 'bayer_rggb8', 'yuv422', '', 'RGB8']) | st.text(max_size=8)
SIZES = st.one_of(st.integers(1, 24), st.integers(1, 24), st.integers(0, 24), st.sampled_from([2 ** 32 - 1]))
STEPS = st.integers(0, 120) | st.sampled_from([2 ** 32 - 1])


def reference_pixels(height, width, channels, step, data):
    """What the image holds, read row by row without strides."""
    rows = np.frombuffer(bytes(data), np.uint8)[:height * step].reshape(height, step)
    return rows[:, :width * channels].reshape(height, width, channels)


def check_decoding(message):
    """The property: decode exactly, or refuse with ImageFormatError; detection stays in the frame."""
    try:
        image = image_msg_to_array(message)
    except ImageFormatError as error:
        assert str(error)
        event('refused: %s' % type(error).__name__)
        return None
    event('decoded')
    channels = CHANNELS[message.encoding]
    assert image.shape == (message.height, message.width, channels)
    np.testing.assert_array_equal(
        image, reference_pixels(message.height, message.width, channels, message.step, message.data))
    detection = find_ball(image, message.encoding)
    assert 0 <= detection.pixel_count <= message.height * message.width
    if detection.found:
        assert 0 <= detection.left <= detection.centroid_column < detection.left + detection.bounding_width
        assert detection.left + detection.bounding_width <= message.width
        assert 0 <= detection.top <= detection.centroid_row < detection.top + detection.bounding_height
        assert detection.top + detection.bounding_height <= message.height
        assert -1.0 <= detection.horizontal_offset <= 1.0
    return detection


@st.composite
def image_fields(draw):
    """Image fields near the edges of consistency: steps around a row's length, data around height * step."""
    height, width = draw(SIZES), draw(SIZES)
    encoding = draw(st.one_of(st.sampled_from(sorted(CHANNELS)), st.sampled_from(sorted(CHANNELS)), ENCODINGS))
    row_bytes = width * CHANNELS.get(encoding, 1)
    near_a_row = st.integers(max(0, row_bytes - 2), row_bytes + 4)
    step = draw(st.one_of(near_a_row, near_a_row, near_a_row, STEPS))
    needed = height * step
    length = draw(st.integers(max(0, needed - 4), needed + 8) if needed <= 4000 else st.integers(0, 64))
    data = draw(st.binary(min_size=length, max_size=length))
    return types.SimpleNamespace(height=height, width=width, encoding=encoding, step=step, data=data)


@FUZZ
@given(image_fields())
def test_any_image_fields_decode_exactly_or_raise_image_format_error(message):
    check_decoding(message)


@st.composite
def mutated_frame(draw):
    """A real frame with a white ball, then a field changed, data cut or grown, or bytes overwritten."""
    encoding = draw(st.sampled_from(sorted(CHANNELS)))
    width, height = draw(st.integers(1, 40)), draw(st.integers(1, 30))
    centre = (draw(st.integers(-5, width + 5)), draw(st.integers(-5, height + 5)))
    message = encode(rgb_scene(width, height, ball_centre=centre, radius=draw(st.integers(0, 8))),
                     encoding, padding=draw(st.integers(0, 8)))
    data = bytearray(message.data)
    for _ in range(draw(st.integers(0, 3))):
        change = draw(st.sampled_from(['height', 'width', 'step', 'encoding', 'cut', 'grow', 'overwrite']))
        if change in ('height', 'width', 'step'):
            value = getattr(message, change) + draw(st.integers(-3, 3))
            setattr(message, change, draw(st.sampled_from([max(value, 0), 0, 2 ** 32 - 1])))
        elif change == 'encoding':
            message.encoding = draw(ENCODINGS)
        elif change == 'cut':
            del data[draw(st.integers(0, len(data))):]
        elif change == 'grow':
            data.extend(draw(st.binary(min_size=1, max_size=64)))
        else:
            at = draw(st.integers(0, len(data)))
            patch = draw(st.binary(min_size=1, max_size=16))
            data[at:at + len(patch)] = patch
    message.data = draw(st.sampled_from([bytes, bytearray, memoryview]))(data)
    return message


@FUZZ
@given(mutated_frame())
def test_mutated_frames_decode_exactly_or_raise_image_format_error(message):
    check_decoding(message)


def test_an_unmutated_frame_finds_the_ball():
    message = encode(rgb_scene(40, 30, ball_centre=(10, 12), radius=3), 'bgra8', padding=5)
    detection = find_ball(image_msg_to_array(message), 'bgra8')
    assert detection.found and detection.centroid_column == 10.0 and detection.centroid_row == 12.0


VELOCITIES = (st.floats() | st.integers() | st.integers(10 ** 300, 10 ** 400)
              | st.sampled_from(['nan', 'inf', '1e999', '-0', '', 'x', None, b'1', 1j, [0.5]])
              | st.floats(width=32).map(np.float32))
LIMIT_VALUES = st.floats(min_value=1e-6, max_value=1e6)


@FUZZ
@given(VELOCITIES, VELOCITIES, LIMIT_VALUES, LIMIT_VALUES)
def test_any_drive_request_is_refused_or_applied_within_the_limits(linear, angular, max_linear, max_angular):
    limits = DriveLimits(max_linear, max_angular)
    try:
        result = apply_limits(linear, angular, limits)
    except DriveRequestError as error:
        assert str(error).startswith(('linear_x must be', 'angular_z must be'))
        return
    assert math.isfinite(result.linear_x) and math.isfinite(result.angular_z)
    assert abs(result.linear_x) <= max_linear and abs(result.angular_z) <= max_angular
    assert result.feedback.startswith('Velocities applied: ')
    assert result.clamped == ('clamped' in result.feedback)
