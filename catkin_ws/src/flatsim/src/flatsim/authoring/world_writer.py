"""Save World As: the running world as a .world file, the way Gazebo's window writes it.

Gazebo writes `<sdf version='1.6'><world name=...>` with every element of the
world it loaded (lights, physics, scene, gui, plugins...), a `ground_plane`
model and a `sun` light, and every model inline at its current pose. Here:
  - a model from the world file keeps its own XML (includes expanded, as
    Gazebo writes them), with its <pose> set to where it is now; where the
    file's <state> moved its links, their poses say so instead;
  - the world's <state> is dropped, so that no stale pose wins on reload;
  - models spawned as SDF or dropped in from the Insert tab follow, from
    the XML they came with;
  - a robot spawned from URDF (the one world.launch spawns) is left out,
    and a note says so: the course's world must not hold the robot;
  - `<include>` of ground_plane and sun is written out inline from the model
    path; physics, the sun and the ground plane are added when missing.
Files are SDF 1.6, or the version the world was read in when that is another
one (flatsim does not convert SDF between versions). No ROS here.
"""
import copy
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import List

import numpy as np

from flatsim.authoring.sdf_text import child, element_depth, set_pose, to_text
from flatsim.loading.model_path import find_model, model_name_from_uri
from flatsim.loading.sdf_world import IMPLICIT_INCLUDES, apply_include_overrides, model_link_poses
from flatsim.pose import Pose
from flatsim.world.sim_models import FROM_URDF, FROM_WORLD, MAX_WRITTEN_DEPTH

SDF_VERSION = '1.6'
# Gazebo's physics when a world sets none.
DEFAULT_PHYSICS = (('max_step_size', '0.001'), ('real_time_factor', '1'), ('real_time_update_rate', '1000'))


@dataclass
class SavedWorld:
    text: str                                   # the .world file
    notes: List[str] = field(default_factory=list)  # what was left out or added, and why


def _planar(x, y, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    mat = np.eye(4)
    mat[:2, :2] = [[c, -s], [s, c]]
    mat[:2, 3] = (x, y)
    return mat


def current_pose(sim, name):
    """The model's world pose now: its start pose moved as the plane moved it.

    flatsim moves moving models in x, y and yaw only; height, roll and pitch
    stay as the file had them. A model that stands still is where it was last
    put, in full.
    """
    model = sim.models[name]
    start = model.initial_pose
    if model.handle is None:
        return sim.model_pose(name)
    now = sim.model_pose(name)
    moved = _planar(now.x, now.y, now.yaw) @ np.linalg.inv(_planar(start.x, start.y, start.yaw))
    return Pose.from_matrix(moved @ start.matrix())


def _model_element(sim, name, origin):
    elem = ET.fromstring(origin.sdf)
    elem.set('name', name)
    set_pose(elem, current_pose(sim, name))
    source = getattr(sim.models[name], 'source', None)
    if origin.kind == FROM_WORLD and source is not None:
        _restore_link_poses(elem, source.links)
    return elem


def _same_pose(a, b, tolerance=1e-9):
    return np.allclose(a.matrix(), b.matrix(), rtol=0.0, atol=tolerance)


def _restore_link_poses(elem, loaded_links):
    """Put the links where the world's <state> had them, now that the state is not written.

    When the state moved any link, every nested model's pose becomes zero and
    every link's pose its pose in the top model frame, so that each link
    reads back where it was loaded.
    """
    own = dict(model_link_poses(elem))
    if all(link in own and _same_pose(own[link], pose) for link, pose in loaded_links):
        return
    loaded = dict(loaded_links)
    pending = [(elem, '')]
    while pending:
        scope, prefix = pending.pop()
        for item in scope:
            if item.tag == 'link' and prefix + item.get('name', '') in loaded:
                set_pose(item, loaded[prefix + item.get('name', '')])
            elif item.tag == 'model':
                set_pose(item, Pose())
                pending.append((item, '%s%s::' % (prefix, item.get('name', ''))))


def _inline_include(include, notes):
    """The model or light an implicit include names, read from the model path; None if not found."""
    uri = (include.findtext('uri') or '').strip()
    entry = find_model(model_name_from_uri(uri))
    if entry is None or entry.problem:
        notes.append('%s is not on the model path; kept as an <include>' % uri)
        return None
    root = ET.parse(entry.sdf).getroot()
    found = root.find('model')
    if found is None:
        found = root.find('light')
    found = copy.deepcopy(found)
    apply_include_overrides(include, found)
    return found


def _shipped(uri):
    return _inline_include(ET.fromstring('<include><uri>%s</uri></include>' % uri), [])


def _version(world):
    version = getattr(world, 'sdf_version', '') or SDF_VERSION
    try:
        tuple(int(part) for part in version.split('.'))
    except ValueError:
        return SDF_VERSION
    return version


def world_sdf(sim, world=None, name=None) -> SavedWorld:
    """The .world text for the simulation now; world is the WorldSpec it was loaded from, if any."""
    notes = []
    root = ET.Element('sdf', version=_version(world))
    world_elem = child(root, 'world', name=name or (world.name if world is not None else 'default'))
    written = set()
    for part in world.parts if world is not None else ():
        if part.model:
            origin = sim.origins.get(part.model)
            if origin is not None and origin.kind == FROM_WORLD and origin.sdf:
                world_elem.append(_model_element(sim, part.model, origin))
                written.add(part.model)
            continue
        elem = part.element
        if element_depth(elem) > MAX_WRITTEN_DEPTH:
            notes.append('a <%s> nested deeper than %d levels; left out' % (elem.tag, MAX_WRITTEN_DEPTH))
            continue
        if elem.tag == 'include' and (elem.findtext('uri') or '').strip() in IMPLICIT_INCLUDES:
            elem = _inline_include(elem, notes) or elem
        world_elem.append(copy.deepcopy(elem))
    for model_name, origin in sim.origins.items():
        if model_name in written:
            continue
        if origin.kind == FROM_URDF:
            notes.append('%s is a robot spawned from URDF (the launch file spawns it); left out of '
                         'the world, which must not hold the robot' % model_name)
        elif not origin.sdf:
            notes.append('%s came with no SDF to write; left out' % model_name)
        else:
            world_elem.append(_model_element(sim, model_name, origin))
    _add_missing_essentials(world_elem, notes)
    return SavedWorld(to_text(root, declaration=False), notes)


def _add_missing_essentials(world_elem, notes):
    """Physics, the sun and the ground plane, as every world Gazebo saves has them."""
    children = list(world_elem)
    if not any(elem.tag == 'physics' for elem in children):
        physics = ET.Element('physics', type='ode')
        for tag, text in DEFAULT_PHYSICS:
            child(physics, tag, text)
        world_elem.append(physics)
    has_sun = any(elem.tag == 'light' and elem.get('name') == 'sun' for elem in children)
    has_ground = any(elem.tag == 'model' and elem.get('name') == 'ground_plane' for elem in children)
    includes = {(elem.findtext('uri') or '').strip() for elem in children if elem.tag == 'include'}
    if not has_ground and 'model://ground_plane' not in includes:
        ground = _shipped('model://ground_plane')
        if ground is not None:
            world_elem.insert(0, ground)
            notes.append('added the ground_plane model, which every Gazebo world has')
    if not has_sun and 'model://sun' not in includes:
        sun = _shipped('model://sun')
        if sun is not None:
            world_elem.insert(0, sun)
            notes.append('added the sun, which every Gazebo world has')

