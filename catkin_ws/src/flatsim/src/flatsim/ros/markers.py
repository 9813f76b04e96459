"""The world as rviz markers: one marker per visual primitive of the scene.

Each visual primitive becomes a CUBE, CYLINDER or SPHERE with its real
footprint, height span and colour. A marker's id is the primitive's scene
index, which never shifts (Scene.remove only marks a slot dead), so a
republished marker replaces the one rviz already shows.

The markers are given in the world frame. flatsim's odometry is ground
truth (odometrySource world, as gazebo_ros's diff drive reports the model's
world pose), so the world frame coincides with the drive's odom frame and
rviz with fixed frame odom shows the markers where the robot sees them.

build_specs() is plain Python; marker_array_msg() only builds messages
(visualization_msgs imports without a master).
"""
from dataclasses import dataclass
from typing import Tuple

import numpy as np
from geometry_msgs.msg import Point, Vector3
from std_msgs.msg import ColorRGBA
from visualization_msgs.msg import Marker, MarkerArray

from flatsim.ros.messages import quaternion_from_rpy
from flatsim.world.scene import BOX, CYLINDER, SPHERE

NAMESPACE = 'flatsim_world'
SHAPES = {BOX: 'cube', CYLINDER: 'cylinder', SPHERE: 'sphere'}
MARKER_TYPES = {'cube': Marker.CUBE, 'cylinder': Marker.CYLINDER, 'sphere': Marker.SPHERE}
# rviz refuses markers with a zero scale; a flat visual gets this thickness.
MIN_THICKNESS = 0.001


@dataclass(frozen=True)
class MarkerSpec:
    """One marker: centre (x, y, z), yaw about z, full sizes, RGBA colour in 0..1."""
    id: int
    name: str
    shape: str                                  # 'cube' | 'cylinder' | 'sphere'
    x: float
    y: float
    z: float
    yaw: float
    size: Tuple[float, float, float]
    color: Tuple[float, float, float, float]


def build_specs(scene, indices=None):
    """Marker specs for the live visual primitives of scene (or just those in indices)."""
    visual = scene.select(visual=True)
    if indices is not None:
        visual = np.intersect1d(visual, np.asarray(list(indices), dtype=int))
    specs = []
    for index in visual:
        index = int(index)
        shape = SHAPES[int(scene.kind[index])]
        z_min, z_max = float(scene.z_min[index]), float(scene.z_max[index])
        height = max(z_max - z_min, MIN_THICKNESS)
        if shape == 'cube':
            size = (2 * float(scene.half_x[index]), 2 * float(scene.half_y[index]), height)
        else:
            diameter = 2 * float(scene.radius[index])
            size = (diameter, diameter, height if shape == 'cylinder' else diameter)
        red, green, blue = (float(c) for c in scene.color[index])
        specs.append(MarkerSpec(index, scene.names[index], shape, float(scene.x[index]),
                                float(scene.y[index]), (z_min + z_max) / 2.0,
                                float(scene.yaw[index]), size, (red, green, blue, 1.0)))
    return specs


def marker_array_msg(specs, frame_id, clear_first=False):
    """A MarkerArray adding (or replacing) each spec; clear_first prepends DELETEALL.

    DELETEALL removes markers of models deleted since the last array. Stamps
    stay zero, which rviz reads as "the latest transform": the array is
    latched, and a late subscriber must not look up a transform at an old time.
    """
    array = MarkerArray()
    if clear_first:
        clear = Marker(action=Marker.DELETEALL, ns=NAMESPACE)
        clear.header.frame_id = frame_id
        array.markers.append(clear)
    for spec in specs:
        marker = Marker(ns=NAMESPACE, id=spec.id, type=MARKER_TYPES[spec.shape],
                        action=Marker.ADD, frame_locked=False)
        marker.header.frame_id = frame_id
        marker.pose.position = Point(spec.x, spec.y, spec.z)
        marker.pose.orientation = quaternion_from_rpy(0.0, 0.0, spec.yaw)
        marker.scale = Vector3(*spec.size)
        marker.color = ColorRGBA(*spec.color)
        array.markers.append(marker)
    return array
