"""The studio's chase view counts the ball pixels by third as the project's process_image does.

flatsim.studio.chase holds the course's rule itself (the project's ball_chaser is not there in
student mode); here it meets ball_chaser's own functions: find_ball and ball_mask (which pixels
are the ball) and CourseController (which third a column is in), on made-up images and on the
course robot's camera image of the white ball.
"""
import pathlib

import numpy as np
import pytest

from ball_chaser.control import CourseController
from ball_chaser.detect import BallDetection, ball_mask, find_ball, image_to_array
from flatsim.loading.sdf_world import load_world
from flatsim.loading.urdf_robot import expand_xacro, load_robot
from flatsim.pose import Pose
from flatsim.studio import chase
from flatsim.studio.world import find_sensor
from flatsim.world.sim import Simulation

MY_ROBOT = pathlib.Path(__file__).resolve().parents[1] / 'catkin_ws' / 'src' / 'my_robot'
CONTROLLER = CourseController()


def process_image_counts(pixels, encoding='rgb8'):
    """Ball pixels per third by ball_chaser's functions: ball_mask for the pixels, and the
    course controller's answer for a ball whose mean column is each pixel's column."""
    height, width = pixels.shape[:2]
    mask = ball_mask(pixels if pixels.ndim == 3 else pixels[:, :, None], encoding)
    counts = [0, 0, 0]
    for column, count in enumerate(mask.sum(axis=0, dtype=np.int64) // 255):
        if count:
            command = CONTROLLER.command(BallDetection(width, height, 1, centroid_column=column))
            third = 0 if command.angular_z > 0 else 1 if command.linear_x > 0 else 2
            counts[third] += int(count)
    return counts


def flatsim_counts(pixels):
    return list(chase.counts_by_third(chase.ball_pixels(pixels)))


@pytest.mark.parametrize('width', [800, 640, 300, 301, 302, 64, 3, 1])
def test_made_up_images_count_alike(width):
    rng = np.random.default_rng(width)
    pixels = rng.choice(np.array([0, 128, 254, 255], dtype=np.uint8), size=(20, width, 3),
                        p=[0.1, 0.1, 0.2, 0.6])
    # Whole columns of white on the thirds' edges, where an off-by-one would show.
    for column in {width // 3, -(-width // 3), 2 * width // 3, -(-2 * width // 3)}:
        if column < width:
            pixels[:, column] = 255
    counts = flatsim_counts(pixels)
    assert counts == process_image_counts(pixels)
    assert sum(counts) == find_ball(pixels, 'rgb8').pixel_count
    mono = pixels[:, :, 0].copy()
    assert flatsim_counts(mono) == process_image_counts(mono, 'mono8')


def test_the_course_robot_sees_the_white_ball_alike():
    sim = Simulation(load_world(str(MY_ROBOT / 'worlds' / 'chase_house.world')))
    spec = load_robot(expand_xacro(str(MY_ROBOT / 'urdf' / 'my_robot.xacro')), name='my_robot')
    sim.spawn_robot('my_robot', spec, Pose(0.0, 0.0))
    # The ball ahead and to the left, over the line between the left and middle thirds.
    sim.set_model_state('white_ball', Pose(1.2, 0.3, 0.1))
    slot = find_sensor(sim, 'my_robot::camera1', 'camera')
    pixels = sim.sense(slot)
    data = np.ascontiguousarray(pixels).tobytes()
    image = image_to_array(pixels.shape[0], pixels.shape[1], 'rgb8', pixels.shape[1] * 3, data)
    counts = flatsim_counts(pixels)
    assert counts[0] > 0 and counts[1] > 0
    assert counts == process_image_counts(image)
    assert sum(counts) == find_ball(image, 'rgb8').pixel_count
