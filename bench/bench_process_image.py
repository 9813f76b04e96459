"""Time process_image's work per camera frame: decode + detect + control.

Prints the median milliseconds per 800x800 frame (the course camera) for a
few scenes and encodings. The budget is 2 ms per frame, leaving most of a
30 Hz frame period for the simulator. No ROS master needed.

    python bench/bench_process_image.py
"""
import pathlib
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / 'catkin_ws' / 'src' / 'ball_chaser' / 'src'))

from ball_chaser.control import CourseController, ProportionalController  # noqa: E402
from ball_chaser.detect import find_ball, image_msg_to_array  # noqa: E402

SIZE = 800
REPEATS = 200


class Frame:
    """Just the sensor_msgs/Image fields process_image reads."""

    def __init__(self, pixels, encoding):
        self.height, self.width, channels = pixels.shape
        self.encoding = encoding
        self.step = self.width * channels
        self.data = pixels.tobytes()


def scene(ball_radius, channels=3):
    pixels = np.empty((SIZE, SIZE, channels), dtype=np.uint8)
    pixels[:SIZE // 2] = 200
    pixels[SIZE // 2:] = 90
    if ball_radius:
        rows, columns = np.ogrid[0:SIZE, 0:SIZE]
        pixels[(columns - 520) ** 2 + (rows - 420) ** 2 <= ball_radius ** 2] = 255
    return pixels


def median_ms(frame, controller):
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        image = image_msg_to_array(frame)
        controller.command(find_ball(image, frame.encoding))
        times.append(time.perf_counter() - start)
    return 1000.0 * statistics.median(times)


def main():
    cases = [
        ('no ball', 'rgb8', scene(0)),
        ('small ball (r=20 px)', 'rgb8', scene(20)),
        ('near ball (r=200 px)', 'rgb8', scene(200)),
        ('ball fills frame', 'rgb8', np.full((SIZE, SIZE, 3), 255, np.uint8)),
        ('small ball (r=20 px)', 'bgra8', scene(20, channels=4)),
    ]
    print('process_image per-frame cost, %dx%d, median of %d (budget 2 ms)' % (SIZE, SIZE, REPEATS))
    for name, encoding, pixels in cases:
        frame = Frame(pixels, encoding)
        for controller in (ProportionalController(), CourseController()):
            print('  %-22s %-6s %-22s %6.3f ms' % (name, encoding, type(controller).__name__,
                                                    median_ms(frame, controller)))


if __name__ == '__main__':
    main()
