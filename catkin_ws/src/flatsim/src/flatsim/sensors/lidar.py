"""A planar laser scanner with the semantics of Gazebo's ray sensor and gazebo_ros_laser.

Beam i points at min_angle + i * (max_angle - min_angle) / (samples - 1),
relative to the sensor's yaw. It sees the collision primitives whose height
span contains the sensor height; for a sphere that is the circle cut at that
height.

Range conventions, as Gazebo 11's RaySensor applies them (REP 117):
- no return, or a return at or beyond range_max: +inf;
- a return at or nearer than range_min: -inf (REP 117's "too close to
  measure");
- otherwise the true range plus gaussian noise (mean, stddev), clamped to
  [range_min, range_max].
<range><resolution> is not applied: Gazebo reads it but never quantises the
ranges, so flatsim does not either.
"""
import math

import numpy as np

from flatsim.errors import FlatsimError
from flatsim.sensors.raycast import nearest
from flatsim.world.scene import SPHERE


def beam_angles(config):
    """The beam angles relative to the sensor, as gazebo_ros_laser reports them."""
    if config.samples == 1:
        return np.array([config.min_angle])
    return config.min_angle + np.arange(config.samples) * angle_increment(config)


def angle_increment(config):
    if config.samples == 1:
        return 0.0
    return (config.max_angle - config.min_angle) / (config.samples - 1)


def scan_msg_fields(config):
    """The sensor_msgs/LaserScan header-free fields a scan from this config carries."""
    return {
        'angle_min': float(config.min_angle),
        'angle_max': float(config.max_angle),
        'angle_increment': float(angle_increment(config)),
        'range_min': float(config.range_min),
        'range_max': float(config.range_max),
    }


class Lidar:
    def __init__(self, config, seed=0):
        if int(config.samples) != config.samples or config.samples < 1:
            raise FlatsimError('laser %r: samples must be a positive integer, got %r'
                               % (config.sensor_name, config.samples))
        if not 0.0 <= config.range_min < config.range_max or not math.isfinite(
                config.range_max):
            raise FlatsimError('laser %r: needs 0 <= range min < range max, got %r and %r'
                               % (config.sensor_name, config.range_min, config.range_max))
        if config.noise_stddev < 0:
            raise FlatsimError('laser %r: noise stddev %r is negative'
                               % (config.sensor_name, config.noise_stddev))
        self.config = config
        self.angles = beam_angles(config)
        self._cos = np.cos(self.angles)
        self._sin = np.sin(self.angles)
        self._rng = np.random.default_rng(seed)

    def scan(self, scene, x, y, z, yaw, exclude=None):
        """Ranges (float32, one per beam) from a sensor at (x, y, z) facing yaw.

        exclude: scene indices (or a mask) the beams pass through, such as the
        robot's own shapes.
        """
        config = self.config
        prims = scene.select(collision=True, height=z, near=(x, y, config.range_max),
                             exclude=exclude)
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        cos_rays = self._cos * cos_yaw - self._sin * sin_yaw
        sin_rays = self._sin * cos_yaw + self._cos * sin_yaw
        radius = scene.radius[prims].copy()
        spheres = scene.kind[prims] == SPHERE
        if spheres.any():
            centre_z = 0.5 * (scene.z_min[prims[spheres]] + scene.z_max[prims[spheres]])
            radius[spheres] = np.sqrt(np.maximum(radius[spheres] ** 2 - (z - centre_z) ** 2,
                                                 0.0))
        distance, _ = nearest(scene, x, y, cos_rays, sin_rays, prims, radius)
        # Draw noise for every beam so a seed gives the same sequence whatever is hit.
        noise = self._rng.normal(config.noise_mean, config.noise_stddev, distance.size) \
            if config.noise_stddev > 0 else np.full(distance.size, config.noise_mean)
        ranges = np.clip(distance + noise, config.range_min, config.range_max)
        ranges[distance >= config.range_max] = np.inf
        ranges[distance <= config.range_min] = -np.inf
        return ranges.astype(np.float32)
