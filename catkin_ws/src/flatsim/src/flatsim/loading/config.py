"""What the robot's <gazebo> plugin tags configure, with gazebo_ros noetic defaults.

The URDF loader fills these; physics, drive and sensors only read them.
Topic fields hold the names as gazebo_ros resolves them (relative names stay
relative to the robot's namespace, which is '' for the course robots).
"""
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

from flatsim.pose import Pose


@dataclass
class Wheel:
    """Where a driven wheel touches the ground and which way its joint rolls the robot.

    All in the robot's base (root link) frame, from the URDF's joint chain: the
    joint's position, and the ground velocity its wheel centre gets per rad/s of
    joint rate (the wheel radius times the joint axis crossed with the vertical).
    """
    joint: str
    x: float = 0.0                             # m
    y: float = 0.0                             # m
    roll_x: float = 1.0                        # m per rad of joint rotation
    roll_y: float = 0.0
    radius: float = 0.0                        # m: the wheel's own collision radius
    z: float = 0.0                             # m, the wheel centre's height in the base frame


@dataclass
class Steering:
    """The tricycle drive's steering joint: a pivot about a (nearly) vertical axis."""
    joint: str
    x: float = 0.0                             # m, pivot position in the base frame
    y: float = 0.0
    sense: float = 1.0                         # +1: a positive angle turns the wheel anticlockwise seen from above


@dataclass
class DriveConfig:
    """A drive plugin: diff drive (two joints), skid steer (four), planar move (none) or tricycle."""
    plugin: str = 'diff_drive'                 # 'diff_drive' | 'skid_steer' | 'planar_move' | 'tricycle'
    command_topic: str = 'cmd_vel'
    odometry_topic: str = 'odom'
    odometry_frame: str = 'odom'
    robot_base_frame: str = 'base_footprint'
    left_joints: List[str] = field(default_factory=lambda: ['left_joint'])
    right_joints: List[str] = field(default_factory=lambda: ['right_joint'])
    wheel_separation: float = 0.34             # m
    wheel_diameter: float = 0.15               # m
    wheel_acceleration: float = 0.0            # m/s^2 at the wheel rim; 0 means no ramp
    wheel_torque: float = 5.0                  # N*m per wheel
    update_rate: float = 100.0                 # Hz; 0 means every physics step
    odometry_source: str = 'world'             # 'world' | 'encoder'
    publish_odometry: bool = True              # diff drive <publishTf>: false means no odom topic and no TF
    publish_tf: bool = True                    # odom -> robot_base_frame
    publish_wheel_tf: bool = False
    publish_wheel_joint_state: bool = False
    # Odometry pose covariance of x, y, yaw: fixed in diff drive, <covariance_*> in skid steer
    # (which also puts them on the twist).
    covariance: Tuple[float, float, float] = (0.00001, 0.00001, 0.001)
    tf_prefix: str = ''                        # diff drive prefixes wheel frames with it (publishWheelTF)
    # The driven wheels as the URDF places them, left joints first; empty: the wheels the
    # plugin's parameters describe (left at +wheelSeparation/2 on y, right at -, axes along +y).
    wheels: List[Wheel] = field(default_factory=list)
    # Tricycle drive: the steering joint, the encoder (passive rear) wheels and their settings.
    steering: Optional[Steering] = None
    encoder_wheels: List[Wheel] = field(default_factory=list)
    encoder_wheel_diameter: float = 0.15       # m
    encoder_wheel_separation: float = 0.5      # m
    wheel_deceleration: float = 0.0            # rad/s^2 of the actuated wheel
    wheel_speed_tolerance: float = 0.01        # rad/s
    steering_speed: float = 0.0                # rad/s; 0 sets the steering angle outright
    steering_angle_tolerance: float = 0.01     # rad


@dataclass
class CameraConfig:
    """A <sensor type="camera"> (or depth camera) with libgazebo_ros_camera or _openni_kinect."""
    sensor_name: str = 'camera'
    link: str = ''                             # link named by <gazebo reference>
    pose: Pose = field(default_factory=Pose)   # sensor pose in the link frame
    update_rate: float = 0.0                   # Hz; 0 means every physics step
    plugin_update_rate: float = 0.0            # Hz; plugin <updateRate> throttles publishing; 0 = no throttle
    width: int = 320
    height: int = 240
    hfov: float = 1.047                        # rad
    image_format: str = 'R8G8B8'
    near: float = 0.1                          # m
    far: float = 100.0                         # m
    image_topic: str = 'image_raw'
    info_topic: str = 'camera_info'
    frame_name: str = ''                       # empty: gazebo_ros falls back to 'world'
    hack_baseline: float = 0.0
    distortion: Tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0)  # k1 k2 t1 t2 k3
    plugin: str = 'camera'                     # 'camera' | 'openni_kinect'


@dataclass
class LaserConfig:
    """A <sensor type="ray"|"gpu_ray"> with libgazebo_ros_laser or _gpu_laser."""
    sensor_name: str = 'laser'
    link: str = ''
    pose: Pose = field(default_factory=Pose)
    update_rate: float = 0.0                   # Hz; 0 means every physics step
    samples: int = 640
    min_angle: float = 0.0                     # rad
    max_angle: float = 0.0                     # rad
    range_min: float = 0.0                     # m
    range_max: float = 0.0                     # m
    range_resolution: float = 0.0              # m; 0 means no quantisation
    noise_mean: float = 0.0                    # m
    noise_stddev: float = 0.0                  # m; 0 means no noise
    topic: str = '/world'
    frame_name: str = 'world'                  # tf::resolve drops the leading '/' of the '/world' default


@dataclass
class Link:
    name: str
    # Collision boxes, cylinders and spheres in the link frame: (kind, pose, size).
    collisions: List[Tuple[str, Pose, Tuple[float, ...]]] = field(default_factory=list)
    visuals: List[Tuple[str, Pose, Tuple[float, ...]]] = field(default_factory=list)
    mass: float = 0.0
    centre_of_mass: Pose = field(default_factory=Pose)   # <inertial><origin>, in the link frame
    material: str = ''                         # <gazebo reference><material> script, as Gazebo draws the link


@dataclass
class Joint:
    name: str
    kind: str                                  # urdf joint type
    parent: str
    child: str
    origin: Pose = field(default_factory=Pose)
    axis: Tuple[float, float, float] = (1.0, 0.0, 0.0)


@dataclass
class RobotSpec:
    """Everything flatsim takes from a robot description."""
    name: str
    root_link: str
    links: dict                                # name -> Link
    joints: dict                               # name -> Joint
    drive: Optional[DriveConfig] = None
    cameras: List[CameraConfig] = field(default_factory=list)
    lasers: List[LaserConfig] = field(default_factory=list)
    # Convex hull of the collision geometry that cuts the working height, in the
    # root link frame, as (x, y) points; the physics body takes this shape.
    footprint: List[Tuple[float, float]] = field(default_factory=list)
    mass: float = 0.0
    skipped: list = field(default_factory=list)  # flatsim.errors.Skipped
    # Movable joints and inertials (flatsim.loading.ros_control.Articulation), and the
    # gazebo_ros_control plugin (RosControlConfig) if the robot has one.
    articulation: object = None
    ros_control: object = None
    # The SDF <model> element a robot was read from (saved in a world, or spawned as SDF);
    # None for a robot from URDF.
    sdf_model: object = None
