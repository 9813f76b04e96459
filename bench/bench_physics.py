"""Physics steps per second in a course-like world: a walled house, a robot, a ball.

Run with flatsim importable (built workspace or PYTHONPATH=catkin_ws/src/flatsim/src).
Prints figures only.
"""
import math
import time

from flatsim.loading.config import DriveConfig
from flatsim.world.drive import make_drive
from flatsim.world.physics import Physics

FOOTPRINT = [(-0.2, -0.15), (0.2, -0.15), (0.2, 0.15), (-0.2, 0.15)]
STEPS = 20000


def course_world():
    physics = Physics(step=0.002)
    # 60 wall segments around and across a 12 m x 10 m house.
    for i in range(12):
        x = -6.0 + 0.5 + i
        physics.add_static_box(x, 5.0, 0.0, 0.5, 0.075)
        physics.add_static_box(x, -5.0, 0.0, 0.5, 0.075)
    for i in range(10):
        y = -5.0 + 0.5 + i
        physics.add_static_box(6.0, y, 0.0, 0.075, 0.5)
        physics.add_static_box(-6.0, y, 0.0, 0.075, 0.5)
    for i in range(16):
        physics.add_static_box(-4.0 + 0.5 * i, 1.5 * (i % 3) - 1.5, math.pi / 2 * (i % 2), 0.25, 0.075)
    drive = make_drive(DriveConfig(update_rate=10.0, wheel_separation=0.4, wheel_diameter=0.2))
    physics.add_robot('my_robot', FOOTPRINT, 15.0, -5.0, 0.0, 0.0, drive)
    physics.add_ball('ball', -4.0, 0.0, 0.1, 0.5)
    drive.set_command(0.6, 0.3)
    return physics


def main():
    physics = course_world()
    statics = len(physics.space.shapes) - 2
    start = time.perf_counter()
    for _ in range(STEPS):
        physics.step()
    elapsed = time.perf_counter() - start
    print('static boxes: %d' % statics)
    print('steps: %d in %.3f s' % (STEPS, elapsed))
    print('steps per second: %.0f' % (STEPS / elapsed))
    print('real-time factor at 2 ms steps: %.1f' % (STEPS * physics.step_size / elapsed))


if __name__ == '__main__':
    main()
