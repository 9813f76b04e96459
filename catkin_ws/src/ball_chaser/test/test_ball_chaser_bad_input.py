"""Bad drive requests and bad camera images: each is refused with an error
that says what is wrong, or applied within the limits; never anything else."""
import math
import types

import numpy as np
import pytest

from ball_chaser.detect import (ImageFormatError, UnsupportedEncodingError, find_ball, image_msg_to_array)
from ball_chaser.drive_logic import DriveLimits, DriveRequestError, apply_limits
from ball_chaser_frames import encode, rgb_scene

LIMITS = DriveLimits(max_linear_x=1.0, max_angular_z=2.0)


# Drive requests --------------------------------------------------------------------

@pytest.mark.parametrize('value, shown', [
    (math.nan, 'nan'), (math.inf, 'inf'), (-math.inf, '-inf'), (float('1e999'), 'inf'),
    (np.float64('nan'), 'nan'), (np.float32('inf'), 'inf'), ('nan', 'nan'),
])
@pytest.mark.parametrize('field', ['linear_x', 'angular_z'])
def test_non_finite_requests_are_refused_naming_the_field_and_the_value(field, value, shown):
    request = {'linear_x': 0.1, 'angular_z': 0.1, field: value}
    with pytest.raises(DriveRequestError) as caught:
        apply_limits(request['linear_x'], request['angular_z'], LIMITS)
    assert str(caught.value) == '%s must be a finite number, got %s; nothing was published' % (field, shown)


@pytest.mark.parametrize('field', ['linear_x', 'angular_z'])
def test_an_integer_too_large_for_a_float_is_refused(field):
    request = {'linear_x': 0.0, 'angular_z': 0.0, field: 10 ** 400}
    with pytest.raises(DriveRequestError, match='%s must be a finite number, got an integer too large'
                       % field):
        apply_limits(request['linear_x'], request['angular_z'], LIMITS)


@pytest.mark.parametrize('value', [None, 'fast', b'\xff', [1.0], 1j])
def test_non_numbers_are_refused(value):
    with pytest.raises(DriveRequestError, match='angular_z must be a number, got'):
        apply_limits(0.0, value, LIMITS)


@pytest.mark.parametrize('linear, angular, expected_linear, expected_angular', [
    (1e308, 0.0, 1.0, 0.0),
    (-1e308, 0.0, -1.0, 0.0),
    (0.0, 1e308, 0.0, 2.0),
    (0.0, -1e308, 0.0, -2.0),
    (np.finfo(np.float64).max, -np.finfo(np.float64).max, 1.0, -2.0),
    (1e30, 1e30, 1.0, 2.0),
    (2 ** 64, -2 ** 64, 1.0, -2.0),
])
def test_huge_requests_are_clamped_and_the_feedback_says_so(linear, angular, expected_linear,
                                                            expected_angular):
    result = apply_limits(linear, angular, LIMITS)
    assert (result.linear_x, result.angular_z) == (expected_linear, expected_angular)
    assert result.clamped
    assert result.feedback.startswith('Velocities applied: linear_x=%g m/s, angular_z=%g rad/s ('
                                      % (expected_linear, expected_angular))
    assert 'clamped to max_' in result.feedback


def test_negative_zero_is_applied_as_zero():
    result = apply_limits(-0.0, -0.0, LIMITS)
    assert (result.linear_x, result.angular_z) == (0.0, 0.0)
    assert math.copysign(1.0, result.linear_x) == 1.0 and math.copysign(1.0, result.angular_z) == 1.0
    assert result.feedback == 'Velocities applied: linear_x=0 m/s, angular_z=0 rad/s'
    assert not result.clamped


def test_the_smallest_subnormal_is_applied_unchanged():
    result = apply_limits(5e-324, -5e-324, LIMITS)
    assert (result.linear_x, result.angular_z) == (5e-324, -5e-324)
    assert not result.clamped


# Camera images ---------------------------------------------------------------------

WIDTH, HEIGHT = 40, 30


def good_frame(encoding='rgb8', padding=0):
    return encode(rgb_scene(WIDTH, HEIGHT, ball_centre=(20, 10), radius=4), encoding, padding)


def altered(message, **fields):
    values = dict(vars(message))
    values.update(fields)
    return types.SimpleNamespace(**values)


def test_the_good_frame_shows_the_ball():
    image = image_msg_to_array(good_frame())
    assert find_ball(image, 'rgb8').centroid_column == pytest.approx(20.0)


@pytest.mark.parametrize('encoding, channels', [('rgb8', 3), ('rgba8', 4), ('mono8', 1)])
@pytest.mark.parametrize('shortfall', [1, WIDTH])
def test_step_shorter_than_a_row_is_refused(encoding, channels, shortfall):
    step = WIDTH * channels - shortfall
    message = altered(good_frame(encoding), step=step)
    with pytest.raises(ImageFormatError) as caught:
        image_msg_to_array(message)
    assert str(caught.value) == ('step %d is shorter than a %s row of %d pixels (%d bytes)'
                                 % (step, encoding, WIDTH, WIDTH * channels))


@pytest.mark.parametrize('missing', [1, WIDTH * 3, WIDTH * HEIGHT * 3])
def test_data_shorter_than_height_times_step_is_refused(missing):
    message = good_frame()
    message.data = message.data[:len(message.data) - missing]
    with pytest.raises(ImageFormatError) as caught:
        image_msg_to_array(message)
    assert str(caught.value) == ('image data holds %d bytes, a %dx%d rgb8 image with step %d needs %d'
                                 % (len(message.data), WIDTH, HEIGHT, WIDTH * 3, WIDTH * HEIGHT * 3))


def test_padding_that_is_missing_from_the_last_row_is_refused():
    message = good_frame(padding=4)
    message.data = message.data[:-4]
    with pytest.raises(ImageFormatError, match='needs %d' % (HEIGHT * (WIDTH * 3 + 4))):
        image_msg_to_array(message)


@pytest.mark.parametrize('height, width', [(0, WIDTH), (HEIGHT, 0), (0, 0)])
def test_zero_width_or_height_is_refused(height, width):
    message = altered(good_frame(), height=height, width=width)
    with pytest.raises(ImageFormatError) as caught:
        image_msg_to_array(message)
    assert str(caught.value) == 'image size must be positive, got %dx%d (width x height)' % (width, height)


@pytest.mark.parametrize('encoding', ['mono16', '16UC1', 'rgb16', 'rgba16', 'bgr16', 'bgra16', '16SC1',
                                      '32FC1', 'bayer_rggb8', 'yuv422', 'jpeg', 'RGB8', '', 'rgb8 '])
def test_unknown_and_16_bit_encodings_are_refused_by_name(encoding):
    message = altered(good_frame(), encoding=encoding)
    with pytest.raises(UnsupportedEncodingError) as caught:
        image_msg_to_array(message)
    assert caught.value.encoding == encoding
    assert str(caught.value) == ("unsupported image encoding %r; supported encodings are "
                                 "bgr8, bgra8, mono8, rgb8, rgba8" % encoding)


def test_a_16_bit_frame_with_a_consistent_step_is_still_refused():
    mono16 = np.full((HEIGHT, WIDTH), 65535, dtype='<u2')
    message = types.SimpleNamespace(height=HEIGHT, width=WIDTH, encoding='mono16', step=WIDTH * 2,
                                    data=mono16.tobytes())
    with pytest.raises(UnsupportedEncodingError, match="'mono16'"):
        image_msg_to_array(message)


@pytest.mark.parametrize('data', ['a' * (WIDTH * HEIGHT * 3), list(range(3)), None, 12])
def test_data_that_is_not_bytes_is_refused(data):
    message = altered(good_frame(), data=data)
    with pytest.raises(ImageFormatError, match='image data must be bytes-like, got %s' % type(data).__name__):
        image_msg_to_array(message)
