"""Median time per camera render and per laser scan on a representative world.

The world is a walled 10 x 10 m room with furniture-like boxes (some
floating, like table tops), a few cylinders and the white ball: 60 boxes in
all. Figures are printed twice: with glibc's default allocator settings, then
after flatsim.sensors.camera.keep_freed_memory(), which the simulator calls at start-up.
Wall-clock medians suffer when other processes share the cores, so the CPU
time median is printed too. Nothing here asserts on time.

    python bench/bench_sensors.py [--repeat N]
"""
import argparse
import math
import os
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..',
                                'catkin_ws', 'src', 'flatsim', 'src'))

from flatsim.loading.config import CameraConfig, LaserConfig  # noqa: E402
from flatsim.sensors.camera import PinholeCamera, keep_freed_memory  # noqa: E402
from flatsim.sensors.lidar import Lidar  # noqa: E402
from flatsim.world.scene import Prim, Scene  # noqa: E402


def representative_world(seed=1):
    rng = np.random.default_rng(seed)
    prims = []
    for i, (x, y, yaw, length) in enumerate([(0, 5, 0, 10.2), (0, -5, 0, 10.2),
                                             (5, 0, math.pi / 2, 10.2),
                                             (-5, 0, math.pi / 2, 10.2)]):
        prims.append(Prim.box('outer_%d' % i, x, y, yaw, length, 0.15, 0.0, 2.5,
                              color=tuple(rng.uniform(0.2, 1.0, 3))))
    while len(prims) < 60:
        x, y = rng.uniform(-4.5, 4.5, 2)
        if math.hypot(x, y) < 1.0:
            continue
        low = rng.choice([0.0, 0.0, 0.0, 0.7])
        prims.append(Prim.box('box_%d' % len(prims), x, y, rng.uniform(-math.pi, math.pi),
                              rng.uniform(0.1, 2.5), rng.uniform(0.1, 0.6), low,
                              low + rng.uniform(0.05, 1.5),
                              color=tuple(rng.uniform(0.0, 1.0, 3))))
    for i in range(4):
        x, y = rng.uniform(-4, 4, 2)
        prims.append(Prim.cylinder('cylinder_%d' % i, x, y, rng.uniform(0.1, 0.4), 0.0,
                                   rng.uniform(0.3, 2.0), color=tuple(rng.uniform(0, 1, 3))))
    prims.append(Prim.sphere('ball', 1.5, 0.2, 0.1, 0.1, color=(1.0, 1.0, 1.0),
                             unlit_white=True))
    return Scene(prims)


def median_ms(action, repeat):
    """Median wall-clock and CPU milliseconds per call."""
    for _ in range(3):
        action()
    wall, cpu = [], []
    for _ in range(repeat):
        began, began_cpu = time.perf_counter(), time.process_time()
        action()
        wall.append(time.perf_counter() - began)
        cpu.append(time.process_time() - began_cpu)
    return 1000.0 * float(np.median(wall)), 1000.0 * float(np.median(cpu))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--repeat', type=int, default=200)
    args = parser.parse_args()
    scene = representative_world()
    camera = PinholeCamera(CameraConfig(width=800, height=800, hfov=1.3962634,
                                        image_format='R8G8B8'))
    lidar = Lidar(LaserConfig(samples=720, min_angle=-math.pi / 2, max_angle=math.pi / 2,
                              range_min=0.1, range_max=30.0, noise_stddev=0.01))
    poses = [(0.0, 0.0, 0.1 * k) for k in range(16)]
    state = {'k': 0}

    def next_pose():
        state['k'] = (state['k'] + 1) % len(poses)
        return poses[state['k']]

    def render():
        x, y, yaw = next_pose()
        camera.render(scene, x, y, 0.35, yaw)

    def scan():
        x, y, yaw = next_pose()
        lidar.scan(scene, x, y, 0.3, yaw)

    print('scene: %d primitives' % len(scene))
    for allocator in ('default allocator', 'keep_freed_memory'):
        if allocator == 'keep_freed_memory' and not keep_freed_memory():
            print('keep_freed_memory: not available with this C library')
            break
        print('%s:' % allocator)
        print('  camera 800x800 rgb8: median %.2f ms per render (cpu %.2f ms)'
              % median_ms(render, args.repeat))
        print('  lidar 720 beams: median %.3f ms per scan (cpu %.3f ms)'
              % median_ms(scan, args.repeat))


if __name__ == '__main__':
    main()
