"""Compile the sensors' numba kernels (and the mesh reader's) into their on-disk cache:
python -m flatsim.sensors.precompile

setup.sh runs this once, so that the first simulator start on a machine does
not spend seconds compiling before its first camera frame; the simulator
calls compile_kernels() at start-up too, to load them before its clock runs.
The calls go through the same code paths, with the same argument types, as
the simulator's.
"""
import numpy as np

from flatsim.loading import meshes
from flatsim.loading.config import CameraConfig, LaserConfig
from flatsim.sensors import camera, raster, raycast
from flatsim.sensors.camera import ENCODINGS, PinholeCamera
from flatsim.sensors.lidar import Lidar
from flatsim.world.scene import Prim, Scene


def kernels():
    return (camera._render_columns, raster.render_tilted, raycast._nearest, meshes.piece_finder())


def compile_kernels():
    """Load (or compile and cache) every sensor kernel; returns how many were compiled."""
    scene = Scene([Prim.box('wall', 2.0, 0.0, 0.0, 0.2, 2.0, 0.0, 1.0),
                   Prim.cylinder('post', 2.0, 1.0, 0.1, 0.0, 1.0),
                   Prim.sphere('ball', 1.0, 0.0, 0.1, 0.1, unlit_white=True)])
    for image_format in ENCODINGS:
        cam = PinholeCamera(CameraConfig(width=4, height=4, image_format=image_format))
        cam.render(scene, 0.0, 0.0, 0.2, 0.0)
        cam.render(scene, 0.0, 0.0, 0.2, 0.0, pitch=0.5)
    Lidar(LaserConfig(samples=4, min_angle=-1.0, max_angle=1.0, range_max=10.0)).scan(
        scene, 0.0, 0.0, 0.1, 0.0)
    # The mesh reader's piece finder, as a mesh of one triangle calls it.
    meshes.cover(np.eye(3), np.array([[0, 1, 2]]))
    return sum(sum(kernel.stats.cache_misses.values()) for kernel in kernels())


def main():
    compiled = compile_kernels()
    # setup.sh prints this as its step's outcome.
    print('    sensor kernels cached and unchanged, skipping' if compiled == 0
          else '    compiled %d sensor kernels' % compiled)


if __name__ == '__main__':
    main()
