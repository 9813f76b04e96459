"""Image decoding and ball detection on synthetic frames with known ball positions."""
import numpy as np
import pytest

from ball_chaser.detect import (CHANNELS, BallDetection, ImageFormatError, UnsupportedEncodingError,
                                find_ball, image_msg_to_array, image_to_array, validate_target)
from ball_chaser_frames import encode, rgb_scene

ENCODINGS = sorted(CHANNELS)
WIDTH, HEIGHT = 120, 90


def detect(message, target=(255, 255, 255), tolerance=0, min_pixels=1):
    return find_ball(image_msg_to_array(message), message.encoding, target, tolerance, min_pixels)


def disc_pixel_count(radius):
    rows, columns = np.mgrid[-radius:radius + 1, -radius:radius + 1]
    return int(np.count_nonzero(columns ** 2 + rows ** 2 <= radius ** 2))


@pytest.mark.parametrize('encoding', ENCODINGS)
@pytest.mark.parametrize('padding', [0, 3, 64])
def test_decoding_returns_the_pixels_in_the_encodings_channel_order(encoding, padding):
    rgb = rgb_scene(WIDTH, HEIGHT, ball_centre=(30, 20), radius=5)
    rgb[0, 0] = (10, 20, 30)
    message = encode(rgb, encoding, padding=padding, alpha=77)
    image = image_msg_to_array(message)
    assert image.shape == (HEIGHT, WIDTH, CHANNELS[encoding])
    expected_first_pixel = {'rgb8': [10, 20, 30], 'bgr8': [30, 20, 10], 'rgba8': [10, 20, 30, 77],
                            'bgra8': [30, 20, 10, 77], 'mono8': [18]}[encoding]
    assert image[0, 0].tolist() == expected_first_pixel
    last_pixel_alone = encode(rgb[-1:, -1:], encoding, alpha=77)
    assert image[HEIGHT - 1, WIDTH - 1].tolist() == list(last_pixel_alone.data)


def test_decoding_does_not_copy_the_data():
    message = encode(rgb_scene(WIDTH, HEIGHT), 'rgb8', padding=8)
    image = image_msg_to_array(message)
    assert np.shares_memory(image, np.frombuffer(message.data, np.uint8))
    assert not image.flags.writeable


@pytest.mark.parametrize('encoding', ['rgb16', 'mono16', '16UC1', '32FC1', 'bayer_rggb8', 'yuv422', '', 'RGB8'])
def test_unsupported_encoding_is_refused_by_name(encoding):
    with pytest.raises(UnsupportedEncodingError, match='unsupported image encoding %r' % encoding) as caught:
        image_to_array(10, 10, encoding, 60, bytes(600))
    assert caught.value.encoding == encoding
    assert isinstance(caught.value, ImageFormatError)


@pytest.mark.parametrize('height, width, step, size, message', [
    (10, 10, 29, 300, 'step 29 is shorter than a rgb8 row of 10 pixels'),
    (10, 10, 30, 299, 'image data holds 299 bytes'),
    (10, 10, 40, 390, 'needs 400'),
    (0, 10, 30, 0, 'image size must be positive'),
    (10, 0, 30, 300, 'image size must be positive'),
])
def test_malformed_image_is_refused_with_a_clear_message(height, width, step, size, message):
    with pytest.raises(ImageFormatError, match=message):
        image_to_array(height, width, 'rgb8', step, bytes(size))


@pytest.mark.parametrize('encoding', ENCODINGS)
@pytest.mark.parametrize('padding', [0, 5])
@pytest.mark.parametrize('column', [15, 60, 104])
def test_white_ball_is_found_at_its_position_in_every_encoding(encoding, padding, column):
    radius = 8
    message = encode(rgb_scene(WIDTH, HEIGHT, ball_centre=(column, 30), radius=radius), encoding, padding)
    detection = detect(message)
    assert detection.found
    assert detection.pixel_count == disc_pixel_count(radius)
    assert detection.centroid_column == pytest.approx(column)
    assert detection.centroid_row == pytest.approx(30)
    assert (detection.left, detection.top) == (column - radius, 30 - radius)
    assert (detection.bounding_width, detection.bounding_height) == (2 * radius + 1, 2 * radius + 1)
    assert detection.area_fraction == pytest.approx(disc_pixel_count(radius) / (WIDTH * HEIGHT))
    assert detection.width_fraction == pytest.approx((2 * radius + 1) / WIDTH)
    assert not detection.touches_side


@pytest.mark.parametrize('encoding', ENCODINGS)
def test_no_ball_is_found_in_an_empty_room(encoding):
    detection = detect(encode(rgb_scene(WIDTH, HEIGHT), encoding, padding=4))
    assert detection == BallDetection(WIDTH, HEIGHT, 0)
    assert not detection.found
    assert detection.area_fraction == 0
    assert detection.horizontal_offset is None


def test_padding_bytes_are_never_read_as_pixels():
    # encode() fills padding with 255: a reader ignoring step would see a white column.
    message = encode(rgb_scene(WIDTH, HEIGHT), 'rgb8', padding=6)
    assert not detect(message).found


@pytest.mark.parametrize('wall', [(254, 254, 254), (255, 255, 254), (254, 255, 255), (255, 254, 255)])
def test_near_white_walls_are_not_ball(wall):
    message = encode(rgb_scene(WIDTH, HEIGHT, ball_centre=(90, 60), radius=6, wall_rgb=wall), 'rgb8')
    detection = detect(message)
    assert detection.pixel_count == disc_pixel_count(6)
    assert detection.centroid_column == pytest.approx(90)


def test_tolerance_lets_near_white_count_as_ball():
    message = encode(rgb_scene(WIDTH, HEIGHT, wall_rgb=(254, 254, 254)), 'rgb8')
    assert detect(message, tolerance=1).pixel_count == WIDTH * (HEIGHT // 2)
    assert not detect(message, tolerance=0).found


@pytest.mark.parametrize('encoding', ['rgb8', 'bgr8', 'rgba8', 'bgra8'])
def test_red_ball_is_found_with_a_red_target_and_the_white_one_is_not(encoding):
    rgb = rgb_scene(WIDTH, HEIGHT, ball_centre=(20, 30), radius=7, ball_rgb=(255, 0, 0))
    rgb[40:50, 90:100] = 255
    message = encode(rgb, encoding)
    red = detect(message, target=(255, 0, 0))
    assert red.pixel_count == disc_pixel_count(7)
    assert red.centroid_column == pytest.approx(20)
    white = detect(message)
    assert white.pixel_count == 100
    assert white.centroid_column == pytest.approx(94.5)


def test_blue_ball_is_not_mistaken_for_red_in_bgr8():
    rgb = rgb_scene(WIDTH, HEIGHT, ball_centre=(20, 30), radius=7, ball_rgb=(0, 0, 255))
    assert not detect(encode(rgb, 'bgr8'), target=(255, 0, 0)).found


@pytest.mark.parametrize('column, visible_left, visible_width', [(-4, 0, 5), (WIDTH + 3, WIDTH - 5, 5)])
def test_ball_partly_out_of_frame_is_found_touching_the_side(column, visible_left, visible_width):
    message = encode(rgb_scene(WIDTH, HEIGHT, ball_centre=(column, 30), radius=8), 'rgb8')
    detection = detect(message)
    assert detection.found
    assert detection.touches_side
    assert (detection.left, detection.bounding_width) == (visible_left, visible_width)
    assert visible_left <= detection.centroid_column < visible_left + visible_width


def test_ball_filling_the_frame_is_all_pixels():
    message = encode(np.full((HEIGHT, WIDTH, 3), 255, np.uint8), 'rgb8')
    detection = detect(message)
    assert detection.pixel_count == WIDTH * HEIGHT
    assert detection.area_fraction == 1.0
    assert detection.width_fraction == 1.0
    assert detection.centroid_column == pytest.approx((WIDTH - 1) / 2)
    assert detection.horizontal_offset == pytest.approx(0.0)


def test_horizontal_offset_spans_minus_one_to_one_across_the_image():
    assert BallDetection(100, 10, 1, centroid_column=-0.5).horizontal_offset == pytest.approx(-1.0)
    assert BallDetection(100, 10, 1, centroid_column=49.5).horizontal_offset == pytest.approx(0.0)
    assert BallDetection(100, 10, 1, centroid_column=99.5).horizontal_offset == pytest.approx(1.0)


def test_fewer_pixels_than_min_pixels_is_no_ball():
    rgb = rgb_scene(WIDTH, HEIGHT)
    rgb[5, 5] = rgb[6, 7] = 255
    message = encode(rgb, 'rgb8')
    assert detect(message, min_pixels=2).pixel_count == 2
    assert not detect(message, min_pixels=3).found


def test_mono8_finds_a_white_ball_among_grey_walls():
    message = encode(rgb_scene(WIDTH, HEIGHT, ball_centre=(60, 20), radius=5), 'mono8')
    detection = detect(message)
    assert detection.pixel_count == disc_pixel_count(5)
    assert detection.centroid_column == pytest.approx(60)


def test_target_settings_from_yaml_are_accepted_as_integers():
    assert validate_target([255, 0.0, 10], 3.0) == ((255, 0, 10), 3)


@pytest.mark.parametrize('target, tolerance, name', [
    ([255, 255], 0, 'target_color'), ([256, 0, 0], 0, 'target_color'), ([1.5, 0, 0], 0, 'target_color'),
    ('white', 0, 'target_color'), ([255, 255, 255], -1, 'color_tolerance'),
    ([255, 255, 255], 2.5, 'color_tolerance'), ([255, 255, 255], 'any', 'color_tolerance'),
])
def test_bad_target_settings_are_refused_by_name(target, tolerance, name):
    with pytest.raises(ValueError, match=name):
        validate_target(target, tolerance)
