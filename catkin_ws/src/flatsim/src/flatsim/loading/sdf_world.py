"""Read Gazebo .world files (SDF 1.4-1.7) into flat records of models and shapes.

What Gazebo's Building Editor and "Save World As" write is covered:
  - model, link and collision/visual poses are composed, nested models too;
    SDF 1.7 `relative_to` may name any link, nested model, joint or <frame>
    of the same model (or a model or <frame> of the world);
  - the <state> block's model and link poses (world poses) win over the
    model's own, as when Gazebo loads the world; <insertions> and
    <deletions> in the state are applied;
  - box, cylinder, sphere and plane shapes; colours from <material>;
  - static and dynamic models, mass from <inertial><mass>.
`<include><uri>model://NAME` is read from the folder NAME on Gazebo's model
path (flatsim.loading.model_path), with the include's <name>, <pose> and
<static> in place of the model's own, nested includes too (to MAX_INCLUDE_DEPTH);
ground_plane and sun need no model in flatsim and stay implicit.
Meshes (STL, OBJ, Collada) are read and covered with upright boxes
(flatsim.loading.meshes); the mesh visuals of a link that has no collision
collide as well, so that a table drawn only by its mesh stops the robot.
A world saved by Gazebo holds model-database models whose mesh files are not
here: a link whose visual mesh cannot be found is drawn by its collisions,
and one record names every such link. Anything else that cannot be used
(polylines, includes of models that are not on the path, plugins, sensors,
actors, a mesh file that cannot be read...) becomes a flatsim.errors.Skipped
record and loading goes on;
the few model-database meshes in flatsim.loading.stand_ins are drawn as boxes
instead, and their record says so.
Geometry sizes follow SDF: box (sx, sy, sz), cylinder (radius, length),
sphere (radius,), plane (nx, ny, nz, sx, sy) with a unit normal.

For "Save World As" the reader keeps the file itself: each model's <model>
element (includes expanded, as Gazebo writes them) and, in file order, the
world's other elements (WorldSpec.parts).
"""
import copy
import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field, replace
from functools import lru_cache
from typing import List, Optional, Tuple

import numpy as np

from flatsim.errors import FlatsimError, ModelFileError, Skipped
from flatsim.loading.materials import DEFAULT_SCENE_AMBIENT, parse_rgba, resolve_visual_color
from flatsim.loading.meshes import MeshError, MeshNotFound, describe, find_mesh, mesh_boxes, read_mesh
from flatsim.loading.model_path import find_model, model_name_from_uri, model_path
from flatsim.loading.sdf_robot import is_saved_robot, saved_robot_urdf
from flatsim.loading.stand_ins import has_stand_in, stand_in
from flatsim.loading.urdf_robot import load_robot
from flatsim.pose import Pose

RGBA = Tuple[float, float, float, float]

DEFAULT_MAX_STEP_SIZE = 0.001
# What flatsim simulates: shapes from 0.1 mm to 1000 km, physics steps from
# 10 us to 50 ms (as flatsim.world.sim takes them), models nested 100 deep.
MIN_SHAPE_SIZE = 1e-4
MAX_SHAPE_SIZE = 1e6
# Finer steps never let time move on at a useful rate, coarser ones make the
# course's 100 Hz drive and contacts meaningless.
MIN_STEP_SIZE = 1e-5
MAX_STEP_SIZE = 0.05
MAX_NESTING = 100
# Includes within included models, as deep as a hand-made model library goes;
# deeper is taken for a model that includes itself.
MAX_INCLUDE_DEPTH = 20
DEFAULT_GRAVITY = (0.0, 0.0, -9.8)
DEFAULT_BACKGROUND = (0.7, 0.7, 0.7, 1.0)
COLLISION_COLOR = resolve_visual_color().color

# Included models that nearly every Gazebo world has; the floor and the light
# need no model in flatsim, so these are not worth a report.
IMPLICIT_INCLUDES = {'model://ground_plane', 'model://sun'}
# World elements that need no mention: settings for Gazebo's GUI, renderer or
# physics engine, or things flatsim does itself.
QUIET_WORLD_ELEMENTS = {
    'gui', 'physics', 'scene', 'light', 'spherical_coordinates', 'atmosphere',
    'wind', 'magnetic_field', 'gravity', 'audio', 'state', 'model', 'include',
    'plugin', 'frame',
}
UNSUPPORTED_SHAPES = {
    'polyline': 'polyline extrusions are not supported; left out',
    'heightmap': 'heightmaps are not supported; left out',
    'image': 'image extrusions are not supported; left out',
    'capsule': 'capsules are not supported; left out',
    'ellipsoid': 'ellipsoids are not supported; left out',
}


@dataclass
class Geom:
    name: str
    kind: str                                  # 'box' | 'cylinder' | 'sphere' | 'plane'
    pose: Pose                                 # in the model frame
    size: Tuple[float, ...]
    color: RGBA = COLLISION_COLOR
    unlit_white: bool = False
    link: str = ''                             # link name, 'nested::link' inside a nested model
    material: str = ''                         # material script name, if any
    from_mesh: bool = False                    # one of the boxes covering a mesh


@dataclass
class Model:
    name: str
    pose: Pose                                 # in the world
    static: bool = False
    mass: float = 1.0                          # kg, sum over links
    collisions: List[Geom] = field(default_factory=list)
    visuals: List[Geom] = field(default_factory=list)
    # (link name, pose in the model frame) of each link, 'nested::link' inside a nested model.
    links: List[Tuple[str, Pose]] = field(default_factory=list)
    # (mass, izz, x, y, z) of each link's <inertial>, its origin in the model frame.
    inertials: List[Tuple[float, float, float, float, float]] = field(default_factory=list)
    friction: float = 1.0                      # least <mu> of its collisions against the ground
    joints: int = 0                            # joints between its links, nested models' too
    # A robot saved into the world (flatsim.loading.sdf_robot): its RobotSpec, run as if
    # spawned from URDF; the shapes above are then only a record of the file.
    robot: object = None
    # The <model> element as read, its includes expanded: what Save World As writes back.
    element: Optional[ET.Element] = field(default=None, repr=False, compare=False)


@dataclass
class WorldPart:
    """One child of the <world> element, in file order, kept to write the world back.

    model names the model (in WorldSpec.models) that the element was read
    into; it is '' for every other element (light, physics, scene, gui, a
    plugin, an include that was not resolved, a model that was left out...).
    """
    element: ET.Element = field(repr=False)
    model: str = ''


@dataclass
class WorldSpec:
    name: str
    path: Optional[str]
    models: List[Model] = field(default_factory=list)
    skipped: List[Skipped] = field(default_factory=list)
    max_step_size: float = DEFAULT_MAX_STEP_SIZE
    gravity: Tuple[float, float, float] = DEFAULT_GRAVITY
    real_time_update_rate: float = 1000.0      # Hz; 0 means as fast as possible
    real_time_factor: float = 1.0
    scene_ambient: Tuple[float, float, float] = DEFAULT_SCENE_AMBIENT
    background: RGBA = DEFAULT_BACKGROUND
    ground_plane: bool = False                 # model://ground_plane included, or an upward plane shape
    sdf_version: str = ''
    parts: List[WorldPart] = field(default_factory=list, repr=False)

    def model(self, name):
        """The model called name, or None."""
        for model in self.models:
            if model.name == name:
                return model
        return None


class _Unusable(Exception):
    """An element that has to be left out; the message is the reason."""


class _MissingMesh(Exception):
    """A mesh whose file is not here: its link may be drawn by its collisions instead."""

    def __init__(self, uri, reason):
        super().__init__(reason)
        self.uri = uri or '(no uri)'
        self.reason = reason


def _mesh_color(uri, base_dir, model_paths):
    try:
        return read_mesh(find_mesh(uri, base_dir, model_paths)).color
    except MeshError:
        return None


def _text(elem, tag, default=None):
    child = elem.find(tag)
    if child is None or child.text is None or not child.text.strip():
        return default
    return child.text.strip()


def _is_true(text):
    return (text or '').strip().lower() in ('1', 'true')


def _floats(text, count, what):
    try:
        values = tuple(float(v) for v in text.split())
    except ValueError:
        raise _Unusable('%s %r is not numbers' % (what, text)) from None
    if len(values) != count:
        raise _Unusable('%s %r is not %d numbers' % (what, text, count))
    if not all(math.isfinite(v) for v in values):
        raise _Unusable('%s %r is not finite' % (what, text))
    return values


def _positive(values, what, text):
    if not all(v > 0.0 for v in values):
        raise _Unusable('%s %r is not positive' % (what, text))
    return values


@lru_cache(maxsize=8192)
def _pose_matrix(text):
    try:
        mat = Pose.parse(text).matrix()
    except FlatsimError as error:
        raise _Unusable(str(error)) from None
    mat.setflags(write=False)
    return mat


IDENTITY = _pose_matrix('')


def _rigid_inverse(mat):
    inverse = np.eye(4)
    inverse[:3, :3] = mat[:3, :3].T
    inverse[:3, 3] = -mat[:3, :3].T @ mat[:3, 3]
    return inverse


def _raw_pose(elem):
    """(matrix, relative_to or None) of elem's <pose>."""
    pose = elem.find('pose')
    if pose is None:
        return IDENTITY, None
    return _pose_matrix((pose.text or '').strip()), pose.get('relative_to') or None


def _state_pose(state_elem):
    """The pose matrix a <state> entry gives, or None where it gives none."""
    text = _text(state_elem, 'pose') if state_elem is not None else None
    return None if text is None else _pose_matrix(text)


class _FrameGraph:
    """Poses of one scope's named frames (SDF 1.7 pose frame semantics) in the scope's frame."""

    def __init__(self, root_names):
        self._roots = root_names
        self._raw = {}
        self._resolved = {}

    def add(self, name, elem, default_relative_to=''):
        """Record elem's <pose> under name; a bad pose only fails whoever resolves name."""
        if not name or name in self._raw:
            return
        try:
            raw, relative_to = _raw_pose(elem)
        except _Unusable as error:
            self._raw[name] = (error, None)
            return
        self._raw[name] = (raw, relative_to or default_relative_to)

    def resolve(self, name):
        if name in self._roots:
            return IDENTITY
        resolved = self._resolved.get(name)
        if resolved is not None:
            return resolved
        chain = []
        current = name
        while current not in self._roots and current not in self._resolved:
            if current not in self._raw:
                raise _Unusable('frame %r does not exist in this scope' % current)
            if current in chain:
                raise _Unusable('frames %s form a loop' % ' -> '.join(chain + [current]))
            raw, relative_to = self._raw[current]
            if isinstance(raw, _Unusable):
                raise raw
            chain.append(current)
            current = relative_to or ''
        base = IDENTITY if current in self._roots else self._resolved[current]
        for frame in reversed(chain):
            base = base @ self._raw[frame][0]
            self._resolved[frame] = base
        return self._resolved[name]


def _model_frame_graph(model_elem):
    graph = _FrameGraph({'', '__model__'})
    for child in model_elem:
        name = child.get('name')
        if child.tag in ('link', 'model'):
            graph.add(name, child)
        elif child.tag == 'joint':
            graph.add(name, child, _text(child, 'child', ''))
        elif child.tag == 'frame':
            graph.add(name, child, child.get('attached_to') or '')
    return graph


class _Scope:
    """A model or nested model being read, with the transforms into the top-level model."""

    def __init__(self, elem, top_from_scope, state_elem, top_from_world, subject, link_prefix,
                 depth=0):
        self.elem = elem
        self.depth = depth
        self.top_from_scope = top_from_scope
        self.top_from_world = top_from_world
        self.subject = subject
        self.link_prefix = link_prefix
        self.state_children = {}
        if state_elem is not None:
            for child in state_elem:
                if child.tag in ('link', 'model'):
                    self.state_children[(child.tag, child.get('name', ''))] = child


class _WorldReader:
    def __init__(self, path, scene_ambient=DEFAULT_SCENE_AMBIENT, robot_namespace='', model_paths=None):
        self.path = path
        self.robot_namespace = robot_namespace
        self.scene_ambient = scene_ambient
        self.model_paths = model_path() if model_paths is None else list(model_paths)
        self.skipped = []
        self._reported_scripts = set()
        self._reading_robot = False
        self._model_files = {}
        self._reported_includes = set()
        self.base_dir = os.path.dirname(os.path.abspath(path)) if path else None
        # Links drawn by their collisions as their visual meshes are missing: (link, uri).
        self.drawn_by_collisions = []

    def report_missing_visuals(self):
        """One record naming every link drawn by its collisions for want of its visual mesh."""
        if self.drawn_by_collisions:
            self.skip('visual meshes not found',
                      'drawn by their collisions instead: %s'
                      % ', '.join('%s (%s)' % item for item in self.drawn_by_collisions))
            self.drawn_by_collisions = []

    def skip(self, subject, reason):
        self.skipped.append(Skipped(subject, reason))

    # World level

    def read_world(self, world_elem, world):
        world.name = world_elem.get('name', 'default')
        self._read_physics(world_elem, world)
        self._read_scene(world_elem, world)
        self.scene_ambient = world.scene_ambient
        self.expand_includes(world_elem, '', 0)
        model_elems = {}
        for child in world_elem:
            tag = child.tag
            part = WorldPart(child)
            if tag == 'model':
                if self.add_model_elem(child, model_elems, 'model'):
                    part.model = child.get('name')
            elif tag == 'include':
                if self._read_include(child, 'include'):
                    world.ground_plane = True
            elif tag == 'plugin':
                self.skip('world plugin %s (%s)' % (child.get('name', ''), child.get('filename', '')),
                          'Gazebo world plugins do not run in flatsim; ignored')
            elif tag == 'actor':
                self.skip('actor %s' % child.get('name', ''), 'animated actors are not simulated; left out')
            elif tag not in QUIET_WORLD_ELEMENTS:
                self.skip('world element <%s>' % tag, 'not used by flatsim; ignored')
            if tag != 'state':
                world.parts.append(part)
        inserted = set(model_elems)
        state_models = self._read_state(world_elem, model_elems)
        # Models the state deleted are gone from the world, as Gazebo would write it.
        world.parts = [part for part in world.parts if not part.model or part.model in model_elems]
        world.parts.extend(WorldPart(elem, name) for name, elem in model_elems.items()
                           if name not in inserted)
        graph = _FrameGraph({'', 'world'})
        for name, elem in model_elems.items():
            graph.add(name, elem)
        for frame in world_elem.findall('frame'):
            graph.add(frame.get('name'), frame, frame.get('attached_to') or '')
        for name, elem in model_elems.items():
            model = self.read_top_model(elem, name, graph, state_models.pop(name, None))
            if model is not None:
                world.models.append(model)
        loaded = {model.name for model in world.models}
        for part in world.parts:
            if part.model not in loaded:
                part.model = ''
        for name in state_models:
            self.skip('state of model %s' % name, 'no such model in the world; its saved pose is ignored')
        self.report_missing_visuals()
        world.ground_plane = world.ground_plane or any(
            geom.kind == 'plane' and _faces_up(model.pose * geom.pose, geom.size[:3])
            for model in world.models for geom in model.collisions)

    def _read_physics(self, world_elem, world):
        physics_elems = world_elem.findall('physics')
        physics = next((p for p in physics_elems if _is_true(p.get('default'))),
                       physics_elems[0] if physics_elems else None)
        gravity_text = _text(world_elem, 'gravity')
        if physics is not None:
            step = self._positive_setting(physics, 'max_step_size', DEFAULT_MAX_STEP_SIZE)
            world.max_step_size = min(max(step, MIN_STEP_SIZE), MAX_STEP_SIZE)
            if world.max_step_size != step:
                self.skip('physics max_step_size', '%g s is outside the %g to %g s flatsim steps; '
                          'flatsim steps by its own ~step_size parameter (the step_size of '
                          'empty_world.launch and world.launch), not by the world\'s'
                          % (step, MIN_STEP_SIZE, MAX_STEP_SIZE))
            world.real_time_factor = self._positive_setting(physics, 'real_time_factor', 1.0)
            world.real_time_update_rate = self._positive_setting(
                physics, 'real_time_update_rate', 1000.0, allow_zero=True)
            gravity_text = gravity_text or _text(physics, 'gravity')
        if gravity_text:
            try:
                world.gravity = _floats(gravity_text, 3, 'gravity')
            except _Unusable as error:
                self.skip('world gravity', '%s; using %s' % (error, DEFAULT_GRAVITY))

    def _positive_setting(self, physics, tag, default, allow_zero=False):
        text = _text(physics, tag)
        if text is None:
            return default
        try:
            value, = _floats(text, 1, tag)
        except _Unusable as error:
            self.skip('physics %s' % tag, '%s; using %g' % (error, default))
            return default
        if value < 0.0 or (value == 0.0 and not allow_zero):
            self.skip('physics %s' % tag, '%g is not positive; using %g' % (value, default))
            return default
        return value

    def _read_scene(self, world_elem, world):
        scene = world_elem.find('scene')
        if scene is None:
            return
        for tag, attr in (('ambient', 'scene_ambient'), ('background', 'background')):
            try:
                rgba = parse_rgba(_text(scene, tag))
            except FlatsimError as error:
                self.skip('scene %s' % tag, '%s; using the default' % error)
                continue
            if rgba is not None:
                setattr(world, attr, rgba[:3] if attr == 'scene_ambient' else rgba)

    def _read_include(self, include, subject):
        """Report an include that was not expanded; True when it is the implicit ground plane."""
        uri = _text(include, 'uri', '')
        if uri in IMPLICIT_INCLUDES:
            return uri == 'model://ground_plane'
        if id(include) in self._reported_includes:
            return False
        what = self._include_subject(include, subject)
        if uri.startswith('model://'):
            reason = "needs Gazebo's model database, which flatsim does not read; left out"
        else:
            reason = 'included models are not loaded; left out'
        self.skip(what, reason)
        return False

    @staticmethod
    def _include_subject(include, subject):
        name = _text(include, 'name')
        return '%s %s' % (subject, _text(include, 'uri', '')) + (' (as %s)' % name if name else '')

    def expand_includes(self, parent, subject, depth, chain=()):
        """Put what each resolvable <include> under parent names in its place, recursively.

        parent is a <world>, <model> or <sdf>. An include of a model that is
        not on the model path stays, for _read_include to report. Models
        nested deeper than the reader goes (MAX_NESTING) are not searched.
        """
        pending = [(parent, subject, 0)]
        while pending:
            elem, where, nesting = pending.pop()
            for index, child in enumerate(list(elem)):
                if child.tag == 'model' and nesting < MAX_NESTING:
                    name = child.get('name', '')
                    pending.append((child, '%s/%s' % (where, name) if where else name, nesting + 1))
                elif child.tag == 'include':
                    found = self._included(child, '%s/include' % where if where else 'include',
                                           depth, chain)
                    if found is not None and (found.tag == 'model' or elem.tag == 'world'):
                        elem[index] = found

    def _included(self, include, subject, depth, chain):
        """The <model> (or <light>) an include names, its overrides applied; None when not resolved."""
        uri = _text(include, 'uri', '')
        name = model_name_from_uri(uri)
        if uri in IMPLICIT_INCLUDES or name is None:
            return None
        entry = find_model(name, self.model_paths)
        if entry is None:
            return None
        self._reported_includes.add(id(include))
        what = self._include_subject(include, subject)
        if entry.problem:
            self.skip(what, 'the model folder %s cannot be used (%s); left out' % (entry.folder, entry.problem))
            return None
        if depth >= MAX_INCLUDE_DEPTH or name in chain:
            self.skip(what, 'includes nested deeper than %d levels (a model that includes itself?); '
                            'left out' % MAX_INCLUDE_DEPTH)
            return None
        root = self._model_files.get(entry.sdf)
        if root is None:
            try:
                with open(entry.sdf, 'rb') as stream:
                    root = _sdf_root(stream.read(), entry.sdf)
            except (OSError, ModelFileError) as error:
                self.skip(what, '%s; left out' % error)
                return None
            self._model_files[entry.sdf] = root
        source = root.find('model')
        if source is None:
            source = root.find('light')
        found = copy.deepcopy(source)
        self._reported_includes.discard(id(include))
        apply_include_overrides(include, found)
        if found.tag == 'model':
            self.expand_includes(found, '%s %s' % (subject, uri), depth + 1, chain + (name,))
        return found

    def add_model_elem(self, elem, model_elems, where):
        """Record a top-level <model>; False when it is left out (no name, or a name taken)."""
        name = elem.get('name')
        if not name:
            self.skip(where, 'a <model> without a name; left out')
        elif name in model_elems:
            self.skip('model %s' % name, 'a second model with this name; left out')
        else:
            model_elems[name] = elem
            return True
        return False

    def _read_state(self, world_elem, model_elems):
        """Apply insertions and deletions; return {model name: state <model>} (later states win)."""
        state_models = {}
        for state in world_elem.findall('state'):
            for insertions in state.findall('insertions'):
                for elem in insertions.findall('model'):
                    self.add_model_elem(elem, model_elems, 'state insertion')
            for deletions in state.findall('deletions'):
                for name_elem in deletions.findall('name'):
                    name = (name_elem.text or '').strip()
                    model_elems.pop(name, None)
                    state_models.pop(name, None)
            for elem in state.findall('model'):
                state_models[elem.get('name', '')] = elem
        return state_models

    # Model level

    def _report_pose_frame(self, elem, subject):
        pose = elem.find('pose')
        frame = pose.get('frame') if pose is not None else None
        if frame:
            self.skip(subject, 'pose frame=%r is ignored, as Gazebo 9 ignores it' % frame)

    def read_top_model(self, elem, name, world_graph, state_elem):
        """One world-level model, its nested models flattened into it; None when unusable."""
        self._report_pose_frame(elem, name)
        try:
            world_from_model = world_graph.resolve(name)
            state_pose = _state_pose(state_elem)
            if state_pose is not None:
                world_from_model = state_pose
        except _Unusable as error:
            self.skip(name, 'pose: %s; model left out' % error)
            return None
        if state_elem is not None:
            self._check_state_scale(state_elem, elem, name)
        model = Model(name=name, pose=Pose.from_matrix(world_from_model),
                      static=_is_true(_text(elem, 'static')), element=elem)
        model.robot = self._read_saved_robot(elem, name)
        self._reading_robot = model.robot is not None
        scope = _Scope(elem, IDENTITY, state_elem, _rigid_inverse(world_from_model), name, '')
        masses = []
        reported = len(self.skipped)
        try:
            joint_count = self._read_scope(scope, model, masses)
        finally:
            self._reading_robot = False
        if model.robot is not None:
            # The robot reader has said what it leaves out; the shapes are only a record.
            del self.skipped[reported:]
        model.mass = float(sum(masses)) if masses else 1.0
        model.joints = joint_count
        if joint_count and not model.static and model.robot is None:
            self.skip(name, '%d joint(s): held still, its links where the file places them: flatsim '
                      'moves a model as one rigid body in the plane, which its joints would take '
                      'apart; set_model_state and the studio still move it whole' % joint_count)
        return model

    def _read_saved_robot(self, elem, name):
        """The RobotSpec of a robot saved into the world, or None for any other model."""
        if not is_saved_robot(elem):
            return None
        try:
            urdf, notes = saved_robot_urdf(elem, name)
            spec = load_robot(urdf, name=name, source='model %s of %s' % (name, self.path or 'the world'),
                              robot_namespace=self.robot_namespace)
        except FlatsimError as error:
            self.skip(name, 'a robot saved in the world, but flatsim cannot run it (%s); its '
                            'sensors and plugins are ignored and it is held still' % error)
            return None
        for note in notes:
            self.skip(name, note)
        for item in spec.skipped:
            self.skipped.append(replace(item, subject='%s: %s' % (name, item.subject)))
        spec.sdf_model = elem
        return spec

    def _check_state_scale(self, state_elem, model_elem, subject):
        scale = _text(state_elem, 'scale')
        if scale is None:
            return
        try:
            values = _floats(scale, 3, 'scale')
        except _Unusable as error:
            self.skip(subject, 'state %s; ignored' % error)
            return
        if all(abs(v - 1.0) <= 1e-9 for v in values) or _meshes_scaled_by(model_elem, values):
            return
        self.skip(subject, 'state scale %s is not applied; shapes keep their file sizes' % scale)

    def _read_scope(self, scope, model, masses):
        """Read one (possibly nested) model's links into the top-level model; return its joint count."""
        graph = _model_frame_graph(scope.elem)
        joint_count = len(scope.elem.findall('joint'))
        for child in scope.elem:
            tag = child.tag
            name = child.get('name', '')
            subject = '%s/%s' % (scope.subject, name)
            if tag in ('link', 'model'):
                self._report_pose_frame(child, subject)
                state_child = scope.state_children.get((tag, name))
                try:
                    state_pose = _state_pose(state_child)
                    if state_pose is not None:
                        top_from_child = scope.top_from_world @ state_pose
                    else:
                        top_from_child = scope.top_from_scope @ graph.resolve(name)
                except _Unusable as error:
                    self.skip(subject, 'pose: %s; %s left out' % (error, tag))
                    continue
                if tag == 'link':
                    self._read_link(child, top_from_child, scope, graph, subject,
                                    scope.link_prefix + name, model, masses)
                elif scope.depth >= MAX_NESTING:
                    self.skip('%s/.../%s' % (scope.subject.split('/')[0], name),
                              'models nested deeper than %d levels are left out' % MAX_NESTING)
                else:
                    nested = _Scope(child, top_from_child, state_child, scope.top_from_world, subject,
                                    '%s%s::' % (scope.link_prefix, name), scope.depth + 1)
                    joint_count += self._read_scope(nested, model, masses)
            elif tag == 'plugin' and not self._reading_robot:
                self.skip('%s/plugin %s (%s)' % (scope.subject, name, child.get('filename', '')),
                          'plugins inside world models do not run in flatsim; ignored')
            elif tag == 'include':
                self._read_include(child, '%s/include' % scope.subject)
        self._report_unmatched_state(scope)
        return joint_count

    def _report_unmatched_state(self, scope):
        names = {(child.tag, child.get('name', '')) for child in scope.elem if child.tag in ('link', 'model')}
        for tag, name in scope.state_children:
            if (tag, name) not in names:
                self.skip('state of %s %s/%s' % (tag, scope.subject, name),
                          'no such %s in the model; its saved pose is ignored' % tag)

    def _read_link(self, link_elem, top_from_link, scope, graph, subject, link_name, model, masses):
        masses.append(self._link_mass(link_elem, subject))
        model.links.append((link_name, Pose.from_matrix(top_from_link)))
        model.inertials.append(self._link_inertial(link_elem, top_from_link, masses[-1], subject))
        for collision in link_elem.findall('collision'):
            model.friction = min(model.friction, self._friction(collision, subject))
        found = {'collision': [], 'visual': []}
        missing = []              # (visual element, uri) of visual meshes not found
        mesh_visuals = []
        for tag in ('collision', 'visual'):
            for elem in link_elem.findall(tag):
                geom_subject = '%s/%s' % (subject, elem.get('name', tag))
                try:
                    geoms = self._read_geom(elem, tag, top_from_link, scope, graph, geom_subject)
                except _MissingMesh as error:
                    if tag == 'visual':
                        missing.append((elem, error.uri))
                    else:
                        self.skip(geom_subject, '%s; left out' % describe(error.uri, error.reason))
                    continue
                except _Unusable as error:
                    self.skip(geom_subject, '%s; left out' % error)
                    continue
                for geom in geoms:
                    geom.link = link_name
                    found[tag].append(geom)
                    if geom.from_mesh and tag == 'visual':
                        mesh_visuals.append(geom)
        collisions = found['collision']
        if not collisions and mesh_visuals:
            # A mesh drawn with no collision of its own (furniture modelled for looks) collides
            # by its shape, or the robot would drive through what its camera sees.
            collisions = [replace(geom, name='%s::collision' % geom.name) for geom in mesh_visuals]
        for elem, uri in missing:
            geom_subject = '%s/%s' % (subject, elem.get('name', 'visual'))
            if not collisions:
                self.skip(geom_subject, '%s; left out' % describe(uri, 'file not found'))
                continue
            for geom in collisions:
                stand_in = replace(geom, name='%s::%s' % (elem.get('name', 'visual'), geom.name))
                self._read_material(elem, stand_in, geom_subject)
                found['visual'].append(stand_in)
            if not self._reading_robot:
                self.drawn_by_collisions.append(('%s::%s' % (model.name, link_name), uri))
        model.collisions.extend(collisions)
        model.visuals.extend(found['visual'])
        for sensor in link_elem.findall('sensor') if not self._reading_robot else ():
            self.skip('%s/sensor %s (%s)' % (subject, sensor.get('name', ''), sensor.get('type', '')),
                      'sensors inside world models are not simulated; ignored')

    def _link_inertial(self, link_elem, top_from_link, mass, subject):
        """(mass, izz, x, y, z): the link's mass and izz (SDF's default 1 kg m^2) at its
        <inertial><pose>, in the model frame."""
        izz, where = 1.0, top_from_link
        inertial = link_elem.find('inertial')
        if inertial is not None:
            text = _text(inertial, 'inertia/izz')
            try:
                if text is not None:
                    izz, = _floats(text, 1, 'izz')
                    if not izz > 0.0:
                        raise _Unusable('izz %s is not positive' % text)
                pose_text = _text(inertial, 'pose')
                if pose_text is not None:
                    where = top_from_link @ _pose_matrix(pose_text)
            except _Unusable as error:
                self.skip(subject, 'inertial: %s; using izz 1 kg m^2 at the link origin' % error)
                izz, where = 1.0, top_from_link
        return (mass, float(izz), float(where[0, 3]), float(where[1, 3]), float(where[2, 3]))

    def _friction(self, collision, subject):
        """The collision's friction coefficient (<surface><friction><ode><mu>, else 1)."""
        text = _text(collision, 'surface/friction/ode/mu')
        if text is None:
            return 1.0
        try:
            mu, = _floats(text, 1, 'mu')
        except _Unusable as error:
            self.skip(subject, 'friction: %s; using 1' % error)
            return 1.0
        if mu < 0.0:
            self.skip(subject, 'friction mu %s is negative; using 1' % text)
            return 1.0
        return mu

    def _link_mass(self, link_elem, subject):
        text = _text(link_elem, 'inertial/mass')
        if text is None:
            return 1.0
        try:
            mass, = _positive(_floats(text, 1, 'mass'), 'mass', text)
        except _Unusable as error:
            self.skip(subject, '%s; using 1 kg' % error)
            return 1.0
        return mass

    def _read_geom(self, elem, tag, top_from_link, scope, graph, subject):
        """The geoms that stand for one <collision> or <visual>: usually one, none when left out."""
        raw, relative_to = _raw_pose(elem)
        self._report_pose_frame(elem, subject)
        if relative_to:
            top_from_geom = scope.top_from_scope @ graph.resolve(relative_to) @ raw
        else:
            top_from_geom = top_from_link @ raw
        geometry = elem.find('geometry')
        if geometry is None:
            raise _Unusable('no <geometry>')
        kind, size = None, None
        for shape in geometry:
            if shape.tag in ('box', 'cylinder', 'sphere', 'plane'):
                kind, size = shape.tag, _shape_size(shape)
                break
            if shape.tag == 'mesh':
                return self._mesh_geoms(elem, shape, tag, top_from_geom, subject)
            if shape.tag in UNSUPPORTED_SHAPES:
                self.skip(subject, UNSUPPORTED_SHAPES[shape.tag])
                return []
            if shape.tag == 'empty':
                return []
        if kind is None:
            raise _Unusable('no box, cylinder, sphere or plane in <geometry>')
        geom = Geom(name=elem.get('name', tag), kind=kind, pose=Pose.from_matrix(top_from_geom), size=size)
        if tag == 'visual':
            self._read_material(elem, geom, subject)
        return [geom]

    def _mesh_geoms(self, elem, mesh, tag, top_from_geom, subject):
        """The boxes that cover a mesh; raises _MissingMesh when its file is not there."""
        uri = _text(mesh, 'uri') or ''
        scale_text = _text(mesh, 'scale', '1 1 1')
        scale = _positive(_floats(scale_text, 3, 'mesh scale'), 'mesh scale', scale_text)
        try:
            boxes = mesh_boxes(find_mesh(uri, self.base_dir, self.model_paths), scale, top_from_geom)
        except MeshNotFound as error:
            if has_stand_in(uri):
                return self._mesh_stand_in(elem, uri, scale, tag, top_from_geom, subject)
            raise _MissingMesh(uri, str(error)) from None
        except MeshError as error:
            raise _Unusable(describe(uri, error)) from None
        name = elem.get('name', tag)
        geoms = []
        for index, box in enumerate(boxes):
            geom = Geom(name=name if len(boxes) == 1 else '%s::mesh_%d' % (name, index), kind='box',
                        pose=box.pose, size=box.size, from_mesh=True)
            if tag == 'visual':
                if geoms:
                    geom.color, geom.unlit_white, geom.material = (geoms[0].color, geoms[0].unlit_white,
                                                                   geoms[0].material)
                else:
                    self._read_material(elem, geom, subject, mesh_uri=uri)
            geoms.append(geom)
        return geoms

    def _mesh_stand_in(self, elem, uri, scale, tag, top_from_geom, subject):
        """Boxes from the stand-in catalogue for a mesh that is not here."""
        found = stand_in(uri, scale, _text(elem, 'material/script/name'))
        self.skip(subject, 'mesh %s cannot be read; drawn as a stand-in instead: %s'
                  % (uri, found.description))
        geoms = []
        for part in found.parts:
            if part.visual_only and tag != 'visual':
                continue
            pose = Pose.from_matrix(top_from_geom @ Pose(*part.centre).matrix())
            geoms.append(Geom(name='%s::%s' % (elem.get('name', tag), part.name), kind='box',
                              pose=pose, size=part.size, color=part.color))
        return geoms

    def _read_material(self, visual_elem, geom, subject, mesh_uri=None):
        material = visual_elem.find('material')
        if material is None and mesh_uri is not None:
            # Gazebo draws a mesh with no <material> in the file's own colours.
            own = _mesh_color(mesh_uri, self.base_dir, self.model_paths)
            if own is not None:
                geom.color = resolve_visual_color(ambient=own, diffuse=own,
                                                  scene_ambient=self.scene_ambient).color
                return
        script_name = None
        colors = {}
        if material is not None:
            script_name = _text(material, 'script/name')
            if script_name == '__default__':
                script_name = None
            for tag in ('ambient', 'diffuse', 'emissive'):
                try:
                    colors[tag] = parse_rgba(_text(material, tag))
                except FlatsimError as error:
                    self.skip(subject, 'material %s: %s; ignored' % (tag, error))
        transparency = 0.0
        text = _text(visual_elem, 'transparency')
        if text is not None:
            try:
                transparency, = _floats(text, 1, 'transparency')
            except _Unusable as error:
                self.skip(subject, '%s; drawn opaque' % error)
        resolved = resolve_visual_color(script_name, transparency=transparency,
                                        scene_ambient=self.scene_ambient, **colors)
        if (not resolved.script_known and not (colors.get('ambient') and colors.get('diffuse'))
                and script_name not in self._reported_scripts):
            self._reported_scripts.add(script_name)
            self.skip('material script %s' % script_name,
                      "not one of Gazebo's built-in materials; its visuals are drawn grey")
        geom.color = resolved.color
        geom.unlit_white = resolved.unlit_white
        geom.material = script_name or ''


def _shape_size(shape):
    kind = shape.tag
    if kind == 'box':
        return _sized(kind, _text(shape, 'size', '1 1 1'))
    if kind == 'sphere':
        return _sized(kind, _text(shape, 'radius', '1'))
    if kind == 'cylinder':
        return _sized(kind, _text(shape, 'radius', '1'), _text(shape, 'length', '1'))
    return _sized(kind, _text(shape, 'normal', '0 0 1'), _text(shape, 'size', '1 1'))


def _size_values(text, count, what):
    values = _positive(_floats(text, count, what), what, text)
    if not all(MIN_SHAPE_SIZE <= v <= MAX_SHAPE_SIZE for v in values):
        raise _Unusable('%s %r is outside the %g to %g m that flatsim simulates'
                        % (what, text, MIN_SHAPE_SIZE, MAX_SHAPE_SIZE))
    return values


@lru_cache(maxsize=4096)
def _sized(kind, *texts):
    """Shape size from its SDF texts; worlds repeat the same few sizes, hence the cache."""
    if kind == 'box':
        return _size_values(texts[0], 3, 'box size')
    if kind == 'sphere':
        return _size_values(texts[0], 1, 'sphere radius')
    if kind == 'cylinder':
        return _size_values(texts[0], 1, 'cylinder radius') + _size_values(texts[1], 1, 'cylinder length')
    normal = _floats(texts[0], 3, 'plane normal')
    norm = math.sqrt(sum(v * v for v in normal))
    if norm == 0.0:
        raise _Unusable('plane normal %r has no direction' % texts[0])
    return tuple(v / norm for v in normal) + _size_values(texts[1], 2, 'plane size')


def _meshes_scaled_by(model_elem, scale):
    """True when every shape of the model is a mesh already at this scale.

    Gazebo gives a model's meshes the scale its saved state holds, so the
    state changes nothing for them.
    """
    shapes = [shape for geometry in model_elem.iter('geometry') for shape in geometry]
    try:
        return bool(shapes) and all(
            shape.tag == 'mesh' and all(abs(a - b) <= 1e-9 for a, b in
                                        zip(_floats(_text(shape, 'scale', '1 1 1'), 3, 'scale'), scale))
            for shape in shapes)
    except _Unusable:
        return False


def _faces_up(world_from_geom, normal):
    return (world_from_geom.matrix()[:3, :3] @ normal)[2] > 0.99


def _parse_xml(text, path):
    # Hand-edited worlds often start with a blank line before <?xml ...?>,
    # which Gazebo accepts and expat does not.
    stripped = text.lstrip()
    skipped_lines = text[:len(text) - len(stripped)].count(b'\n' if isinstance(text, bytes) else '\n')
    try:
        return ET.fromstring(stripped)
    except ET.ParseError as error:
        line = error.position[0] + skipped_lines if getattr(error, 'position', None) else None
        raise ModelFileError('not well-formed XML (%s)' % error, path, line) from None


def _sdf_root(text, path):
    root = _parse_xml(text, path)
    if root.tag != 'sdf':
        raise ModelFileError('root element is <%s>, not <sdf>' % root.tag, path)
    return root


def parse_world(text, path=None, model_paths=None) -> WorldSpec:
    """Read a world from SDF text (str or bytes); path only names it in messages.

    Includes are looked up in model_paths, by default Gazebo's model path now.
    """
    root = _sdf_root(text, path)
    worlds = root.findall('world')
    if not worlds:
        raise ModelFileError('no <world> element in this SDF', path)
    reader = _WorldReader(path, model_paths=model_paths)
    world = WorldSpec(name='default', path=path, sdf_version=root.get('version', ''))
    for extra in worlds[1:]:
        reader.skip('world %s' % extra.get('name', ''), 'only the first <world> is loaded')
    reader.read_world(worlds[0], world)
    world.skipped = reader.skipped
    return world


def load_world(path, model_paths=None) -> WorldSpec:
    """Read a .world file; a missing or unreadable file raises ModelFileError."""
    try:
        with open(path, 'rb') as stream:
            data = stream.read()
    except OSError as error:
        raise ModelFileError('cannot read world file: %s' % (error.strerror or error), path) from None
    return parse_world(data, os.fspath(path), model_paths)


def parse_sdf_models(text, path=None, scene_ambient=DEFAULT_SCENE_AMBIENT, robot_namespace='',
                     model_paths=None):
    """The <model>s of a model SDF (as spawn_model -sdf reads it): (models, skipped).

    An SDF that holds no <model> but a <world> with includes (what
    `spawn_model -database NAME` sends) gives the models those includes name.
    """
    root = _sdf_root(text, path)
    reader = _WorldReader(path, scene_ambient, robot_namespace, model_paths)
    reader.expand_includes(root, '', 0)
    elems = root.findall('model')
    if not elems and root.find('world') is not None:
        world = root.find('world')
        reader.expand_includes(world, '', 0)
        elems = world.findall('model')
        for include in world.findall('include'):
            reader._read_include(include, 'include')
    model_elems = {}
    for elem in elems:
        reader.add_model_elem(elem, model_elems, 'model')
    if not model_elems:
        raise ModelFileError('no <model> element in this SDF', path)
    graph = _FrameGraph({''})
    for name, elem in model_elems.items():
        graph.add(name, elem)
    models = []
    for name, elem in model_elems.items():
        model = reader.read_top_model(elem, name, graph, None)
        if model is not None:
            models.append(model)
    reader.report_missing_visuals()
    return models, reader.skipped


def read_spawned_model(text, name, path=None, robot_namespace='', model_paths=None):
    """The one model an SDF to spawn holds, renamed name: (Model, skipped).

    FlatsimError when the SDF holds no usable model or several, or a model with
    no shape flatsim can use. A robot (sensors, plugins) comes back with its
    RobotSpec in .robot, its own <pose> in .pose.
    """
    models, skipped = parse_sdf_models(text, path, robot_namespace=robot_namespace,
                                       model_paths=model_paths)
    if len(models) != 1:
        raise FlatsimError('the SDF must hold exactly one usable <model>, found %d' % len(models))
    model = models[0]
    if not model.collisions and not model.visuals:
        raise FlatsimError('the model has no shape flatsim can use%s'
                           % ''.join('; %s' % item for item in skipped))
    model.name = name
    return model, skipped


def model_link_poses(elem):
    """(link name, pose in the model frame) of a <model> element's links by its own poses, no <state>.

    Nested models' links are named 'nested::link'; links whose pose cannot be read are left out.
    """
    reader = _WorldReader(None, model_paths=[])
    model = Model(name=elem.get('name', ''), pose=Pose())
    reader._read_scope(_Scope(elem, IDENTITY, None, IDENTITY, model.name, ''), model, [])
    return model.links


def _sphere_radius(model):
    shapes = model.collisions + model.visuals
    if (not shapes or len(model.collisions) > 1 or len(model.visuals) > 1
            or any(geom.kind != 'sphere' for geom in shapes)):
        return None
    return max(geom.size[0] for geom in shapes)


def find_balls(world, min_radius=0.0):
    """Dynamic models made of one sphere (one sphere collision and/or one sphere visual)."""
    balls = []
    for model in world.models:
        if model.static:
            continue
        radius = _sphere_radius(model)
        if radius is not None and radius >= min_radius:
            balls.append(model)
    return balls


def white_balls(world):
    """The balls whose sphere visual renders pure white, the target the course chases."""
    return [model for model in find_balls(world) if model.visuals and model.visuals[0].unlit_white]


def apply_include_overrides(include, found):
    """An include's <name>, <pose> and <static> replace the model's own; its plugins are added."""
    name = _text(include, 'name')
    if name:
        found.set('name', name)
    for tag in ('pose', 'static'):
        override = include.find(tag)
        if override is None or found.tag != 'model' and tag == 'static':
            continue
        own = found.find(tag)
        if own is None:
            found.insert(0, copy.deepcopy(override))
        else:
            found[list(found).index(own)] = copy.deepcopy(override)
    if found.tag == 'model':
        for plugin in include.findall('plugin'):
            found.append(copy.deepcopy(plugin))
