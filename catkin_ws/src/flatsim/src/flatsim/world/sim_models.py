"""What the simulation keeps of each model: where it came from (ModelOrigin, for Save World
As), the model itself (SimModel, SimRobot) and a robot's sensor schedules (SensorSlot).
No ROS here."""
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import List

from flatsim.authoring.sdf_text import element_depth
from flatsim.pose import Pose

# Where a model came from (ModelOrigin.kind).
FROM_WORLD = 'world'        # the world file
FROM_SDF = 'sdf'            # spawned as SDF (spawn_sdf_model, spawn_model -sdf)
FROM_URDF = 'urdf'          # a robot spawned from URDF (world.launch's robot)
FROM_INSERT = 'insert'      # dropped into the world from the studio's Insert tab
# A model nested deeper than this is kept without its text (Save World As leaves it out).
# ElementTree writes recursively, a Python call per level: writing thousands of levels would
# run Python into its recursion limit, and a garbage collection there frees pymunk's bodies
# without the callbacks that first take them out of their space (a crash, not an error).
MAX_WRITTEN_DEPTH = 300


@dataclass(frozen=True)
class ModelOrigin:
    """Where a model in the simulation came from, so that Save World As can write it back."""
    kind: str                      # FROM_WORLD | FROM_SDF | FROM_URDF | FROM_INSERT
    sdf: str = ''                  # its SDF <model> element as XML text; '' for a robot from URDF


def model_origin(kind, element=None):
    """A ModelOrigin holding element (an ElementTree <model>) as text, without its tail.

    A model nested deeper than MAX_WRITTEN_DEPTH keeps no text; Save World As then says it
    left the model out.
    """
    if element is None or element_depth(element) > MAX_WRITTEN_DEPTH:
        return ModelOrigin(kind)
    tail, element.tail = element.tail, None
    try:
        return ModelOrigin(kind, ET.tostring(element, encoding='unicode'))
    finally:
        element.tail = tail


@dataclass
class SensorSlot:
    """A sensor on a robot with its own update schedule in sim time."""
    kind: str                      # 'camera' | 'laser'
    config: object                 # CameraConfig | LaserConfig
    robot: 'SimRobot'
    impl: object                   # PinholeCamera | Lidar
    mount: Pose                    # sensor pose in the robot's root link frame
    period: float                  # s; 0 means every physics step
    next_due: float = 0.0


@dataclass
class SimModel:
    name: str
    kind: str                      # 'static' | 'ball' | 'body' | 'robot'
    initial_pose: Pose
    handle: object = None          # physics handle for moving models
    prim_ids: List[int] = field(default_factory=list)
    z: float = 0.0                 # height of the model origin above the floor
    # (x, y, yaw) of each prim in the model frame, for models that move.
    prim_offsets: List[tuple] = field(default_factory=list)
    colliders: List[object] = field(default_factory=list)  # static physics shapes
    source: object = None          # the world file's model record (flatsim.loading.sdf_world.Model)
    saved: bool = False            # a robot saved in the world file: a spawned robot replaces it
    pose: Pose = None              # where a model without a body stands now (moved by hand)
    # (z_min, z_max) of each prim of a moving model, standing on the floor.
    prim_heights: List[tuple] = field(default_factory=list)
    ground: List[object] = field(default_factory=list)    # its collision prims that are ground
    held: str = ''                 # why flatsim holds this dynamic model still, '' when it does not


@dataclass
class SimRobot(SimModel):
    spec: object = None            # flatsim.loading.config.RobotSpec
    drive: object = None
    control: object = None         # flatsim.world.robot_control.RobotControl (ros_control robots)
    sensors: List[SensorSlot] = field(default_factory=list)

