"""What the studio reads from a Simulation, as plain values, and what it asks of the simulator.

describe_scene() turns the simulated world into the models the page draws:
every model with its links, each link with its shapes (boxes, cylinders and
spheres with size, pose and colour) and its sensors. World models are drawn
as flatsim simulates them, from the scene's 2.5D primitives; robots from
their URDF visuals, coloured as their <gazebo reference><material> says.
A SnapshotTaker reads what moves (poses, time) under the simulator's lock at
every frame the page shows: the moving models' poses into one array, and
nothing else; rounding and JSON come after, outside the lock.

WorldAccess is the whole surface the studio uses; the ROS node implements it
(flatsim.ros.studio_world) and the tests implement it over a bare Simulation.
No ROS here.
"""
import copy
import functools
import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from flatsim.errors import FlatsimError
from flatsim.loading.materials import resolve_visual_color
from flatsim.loading.sdf_world import read_spawned_model
from flatsim.loading.urdf_robot import link_poses
from flatsim.pose import Pose
from flatsim.studio.scaling import simple_shape
from flatsim.world.scene import BOX, CYLINDER, SPHERE
from flatsim.world.sim_models import FROM_INSERT, model_origin

SHAPE_NAMES = {BOX: 'box', CYLINDER: 'cylinder', SPHERE: 'sphere'}
# Poses go to the page rounded to 0.01 mm and 1 micro-radian: finer changes are
# not worth a message, and equal poses stay equal after rounding.
DIGITS = 5
# What Gazebo draws a robot link in when nothing sets its material.
DEFAULT_LINK_MATERIAL = 'Gazebo/Grey'
# A flat visual still gets this thickness, so that the page can draw it.
MIN_THICKNESS = 0.001
# Gazebo draws collisions in translucent orange.
COLLISION_RGBA = [1.0, 0.5, 0.0, 0.5]


def pose_list(pose):
    """[x, y, z, roll, pitch, yaw] of a Pose, rounded for the page."""
    return [round(float(v), DIGITS) for v in
            (pose.x, pose.y, pose.z, pose.roll, pose.pitch, pose.yaw)]


def inverse(pose):
    return Pose.from_matrix(np.linalg.inv(pose.matrix()))


@dataclass
class Outcome:
    """The simulator's answer to a change the studio asked for."""
    ok: bool
    message: str = ''


@dataclass
class Snapshot:
    """What moves, read under the simulator's lock.

    moving: the names of the models that can move (balls, robots), in order.
    moving_poses: one row per moving model: x, y, z, yaw in the world, as read.
    static_poses: model name -> [x, y, z, roll, pitch, yaw] of each static model
        (they move only by hand; shared by the snapshots until one is moved, or
        models come or go).
    joint_links: model name -> [(link, Pose in the model frame)], for robots
        whose joints move (ros_control); other links never move in their model.
    models_key: changes whenever models come or go (the scene must be sent again).
    """
    sim_time: float
    paused: bool
    iterations: int
    step_size: float
    moving: Tuple[str, ...]
    moving_poses: np.ndarray
    static_poses: Dict[str, List[float]]
    joint_links: Dict[str, List[Tuple[str, Pose]]]
    models_key: tuple

    @functools.cached_property
    def rounded_poses(self):
        """moving_poses rounded for the page (outside the lock, when first asked for)."""
        return np.round(self.moving_poses, DIGITS)

    def moving_pose(self, row):
        """[x, y, z, roll, pitch, yaw] of the moving model in that row, rounded."""
        x, y, z, yaw = self.rounded_poses[row].tolist()
        return [x, y, z, 0.0, 0.0, yaw]

    @property
    def poses(self):
        """model name -> [x, y, z, roll, pitch, yaw] in the world, of every model."""
        poses = dict(self.static_poses)
        for row, name in enumerate(self.moving):
            poses[name] = self.moving_pose(row)
        return poses

    @property
    def link_poses(self):
        """model name -> {link: [x, y, z, roll, pitch, yaw] in the model frame}."""
        return {name: {link: pose_list(pose) for link, pose in links}
                for name, links in self.joint_links.items()}


@dataclass
class Scan:
    """A lidar's latest scan: where it was taken from and its ranges (None: no return)."""
    sensor: str                                # 'model::sensor'
    origin: List[float]                        # x, y, z, yaw of the sensor in the world
    min_angle: float
    max_angle: float
    range_max: float
    ranges: List[Optional[float]] = field(default_factory=list)


class WorldAccess:
    """The simulator as the studio sees it. Every method is called from one studio thread.

    Changes return an Outcome whose message is the simulator's own answer
    (gazebo_ros's status message where there is one).
    """

    def snapshot(self) -> Snapshot:
        raise NotImplementedError

    def scene(self) -> dict:
        """describe_scene() of the world now."""
        raise NotImplementedError

    def skipped(self) -> List[dict]:
        """What flatsim left out: [{'subject': ..., 'reason': ...}]."""
        raise NotImplementedError

    def set_model_pose(self, name, pose: Pose) -> Outcome:
        raise NotImplementedError

    def delete_model(self, name) -> Outcome:
        raise NotImplementedError

    def copy_model(self, source, name, pose: Pose) -> Outcome:
        """Spawn a copy of model source under a new name at pose."""
        raise NotImplementedError

    def scale_model(self, name, scale) -> Outcome:
        """Gazebo's Scale tool: a simple shape model's sizes times scale [sx, sy, sz]
        (flatsim.studio.scaling.rescale)."""
        raise NotImplementedError

    def keep_model(self, name) -> 'KeptModel':
        """What restore_model needs to put the model back as it is now (keep_model()); a
        FlatsimError if there is no such model or it cannot be kept."""
        raise NotImplementedError

    def restore_model(self, kept: 'KeptModel') -> Outcome:
        """Put a kept model back under its name, at its kept pose (Undo of a delete, Redo of an
        insert)."""
        raise NotImplementedError

    def insert_model(self, name, sdf, position=None, path=None) -> Outcome:
        """Gazebo's Insert: spawn the one model the SDF text holds, named name, at
        position (x, y) on the floor with its own height and turn, or where its own
        <pose> puts it when position is None. Save World As writes it back from the
        SDF (ModelOrigin FROM_INSERT). path is the SDF file's, for its relative URIs."""
        raise NotImplementedError

    def world_sdf(self):
        """The world now as Save World As writes it (flatsim.authoring.world_writer.SavedWorld)."""
        raise NotImplementedError

    def pause(self) -> Outcome:
        raise NotImplementedError

    def play(self) -> Outcome:
        raise NotImplementedError

    def step(self, count) -> Outcome:
        """Advance count physics steps while paused."""
        raise NotImplementedError

    def reset_model_poses(self) -> Outcome:
        raise NotImplementedError

    def reset_world(self) -> Outcome:
        """Models back to their start and time back to zero."""
        raise NotImplementedError

    def camera_image(self, sensor) -> Optional[Tuple[float, np.ndarray]]:
        """(sim time, rgb8 pixels) the camera 'model::sensor' sees now, or None if there is none."""
        raise NotImplementedError

    def want_scans(self, wanted: bool):
        """Ask the simulator to keep its lidars scanning (or not) for the page."""
        raise NotImplementedError

    def want_commands(self, wanted: bool):
        """Ask the simulator to record the drive commands robots get and to watch the calls to
        /ball_chaser/command_robot (or to stop and forget them), for the chase view
        (flatsim.studio.chase.CommandLog, flatsim.studio.service_watch)."""
        raise NotImplementedError

    def drive_commands(self, model, now) -> list:
        """The DriveCommands model got over the chase view's window up to sim time now, oldest
        first; [] when none are recorded."""
        raise NotImplementedError

    def service_calls(self, now):
        """The calls to /ball_chaser/command_robot over the chase view's window up to sim time
        now, as the node serving it logged them (flatsim.studio.chase.ServiceCalls); None when
        nothing watches them."""
        return None

    def scans(self) -> List[Scan]:
        raise NotImplementedError


def model_to_insert(name, sdf, position=None, path=None):
    """(model, pose, origin) to place for WorldAccess.insert_model; FlatsimError if the SDF
    holds no usable model. The model's own pose moves into pose (the world pose to place it
    at), so that it is not applied twice."""
    model, _ = read_spawned_model(sdf, name, path)
    own = model.pose
    pose = own if position is None else Pose(position[0], position[1], own.z, own.roll, own.pitch,
                                             own.yaw)
    model.pose = Pose()
    element = model.element
    if element is not None:
        element.set('name', name)
    return model, pose, model_origin(FROM_INSERT, element)


@dataclass
class KeptModel:
    """A model as it was, to be put back by Undo or Redo: what it was made from (its robot
    spec or SDF model, its own pose cleared, as a copy is placed), where it came from (for
    Save World As), where it stood and where Reset Model Poses puts it."""
    name: str
    robot: bool
    loaded: object                 # a RobotSpec or a flatsim.loading.sdf_world.Model; never placed
    origin: object                 # flatsim.world.sim_models.ModelOrigin
    pose: Pose
    initial_pose: Pose
    saved: bool = False            # a robot saved in the world file
    saved_source: object = None


def model_parts(sim, name):
    """What keep_model() copies, read under the simulator's lock: the copying comes after."""
    model = sim.models.get(name)
    if model is None:
        raise FlatsimError('there is no model named %r to keep' % name)
    spec = getattr(model, 'spec', None)
    original = spec if spec is not None else model.source
    if original is None:
        raise FlatsimError('%s was not made from a model that can be made again' % name)
    return (name, spec is not None, original, sim.origins.get(name), sim.model_pose(name),
            model.initial_pose, model.saved, model.source if spec is not None else None)


def keep_model(parts):
    """A KeptModel from model_parts(), outside the lock: the loaded model is a deep copy, so
    that nothing the simulator does to the placed model changes it."""
    name, robot, original, origin, pose, initial_pose, saved, saved_source = parts
    loaded = copy.deepcopy(original)
    if not robot:
        loaded.name = name
        loaded.pose = Pose()
    return KeptModel(name, robot, loaded, origin, pose, initial_pose, saved, saved_source)


def placed_again(model, kept):
    """After a kept model is placed again: it starts where it started before, as it was."""
    model.initial_pose = kept.initial_pose
    if kept.robot:
        model.saved = kept.saved
        if kept.saved_source is not None:
            model.source = kept.saved_source


# -- the scene ---------------------------------------------------------------------

def gui_camera_pose(world_spec):
    """The pose of the world's <gui><camera>, where Gazebo's window first looks from, as
    [x, y, z, roll, pitch, yaw]; None when the world gives none or one that is no pose."""
    for part in getattr(world_spec, 'parts', None) or []:
        if part.element.tag != 'gui':
            continue
        pose = part.element.find('camera/pose')
        if pose is None:
            return None
        try:
            return pose_list(Pose.parse((pose.text or '').strip()))
        except FlatsimError:
            return None
    return None


def describe_scene(sim, world_name='', camera=None):
    """Every model of sim with its links, shapes and sensors, as plain values for JSON;
    camera: the world's gui camera pose (gui_camera_pose), or None."""
    return {
        'world': world_name,
        'camera': camera,
        'sky': [round(float(c), 3) for c in sim.scene.sky_color],
        'floor': [round(float(c), 3) for c in sim.scene.floor_color],
        'models': [describe_model(sim, name) for name in sim.models],
    }


def describe_model(sim, name):
    model = sim.models[name]
    pose = sim.model_pose(name)
    spec = getattr(model, 'spec', None)
    if spec is not None:
        links = _robot_links(spec, getattr(model, 'control', None))
        sensors = [_sensor(slot) for slot in model.sensors]
    else:
        links = [{'name': _first_link(model), 'pose': pose_list(Pose()),
                  'shapes': _prim_shapes(sim, model, pose),
                  'collisions': _prim_shapes(sim, model, pose, collisions=True)}]
        sensors = []
    return {'name': name, 'kind': model.kind, 'static': model.handle is None,
            'pose': pose_list(pose), 'links': links, 'sensors': sensors,
            # What Gazebo's Scale tool scales: box, cylinder or sphere; None for anything else.
            'simple_shape': simple_shape(model.source) if spec is None else None}


def _first_link(model):
    links = getattr(model.source, 'links', None)
    return links[0][0] if links else 'link'


def _prim_shapes(sim, model, pose, collisions=False):
    """The model's scene primitives in the model frame: the camera's visuals, or the
    lidar's colliders for a model that has no visual; with collisions, its colliders (what
    the model menu's View > Collisions shows)."""
    scene = sim.scene
    alive = [i for i in model.prim_ids if scene.alive[i]]
    if collisions:
        chosen = [i for i in alive if not scene.visual[i]]
    else:
        chosen = [i for i in alive if scene.visual[i]] or alive
    to_model = inverse(pose)
    shapes = []
    for index in chosen:
        kind = SHAPE_NAMES[int(scene.kind[index])]
        z_min, z_max = float(scene.z_min[index]), float(scene.z_max[index])
        height = max(z_max - z_min, MIN_THICKNESS)
        if kind == 'box':
            size = [2 * float(scene.half_x[index]), 2 * float(scene.half_y[index]), height]
        elif kind == 'cylinder':
            size = [float(scene.radius[index]), height]
        else:
            size = [float(scene.radius[index])]
        world = Pose(float(scene.x[index]), float(scene.y[index]), (z_min + z_max) / 2.0,
                     yaw=float(scene.yaw[index]))
        shapes.append({'name': scene.names[index], 'shape': kind,
                       'size': [round(s, DIGITS) for s in size],
                       'pose': pose_list(to_model * world),
                       'color': _rgba(tuple(scene.color[index]) + (1.0,))})
    return shapes


def _robot_links(spec, control):
    poses = link_poses(spec)
    links = []
    for name, link in spec.links.items():
        color = _rgba(resolve_visual_color(link.material or DEFAULT_LINK_MATERIAL).color)
        shapes = [{'name': '%s::visual_%d' % (name, index), 'shape': kind,
                   'size': [round(float(s), DIGITS) for s in size],
                   'pose': pose_list(origin), 'color': color}
                  for index, (kind, origin, size) in enumerate(link.visuals)]
        collisions = [{'name': '%s::collision_%d' % (name, index), 'shape': kind,
                       'size': [round(float(s), DIGITS) for s in size],
                       'pose': pose_list(origin), 'color': COLLISION_RGBA}
                      for index, (kind, origin, size) in enumerate(link.collisions)]
        pose = control.link_pose(name) if control is not None else poses[name]
        links.append({'name': name, 'pose': pose_list(pose), 'shapes': shapes,
                      'collisions': collisions})
    return links


def _sensor(slot):
    cfg = slot.config
    described = {'name': cfg.sensor_name, 'kind': slot.kind, 'link': cfg.link,
                 'pose': pose_list(cfg.pose)}
    if slot.kind == 'camera':
        described.update(hfov=float(cfg.hfov), width=int(cfg.width), height=int(cfg.height),
                         near=float(cfg.near), far=float(cfg.far))
    else:
        described.update(min_angle=float(cfg.min_angle), max_angle=float(cfg.max_angle),
                         samples=int(cfg.samples), range_min=float(cfg.range_min),
                         range_max=float(cfg.range_max))
    return described


def _rgba(color):
    return [round(float(c), 3) for c in color]


def sensor_name(slot):
    return '%s::%s' % (slot.robot.name, slot.config.sensor_name)


def find_sensor(sim, name, kind):
    """The sensor slot called 'model::sensor' of that kind, or None."""
    for robot in sim.robots():
        for slot in robot.sensors:
            if slot.kind == kind and sensor_name(slot) == name:
                return slot
    return None


def skipped_items(sim):
    """What the world and every robot in it left out, subject and reason."""
    items = [{'subject': item.subject, 'reason': item.reason} for item in sim.skipped]
    for robot in sim.robots():
        for item in getattr(robot.spec, 'skipped', ()):
            items.append({'subject': 'robot %s: %s' % (robot.name, item.subject),
                          'reason': item.reason})
    return items


# -- what moves --------------------------------------------------------------------

class SnapshotTaker:
    """Takes Snapshots of one Simulation, remembering between them which models move
    (and the static ones' poses) until models come or go: under the lock, only the
    moving models are read."""

    def __init__(self):
        self.models_key = None
        self.moving = ()              # (name, model) of the models that can move
        self.jointed = ()             # (name, model) of those whose joints move
        self.static_poses = {}
        self.layout_version = None

    def take(self, sim):
        """A Snapshot of sim; call under the simulator's lock."""
        # Model objects are new when a model comes back under an old name.
        models_key = tuple((name, id(model)) for name, model in sim.models.items())
        if models_key != self.models_key:
            self._learn_models(sim, models_key)
        elif sim.layout_version != self.layout_version:
            self._learn_static_poses(sim)
        pose = sim.physics.pose
        rows = []
        for _, model in self.moving:
            x, y, yaw = pose(model.handle)
            rows.append((x, y, model.z, yaw))
        joint_links = {name: [(link, model.control.link_pose(link)) for link in model.spec.links]
                       for name, model in self.jointed}
        return Snapshot(sim_time=float(sim.time), paused=bool(sim.paused), iterations=int(sim.steps),
                        step_size=float(sim.step_size), moving=self.moving_names,
                        moving_poses=np.array(rows, dtype=float).reshape(-1, 4),
                        static_poses=self.static_poses, joint_links=joint_links,
                        models_key=models_key)

    def _learn_models(self, sim, models_key):
        self.models_key = models_key
        # Held until the next change: a model that takes an old one's name before then never
        # gets its id, so models_key changes whenever a model is replaced (Undo relies on it).
        self.held = tuple(sim.models.values())
        self.moving = tuple((name, model) for name, model in sim.models.items()
                            if model.handle is not None)
        self.moving_names = tuple(name for name, _ in self.moving)
        self.jointed = tuple((name, model) for name, model in self.moving
                             if getattr(model, 'control', None) is not None)
        self._learn_static_poses(sim)

    def _learn_static_poses(self, sim):
        """The poses of the models that stand still, anew (one was moved by hand)."""
        self.layout_version = sim.layout_version
        self.static_poses = {name: pose_list(sim.model_pose(name))
                             for name, model in sim.models.items() if model.handle is None}


def scan_of(slot, ranges, angles, eye):
    """A Scan from what the node keeps of a lidar's last scan (ranges, angles, (x, y, yaw))."""
    cfg = slot.config
    values = [round(float(r), 3) if math.isfinite(r) else None for r in ranges]
    return Scan(sensor=sensor_name(slot), origin=[round(float(v), DIGITS) for v in eye],
                min_angle=float(angles[0]) if len(angles) else float(cfg.min_angle),
                max_angle=float(angles[-1]) if len(angles) else float(cfg.max_angle),
                range_max=float(cfg.range_max), ranges=values)
