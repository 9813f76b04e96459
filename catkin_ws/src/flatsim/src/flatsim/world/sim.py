"""The simulated world: models, robots, fixed-step time and sensor schedules.

No ROS here. The node asks which sensors are due after each step and turns
their output into messages; everything else (physics, drives, raycasts) is
driven from this class so that tests and benchmarks run it without a master.
"""
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field, replace
from typing import List

import numpy as np
import pymunk

from flatsim.authoring.sdf_text import element_depth
from flatsim.errors import FlatsimError, Skipped
from flatsim.loading.sdf_world import MAX_STEP_SIZE, MIN_STEP_SIZE
from flatsim.loading.urdf_robot import link_pose
from flatsim.pose import Pose
from flatsim.sensors.camera import PinholeCamera
from flatsim.sensors.lidar import Lidar
from flatsim.world.drive import RosControlWheels, make_drive
from flatsim.world.physics import Physics, check_position, check_twist
from flatsim.world.robot_control import RobotControl
from flatsim.world.scene import Prim, Scene
from flatsim.world.wrench import Wrenches

# Heights between which geometry blocks a ground robot: above the floor's
# contact patch and below the top of any course robot.
WORKING_HEIGHT = (0.02, 0.5)
# A slab lying on the floor whose top is no higher than this is ground that robots drive onto,
# not an obstacle: the Building Editor's floor (0.1 m thick) and a thin mat or platform. 0.1 m
# is the wheel radius of most course robots, which a wheel meets at or below its axle.
MAX_STEP_HEIGHT = 0.1
# A sphere this small or smaller is a ball the robot can push.
MAX_BALL_RADIUS = 0.5
# A ros_control velocity joint's wheel counts as on the floor when its bottom is this close to
# the robot's lowest point (m).
WHEEL_FLOOR_TOLERANCE = 0.01
# A collision's friction coefficient against the ground when its <surface> gives none: ODE's <mu>.
DEFAULT_FRICTION = 1.0
# Physics that diverges this often within this many seconds of sim time is stopped.
DIVERGENCE_LIMIT = 3
DIVERGENCE_WINDOW = 1.0


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


def world_of(base_xy_yaw, base_z, local):
    """World pose of a pose given in a floor-bound body frame."""
    x, y, yaw = base_xy_yaw
    c, s = math.cos(yaw), math.sin(yaw)
    return Pose(x + c * local.x - s * local.y, y + s * local.x + c * local.y,
                base_z + local.z, local.roll, local.pitch, yaw + local.yaw)


def geom_prims(name, model_pose, geoms, seen_by):
    """2.5D primitives for a model's geoms, in the world frame.

    seen_by is 'lidar' for collision geometry and 'camera' for visuals.
    """
    prims = []
    for geom in geoms:
        pose = model_pose * geom.pose
        prim = _prim_for(name + '::' + geom.name, geom, pose)
        if prim is not None:
            prim.collision = seen_by == 'lidar'
            prim.visual = seen_by == 'camera'
            prims.append(prim)
    return prims


def _prim_for(name, geom, pose):
    color = tuple(geom.color[:3]) if getattr(geom, 'color', None) else (0.7, 0.7, 0.7)
    unlit = bool(getattr(geom, 'unlit_white', False))
    common = dict(name=name, color=color, unlit_white=unlit)
    if geom.kind == 'box':
        sx, sy, sz = geom.size
        return _box_prim(pose, sx, sy, sz, common)
    if geom.kind == 'cylinder':
        radius, length = geom.size
        if abs(pose.roll) < 1e-3 and abs(pose.pitch) < 1e-3:
            return Prim(kind='cylinder', x=pose.x, y=pose.y, yaw=pose.yaw, radius=radius,
                        z_min=pose.z - length / 2, z_max=pose.z + length / 2, **common)
        # A cylinder on its side casts the box its bounding box does.
        return _box_prim(pose, 2 * radius, 2 * radius, length, common)
    if geom.kind == 'sphere':
        (radius,) = geom.size
        return Prim(kind='sphere', x=pose.x, y=pose.y, yaw=0.0, radius=radius,
                    z_min=pose.z - radius, z_max=pose.z + radius, **common)
    return None


def _box_prim(pose, sx, sy, sz, common):
    rot = pose.matrix()[:3, :3]
    half = rot @ [[sx / 2, 0, 0], [0, sy / 2, 0], [0, 0, sz / 2]]
    half_height = float(sum(abs(half[2])))
    # The box's footprint: its x axis direction on the floor sets the yaw,
    # and the projected extents set the half sizes.
    yaw = math.atan2(rot[1, 0], rot[0, 0]) if math.hypot(rot[0, 0], rot[1, 0]) > 1e-6 \
        else math.atan2(rot[1, 2], rot[0, 2])
    c, s = math.cos(yaw), math.sin(yaw)
    along = abs(c * half[0] + s * half[1])
    across = abs(-s * half[0] + c * half[1])
    return Prim(kind='box', x=pose.x, y=pose.y, yaw=yaw,
                half_x=float(sum(along)), half_y=float(sum(across)),
                z_min=pose.z - half_height, z_max=pose.z + half_height, **common)


def body_inertia(model, upright):
    """((x, y) centre of mass in the body frame, moment of inertia about it about z) of a
    dynamic model, from its links' <inertial>s (mass, izz and origin), the model turned by
    upright's roll and pitch. A link's izz is taken about the vertical."""
    inertials = getattr(model, 'inertials', None) or [(model.mass or 1.0, 1.0, 0.0, 0.0, 0.0)]
    points = []
    for mass, izz, x, y, z in inertials:
        where = upright * Pose(x, y, z)
        points.append((mass, izz, where.x, where.y))
    total = sum(mass for mass, _, _, _ in points)
    centre_x = sum(mass * x for mass, _, x, _ in points) / total
    centre_y = sum(mass * y for mass, _, _, y in points) / total
    moment = sum(izz + mass * ((x - centre_x) ** 2 + (y - centre_y) ** 2)
                 for mass, izz, x, y in points)
    return (centre_x, centre_y), moment


def robot_prims(name, spec, z):
    """The robot's collision shapes as the lidars of other robots see them, in the robot's
    frame (its root link at height z), with every joint at zero.

    They are for lidars only: the camera, the overhead view and the markers draw a
    robot from its own description, not from these.
    """
    return [replace(prim, name='%s::%s' % (name, prim.name), z_min=prim.z_min + z,
                    z_max=prim.z_max + z, collision=True, visual=False)
            for prim in _robot_shapes(spec)]


def _robot_shapes(spec):
    """The robot's collision shapes in its root link frame, kept on the spec, so that a
    spawn works them out (in root_height) before it takes the simulator's lock."""
    key = (len(spec.links), len(spec.joints), spec.root_link)
    cached = getattr(spec, '_robot_shapes', None)
    if cached is not None and cached[0] == key:
        return cached[1]
    shapes = []
    for link_name, link in spec.links.items():
        to_root = link_pose(spec, link_name)
        for index, (kind, origin, size) in enumerate(link.collisions):
            prim = _prim_for('%s::collision_%d' % (link_name, index), _Geom(kind, origin, size),
                             to_root * origin)
            if prim is not None:
                shapes.append(prim)
    spec._robot_shapes = (key, shapes)
    return shapes


def root_height(spec):
    """Height of the root link above the floor when the robot rests on its lowest geometry.

    Kept on the spec, so that a spawn can work it out before it takes the
    simulator's lock (a 1,000-link robot takes 0.1 s).
    """
    key = (len(spec.links), len(spec.joints), spec.root_link)
    cached = getattr(spec, '_root_height', None)
    if cached is not None and cached[0] == key:
        return cached[1]
    lowest = min([0.0] + [prim.z_min for prim in _robot_shapes(spec)])
    spec._root_height = (key, max(0.0, -lowest))
    return spec._root_height[1]


@dataclass
class _Geom:
    kind: str
    pose: Pose
    size: tuple
    name: str = ''


def cuts_working_height(prim):
    return prim.z_min < WORKING_HEIGHT[1] and prim.z_max > WORKING_HEIGHT[0]


def is_ground(prim):
    """A slab at ground level that wheels drive onto: its bottom at most WORKING_HEIGHT[0]
    above the floor and its top at most MAX_STEP_HEIGHT. A sphere is never ground."""
    return prim.kind != 'sphere' and prim.z_min <= WORKING_HEIGHT[0] and prim.z_max <= MAX_STEP_HEIGHT


def is_obstacle(prim):
    """A collision that stops a robot: it cuts the working height and is not ground."""
    return cuts_working_height(prim) and not is_ground(prim)


def _covers(prim, x, y):
    """Whether the prim's footprint holds the point (x, y)."""
    dx, dy = x - prim.x, y - prim.y
    if prim.kind == 'box':
        c, s = math.cos(prim.yaw), math.sin(prim.yaw)
        return abs(c * dx + s * dy) <= prim.half_x and abs(-s * dx + c * dy) <= prim.half_y
    return dx * dx + dy * dy <= prim.radius * prim.radius


def check_step_size(step_size):
    if not (isinstance(step_size, (int, float)) and MIN_STEP_SIZE <= step_size <= MAX_STEP_SIZE):
        raise FlatsimError('step size must be between %g and %g s, got %r'
                           % (MIN_STEP_SIZE, MAX_STEP_SIZE, step_size))


@dataclass(frozen=True)
class Recovery:
    """What Simulation.recover did after physics diverged."""
    stopped: bool                  # physics paused: it diverged again and again
    dropped_wrenches: List[str]    # the scoped links whose wrenches it dropped


class Simulation:
    """A world with its models and robots, advanced in fixed steps."""

    def __init__(self, world=None, step_size=0.002, seed=0):
        check_step_size(step_size)
        self.step_size = step_size
        self.seed = seed
        self.time = 0.0
        self.steps = 0
        # Time at step 0 of the current step size: a new step size keeps time continuous.
        self.time_base = 0.0
        self.paused = False
        self.physics = Physics(step=step_size)
        self.wrenches = Wrenches()
        self.divergences = []      # sim times at which physics diverged lately
        # Counts the changes of where models stand still (moves, arrivals, departures), for
        # readers that keep their poses and for the ground's cache.
        self.layout_version = 0
        self._ground_cache = None
        self.scene = Scene([])
        self.models = {}
        # name -> ModelOrigin of every model, kept as models come and go.
        self.origins = {}
        self.skipped = []
        if world is not None:
            self.skipped.extend(world.skipped)
            # One scene update for the whole world: adding shapes one by one is quadratic.
            pending = []
            for model in world.models:
                if model.robot is None:
                    pending.extend(self._place_world_model(
                        model, model.pose, model_origin(FROM_WORLD, model.element)))
            self._add_prims(pending)
            # Bodies and balls rest on the ground under them, whatever came first in the file.
            for model in self.models.values():
                self._settle(model)
            self.sync_moving_prims()
            for model in world.models:
                if model.robot is not None:
                    self._spawn_saved_robot(model)

    def _add_prims(self, pending):
        """pending: (model, prim) pairs; each model learns the scene indices of its prims."""
        indices = self.scene.extend(prim for _, prim in pending)
        for (model, _), index in zip(pending, indices):
            model.prim_ids.append(index)

    # -- building the world ----------------------------------------------
    def add_world_model(self, model, pose=None, origin=None):
        """Add an SDF model: statics and jointed models become colliders, small dynamic
        spheres balls, other dynamic models bodies that robots and balls push.

        origin (a ModelOrigin) says where it came from; by default a spawned SDF.
        """
        pending = self._place_world_model(model, pose or model.pose,
                                          origin or model_origin(FROM_SDF, model.element))
        sim_model = self.models[model.name]
        try:
            self._add_prims(pending)
            self._settle(sim_model)
            self._sync_model_prims(sim_model)
        except Exception:
            self.delete_model(model.name)
            raise
        return sim_model

    def _place_world_model(self, model, pose, origin, hold=''):
        """Register a model and its colliders; returns its (model, prim) pairs for the scene.

        A dynamic model becomes a body that robots and balls push, unless it is
        jointed (its joints would move its links apart, which one body in the
        plane cannot) or hold is set; such a model, and every static one, stands
        where it is put until it is moved by hand (set_model_state, the studio).
        hold: why to hold a dynamic model still, said before (a saved robot that cannot run).

        A model that cannot be placed leaves nothing behind: no collider, no origin (which
        Save World As would write a model for) and no entry in models.
        """
        if model.name in self.models:
            raise FlatsimError('a model named %r already exists' % model.name)
        joints = getattr(model, 'joints', 0)
        if not model.static and not hold and joints:
            # The loader has said so.
            hold = ('its %d joint(s) would take its links apart, and flatsim moves a model as '
                    'one rigid body in the plane' % joints)
        if not model.static and not hold:
            ball = self._ball_geom(model)
            pending = (self._place_ball(model, pose, ball) if ball is not None
                       else self._place_body(model, pose))
            if pending is not None:
                self.origins[model.name] = origin
                return pending
            hold = ('no collision of it stands in the working height (%g to %g m above the '
                    'ground) for anything to push' % WORKING_HEIGHT)
            self.skipped.append(Skipped('model %s' % model.name, '%s; held still' % hold))
        sim_model = SimModel(model.name, 'static', pose, pose=pose, source=model, held=hold)
        pending = self._place_fixed(sim_model, pose)
        self.models[model.name] = sim_model
        self.layout_version += 1
        self.origins[model.name] = origin
        return pending

    def _place_fixed(self, sim_model, pose):
        """The colliders and ground of a model that stands still at pose; its (model, prim) pairs."""
        collisions, prims = self._fixed_prims(sim_model.source, pose)
        sim_model.colliders = self._static_colliders(collisions)
        sim_model.ground = [prim for prim in collisions if is_ground(prim) and prim.z_max > 0.0]
        return [(sim_model, prim) for prim in prims]

    @staticmethod
    def _fixed_prims(model, pose):
        """(its collision prims, all its prims: collisions then visuals) of a model at pose."""
        collisions = geom_prims(model.name, pose, model.collisions, 'lidar')
        return collisions, collisions + geom_prims(model.name, pose, model.visuals, 'camera')

    def _static_colliders(self, collisions):
        """Static physics shapes for the obstacles among collisions; none are left on failure."""
        colliders = []
        try:
            for prim in filter(is_obstacle, collisions):
                if prim.kind == 'box':
                    shape = self.physics.add_static_box(prim.x, prim.y, prim.yaw, prim.half_x,
                                                        prim.half_y)
                else:
                    shape = self.physics.add_static_circle(prim.x, prim.y, prim.radius)
                colliders.append(shape)
        except Exception:
            for shape in colliders:
                self.physics.remove_static(shape)
            raise
        return colliders

    @staticmethod
    def _ball_geom(model):
        spheres = [g for g in model.collisions if g.kind == 'sphere']
        others = [g for g in model.collisions if g.kind != 'sphere']
        if len(spheres) == 1 and not others and spheres[0].size[0] <= MAX_BALL_RADIUS:
            return spheres[0]
        return None

    def _place_ball(self, model, pose, geom):
        radius = geom.size[0]
        handle = self.physics.add_ball(model.name, pose.x, pose.y, radius, model.mass or 1.0)
        sim_model = SimModel(model.name, 'ball', pose, handle=handle, z=pose.z, source=model)
        # Prims are made at the model origin, and their offsets kept, so that they follow the body.
        try:
            prims = (geom_prims(model.name, Pose(z=pose.z), model.collisions, 'lidar')
                     + geom_prims(model.name, Pose(z=pose.z), model.visuals, 'camera'))
        except Exception:
            self.physics.remove(handle)
            raise
        self._follow_body(sim_model, prims)
        self.models[model.name] = sim_model
        return [(sim_model, prim) for prim in prims]

    def _place_body(self, model, pose):
        """A dynamic model as one body in the plane, pushed by whatever runs into it and
        braked by its friction on the ground; None when nothing of it would be pushed."""
        # Made with the model's roll and pitch but no yaw: the body's angle turns them.
        upright = Pose(0.0, 0.0, pose.z, pose.roll, pose.pitch, 0.0)
        collisions = geom_prims(model.name, upright, model.collisions, 'lidar')
        blocking = [prim for prim in collisions if is_obstacle(prim)]
        if not blocking:
            return None
        prims = collisions + geom_prims(model.name, upright, model.visuals, 'camera')
        centre, moment = body_inertia(model, upright)
        handle = self.physics.add_body(model.name, blocking, model.mass or 1.0, moment, centre,
                                       pose.x, pose.y, pose.yaw,
                                       getattr(model, 'friction', DEFAULT_FRICTION))
        sim_model = SimModel(model.name, 'body', pose, handle=handle, z=pose.z, source=model)
        self._follow_body(sim_model, prims)
        self.models[model.name] = sim_model
        return [(sim_model, prim) for prim in prims]

    @staticmethod
    def _follow_body(sim_model, prims):
        """Keep each prim's place on the body, so that it follows the body as it moves."""
        sim_model.prim_offsets = [(prim.x, prim.y, prim.yaw) for prim in prims]
        sim_model.prim_heights = [(prim.z_min, prim.z_max) for prim in prims]

    def _ground(self):
        """Every model's ground prims, gathered once after each change of the world's layout."""
        key = (len(self.models), self.layout_version)
        if self._ground_cache is None or self._ground_cache[0] != key:
            self._ground_cache = (key, [prim for model in self.models.values()
                                        for prim in model.ground])
        return self._ground_cache[1]

    def has_ground(self):
        """Whether any model holds ground (a slab robots drive onto)."""
        return bool(self._ground())

    def ground_height(self, x, y):
        """Height of the ground at (x, y): the top of the highest slab there that robots
        drive onto (see is_ground), else 0, the floor."""
        height = 0.0
        for prim in self._ground():
            if prim.z_max > height and _covers(prim, x, y):
                height = prim.z_max
        return height

    def _settle(self, model):
        """A body or ball placed over ground (a slab) rests on it: its height is kept above
        the ground under it, and one placed into the slab comes up onto it, as Gazebo's
        contacts push it up."""
        start = model.initial_pose
        ground = self.ground_height(start.x, start.y)
        if ground <= 0.0 or not model.prim_heights:
            return
        bottom = min(z_min for z_min, _ in model.prim_heights)
        drop = min(ground, bottom)
        model.z -= drop
        model.prim_heights = [(z_min - drop, z_max - drop) for z_min, z_max in model.prim_heights]

    def spawn_robot(self, name, spec, pose, origin=None):
        """Put a robot (a loaded RobotSpec) on the floor at pose (x, y, yaw are used).

        origin (a ModelOrigin) defaults to a spawned SDF for a robot read from
        SDF, else to a robot from URDF.

        A world saved from Gazebo with the robot in it holds a copy of that
        robot: running (saved) or, when flatsim cannot read it as a robot, a
        plain model. A robot spawned under the same name takes its place, so
        the saved copy does not stand in the way. A spawn that fails leaves the
        copy where it was, as Gazebo leaves its world when a spawn fails.
        """
        existing = self.models.get(name)
        if existing is not None and not self.robot_may_replace(name):
            raise FlatsimError('a model named %r already exists' % name)
        if len(spec.footprint) < 3:
            raise FlatsimError('robot %r has no collision geometry to stand on' % name)
        drive = make_drive(spec.drive) if spec.drive is not None else None
        # A URDF rooted at a link called world is fixed to the world, as in Gazebo.
        fixed = spec.root_link == 'world'
        robot = SimRobot(name, 'robot', pose, z=pose.z if fixed else root_height(spec), spec=spec,
                         drive=drive)
        if spec.ros_control is not None:
            robot.control = RobotControl(spec, self.step_size)
            if drive is None:
                drive = robot.drive = self._ros_control_wheels(spec, robot.control)
        for index, cfg in enumerate(spec.cameras):
            robot.sensors.append(self._slot('camera', cfg, robot, PinholeCamera(cfg)))
        for index, cfg in enumerate(spec.lasers):
            robot.sensors.append(self._slot('laser', cfg, robot, self._lidar(cfg, index)))
        # The copy's body holds the name in physics: it steps aside for the new body and comes
        # back, where it was and as it was moving, if the new one cannot be placed.
        prims = robot_prims(name, spec, robot.z)
        if existing is not None:
            self._withdraw_physics(existing)
        try:
            robot.handle = self.physics.add_robot(name, spec.footprint, spec.mass or 1.0,
                                                  pose.x, pose.y, pose.yaw, drive, fixed=fixed)
        except Exception:
            if existing is not None:
                self._restore_physics(existing)
            raise
        if existing is not None:
            self._forget(existing)
            self.skipped.append(Skipped('model %s' % name, 'replaced by the robot spawned under that name'))
        self.models[name] = robot
        robot.prim_offsets = [(prim.x, prim.y, prim.yaw) for prim in prims]
        self._add_prims([(robot, prim) for prim in prims])
        self._sync_model_prims(robot)
        if origin is None:
            sdf_model = getattr(spec, 'sdf_model', None)
            origin = model_origin(FROM_SDF, sdf_model) if sdf_model is not None else ModelOrigin(FROM_URDF)
        self.origins[name] = origin
        return robot

    @staticmethod
    def _ros_control_wheels(spec, control):
        """ros_control's velocity joints whose wheels reach the floor, as a drive; or None."""
        floor = -root_height(spec)
        wheels = [wheel for wheel in spec.ros_control.wheels
                  if abs(wheel.z - wheel.radius - floor) < WHEEL_FLOOR_TOLERANCE]
        return RosControlWheels(control, wheels) if wheels else None

    def robot_may_replace(self, name):
        """Whether a robot spawned under name takes the place of the model of that name: a
        copy of a robot saved in the world (running or not), or a model that no robot drives."""
        model = self.models[name]
        if model.saved or model.kind == 'static':
            return True
        origin = self.origins.get(name)
        return model.kind == 'body' and origin is not None and origin.kind == FROM_WORLD

    def _spawn_saved_robot(self, model):
        """A robot saved in the world file runs as if spawned, until one is spawned in its place."""
        origin = model_origin(FROM_WORLD, model.element)
        try:
            robot = self.spawn_robot(model.name, model.robot, model.pose, origin)
        except FlatsimError as error:
            self.skipped.append(Skipped('model %s' % model.name,
                                        'a robot saved in the world that cannot run (%s); held '
                                        'still' % error))
            self._add_prims(self._place_world_model(
                model, model.pose, origin, hold='a robot saved in the world that flatsim cannot run'))
            return
        robot.saved = True
        robot.source = model

    def _slot(self, kind, cfg, robot, impl):
        mount = link_pose(robot.spec, cfg.link) * cfg.pose
        # A camera plugin's own <updateRate> can only slow the sensor down.
        rates = [r for r in (cfg.update_rate, getattr(cfg, 'plugin_update_rate', 0.0)) if r > 0]
        period = 1.0 / min(rates) if rates else 0.0
        return SensorSlot(kind, cfg, robot, impl, mount, period, next_due=self.time)

    def delete_model(self, name):
        model = self._model(name)
        self._withdraw_physics(model)
        self._forget(model)

    def _withdraw_physics(self, model):
        if model.handle is not None:
            self.physics.remove(model.handle)
        for shape in model.colliders:
            self.physics.remove_static(shape)

    def _restore_physics(self, model):
        """Puts back what _withdraw_physics took out of physics, as it was."""
        if model.handle is not None:
            self.physics.restore(model.handle)
        for shape in model.colliders:
            self.physics.restore_static(shape)

    def _forget(self, model):
        """Everything but physics of a model that leaves the world."""
        self.layout_version += 1
        for prim_id in model.prim_ids:
            self.scene.remove(prim_id)
        del self.models[model.name]
        self.origins.pop(model.name, None)
        self.wrenches.clear_model(model.name)

    # -- state ------------------------------------------------------------
    def _model(self, name):
        try:
            return self.models[name]
        except KeyError:
            known = ', '.join(sorted(self.models)) or 'none'
            raise FlatsimError('no model named %r (models: %s)' % (name, known)) from None

    def model_pose(self, name):
        model = self._model(name)
        if model.handle is None:
            return model.pose or model.initial_pose
        x, y, yaw = self.physics.pose(model.handle)
        return Pose(x, y, model.z + self._lift(model, x, y), 0.0, 0.0, yaw)

    def _lift(self, model, x, y):
        """How far the ground under (x, y) raises a moving model: robots bolted to the world
        stay where they are."""
        if model.kind == 'robot' and model.handle.body.body_type == pymunk.Body.STATIC:
            return 0.0
        return self.ground_height(x, y)

    def model_twist(self, name):
        """World-frame (vx, vy, wz)."""
        model = self._model(name)
        if model.handle is None:
            return 0.0, 0.0, 0.0
        return self.physics.twist(model.handle)

    def set_model_state(self, name, pose, twist=(0.0, 0.0, 0.0)):
        """Put a model at pose with a world-frame twist (vx, vy, wz).

        A moving model (robot, ball, body) takes x, y and yaw, its height set by
        the ground under it; a model that stands still (static, jointed) takes
        the whole pose, as Gazebo moves a static model, and no twist.
        """
        model = self._model(name)
        values = (pose.x, pose.y, pose.yaw) + tuple(twist)
        if not all(math.isfinite(v) for v in values):
            raise FlatsimError('pose and twist must be finite numbers')
        if model.handle is None:
            self._move_fixed(model, pose)
            return
        # Checked before anything moves, so a refused request changes nothing.
        check_position(name, pose.x, pose.y)
        check_twist(name, *twist)
        self.physics.set_pose(model.handle, pose.x, pose.y, pose.yaw)
        self.physics.set_twist(model.handle, *twist)
        self._sync_model_prims(model)

    def _move_fixed(self, model, pose):
        """A model that stands still, moved by hand: its shapes, colliders and ground go along.
        A refused move changes nothing."""
        if not all(math.isfinite(v) for v in (pose.z, pose.roll, pose.pitch)):
            raise FlatsimError('pose and twist must be finite numbers')
        check_position(model.name, pose.x, pose.y)
        collisions, prims = self._fixed_prims(model.source, pose)
        for prim in prims:
            prim.validate()
        colliders = self._static_colliders(collisions)
        for shape in model.colliders:
            self.physics.remove_static(shape)
        model.colliders = colliders
        model.ground = [prim for prim in collisions if is_ground(prim) and prim.z_max > 0.0]
        for prim_id, prim in zip(model.prim_ids, prims):
            self.scene.replace(prim_id, prim)
        model.pose = pose
        self.layout_version += 1

    def reset_world(self):
        """Every model back to where it started, moving ones at rest; time goes on."""
        for model in self.models.values():
            if model.handle is None and model.pose is not None and model.pose != model.initial_pose:
                self._move_fixed(model, model.initial_pose)
            if model.handle is not None:
                start = model.initial_pose
                self.physics.restart(model.handle, start.x, start.y, start.yaw)
                if isinstance(model, SimRobot) and model.drive is not None:
                    model.drive.reset()
                if isinstance(model, SimRobot) and model.control is not None:
                    model.control.reset()
                self._sync_model_prims(model)

    def recover(self, error=None):
        """After physics diverged (error, a FlatsimError): the world starts over, or stops
        when that keeps happening. The wrenches on the model that diverged are dropped: a
        wrench that lasts would push it over again as soon as the world starts over.

        Returns a Recovery: stopped (physics paused) after DIVERGENCE_LIMIT divergences
        within DIVERGENCE_WINDOW s of sim time, so starting over does not help.
        """
        self.divergences = [t for t in self.divergences if self.time - t < DIVERGENCE_WINDOW]
        self.divergences.append(self.time)
        self.reset_world()
        model = getattr(error, 'model', None)
        dropped = self.wrenches.clear_model(model) if model else []
        stopped = len(self.divergences) >= DIVERGENCE_LIMIT
        if stopped:
            self.paused = True
            self.divergences = []
        return Recovery(stopped, dropped)

    def _lidar(self, config, index):
        """A robot's index-th lidar; its noise follows from the seed alone, so a reset repeats it."""
        return Lidar(config, seed=self.seed + index)

    def reset_time(self):
        """Time back to zero, as gazebo's reset_simulation does, and the world as it started.

        The sensor noise starts over from the seed too, so that the same
        placements after a reset give the same run, bit for bit, whatever
        ran before.
        """
        self.reset_world()
        self.time = 0.0
        self.steps = 0
        self.time_base = 0.0
        for robot in self.robots():
            lasers = (slot for slot in robot.sensors if slot.kind == 'laser')
            for index, slot in enumerate(lasers):
                slot.impl = self._lidar(slot.config, index)
            for slot in robot.sensors:
                slot.next_due = 0.0

    def robots(self):
        return [m for m in self.models.values() if isinstance(m, SimRobot)]

    # -- time -------------------------------------------------------------
    def step(self):
        """Advance one fixed step (nothing moves while paused)."""
        if self.paused:
            return
        for robot in self.robots():
            if robot.control is not None:
                robot.control.step(self.time, self.step_size)
        self.wrenches.apply(self)
        self.physics.step()
        self.steps += 1
        self.time = self.time_base + self.steps * self.step_size

    def set_step_size(self, step_size):
        """A new fixed step from now on; time goes on from where it is."""
        check_step_size(step_size)
        self.time_base, self.steps = self.time, 0
        self.step_size = self.physics.step_size = float(step_size)

    def due_sensors(self):
        """Sensors whose next update time has come; each is rescheduled."""
        due = []
        for robot in self.robots():
            for slot in robot.sensors:
                if self.time + 1e-9 >= slot.next_due:
                    due.append(slot)
                    # Keep a fixed cadence: skipped updates are not made up. A rate above
                    # the physics rate means every step.
                    step = max(slot.period, self.step_size)
                    missed = math.floor((self.time + 1e-9 - slot.next_due) / step) + 1
                    slot.next_due += max(missed, 1) * step
                    if slot.next_due <= self.time + 1e-9:  # too far ahead for the float's precision
                        slot.next_due = self.time + step
        return due

    def sensor_pose(self, slot):
        base = self.physics.pose(slot.robot.handle)
        height = slot.robot.z + self._lift(slot.robot, base[0], base[1])
        control = slot.robot.control
        if control is not None:
            # On a moving link: the link where the joints are now, then the sensor on it.
            return world_of(base, height, control.link_pose(slot.config.link) * slot.config.pose)
        return world_of(base, height, slot.mount)

    def sense(self, slot):
        """The sensor's output now: an image array or an array of ranges."""
        self.sync_moving_prims()
        pose = self.sensor_pose(slot)
        # A robot's own shapes neither hide its camera's view nor block its lidar.
        own = slot.robot.prim_ids or None
        if slot.kind == 'camera':
            return slot.impl.render(self.scene, pose.x, pose.y, pose.z, pose.yaw, exclude=own,
                                    pitch=pose.pitch, roll=pose.roll)
        return slot.impl.scan(self.scene, pose.x, pose.y, pose.z, pose.yaw, exclude=own)

    def sync_moving_prims(self):
        """Bring the balls' and bodies' scene primitives to their bodies' poses.

        They are moved only when something looks at the scene (a sensor, the
        overhead view, the markers), not on every physics step.
        """
        for model in self.models.values():
            if model.kind in ('ball', 'body', 'robot'):
                self._sync_model_prims(model)

    def _sync_model_prims(self, model):
        if model.kind not in ('ball', 'body', 'robot') or not model.prim_ids or model.handle is None:
            return
        x, y, yaw = self.physics.pose(model.handle)
        c, s = math.cos(yaw), math.sin(yaw)
        offsets = np.asarray(model.prim_offsets, dtype=float).reshape(-1, 3)
        self.scene.set_poses(model.prim_ids, x + c * offsets[:, 0] - s * offsets[:, 1],
                             y + s * offsets[:, 0] + c * offsets[:, 1], yaw + offsets[:, 2])
        if model.kind in ('ball', 'body'):
            # A robot's shapes are placed at its spawn height, which already stands on the ground.
            lift = self.ground_height(x, y) if self.has_ground() else 0.0
            for prim_id, (z_min, z_max) in zip(model.prim_ids, model.prim_heights):
                self.scene.set_height(prim_id, z_min + lift, z_max + lift)
