"""Gazebo's Scale tool: a model that is one simple shape (a box, a cylinder or a sphere, as the
toolbar makes them) gets new sizes, and the simulator takes the model back with them.

As in Gazebo, only such models scale: a sphere stays round (one factor for its radius), a
cylinder stays round (one factor for its radius, one for its length), a box takes three. The
model's SDF (what Save World As writes) gets the new sizes, so that the saved world holds them,
and the model is placed anew where it stands, under its name: its colliders, the lidar and the
camera see the new shape at once. No ROS here.
"""
import copy
import math
import xml.etree.ElementTree as ET

from flatsim.errors import FlatsimError
from flatsim.loading.sdf_world import read_spawned_model
from flatsim.pose import Pose
from flatsim.world.sim_models import model_origin

SCALABLE = ('box', 'cylinder', 'sphere')
# A scaled shape's sizes stay within these (m).
MIN_SIZE = 0.001
MAX_SIZE = 100.0


def simple_shape(model):
    """The shape a model record (flatsim.loading.sdf_world.Model) is made of, when it is one
    simple shape that Gazebo's Scale tool scales: 'box', 'cylinder' or 'sphere'; else None."""
    if model is None or getattr(model, 'robot', None) is not None or len(model.links) != 1:
        return None
    geoms = list(model.collisions) + list(model.visuals)
    kinds = {geom.kind for geom in geoms}
    if len(kinds) != 1 or any(geom.from_mesh for geom in geoms):
        return None
    kind = kinds.pop()
    return kind if kind in SCALABLE else None


def _furthest_from_one(*factors):
    """The factor that changes most (a drag moves one handle; the others stay at 1)."""
    return max(factors, key=lambda factor: abs(math.log(factor)))


def shape_factors(kind, scale):
    """The factors for the shape's own sizes (box: x, y, z; cylinder: radius, length; sphere:
    radius) from the scale [sx, sy, sz] asked for."""
    sx, sy, sz = scale
    if kind == 'box':
        return (sx, sy, sz)
    if kind == 'cylinder':
        return (_furthest_from_one(sx, sy), sz)
    return (_furthest_from_one(sx, sy, sz),)


def _numbers(element, count, what):
    try:
        values = [float(value) for value in (element.text or '').split()]
    except ValueError:
        values = []
    if len(values) != count:
        raise FlatsimError('its %s is not %d numbers: %r' % (what, count, element.text))
    return values


def _scaled(values, factors, name):
    scaled = [value * factor for value, factor in zip(values, factors)]
    for value in scaled:
        if not MIN_SIZE <= abs(value) <= MAX_SIZE:
            raise FlatsimError('%s would be %g m; a scaled shape is %g to %g m'
                               % (name, value, MIN_SIZE, MAX_SIZE))
    return ' '.join('%.6g' % value for value in scaled)


def scaled_element(element, kind, factors, name):
    """A copy of a <model> element whose every <geometry><KIND> has its sizes times factors."""
    scaled = copy.deepcopy(element)
    shapes = scaled.findall('.//geometry/%s' % kind)
    if not shapes:
        raise FlatsimError('%s has no %s in its SDF to scale' % (name, kind))
    for shape in shapes:
        if kind == 'box':
            size = shape.find('size')
            if size is None:
                size = ET.SubElement(shape, 'size')
                size.text = '1 1 1'
            size.text = _scaled(_numbers(size, 3, 'box size'), factors, '%s\'s size' % name)
        else:
            radius = shape.find('radius')
            if radius is None:
                radius = ET.SubElement(shape, 'radius')
                radius.text = '0.5' if kind == 'sphere' else '1'
            radius.text = _scaled(_numbers(radius, 1, 'radius'), factors[:1], '%s\'s radius' % name)
            if kind == 'cylinder':
                length = shape.find('length')
                if length is None:
                    length = ET.SubElement(shape, 'length')
                    length.text = '1'
                length.text = _scaled(_numbers(length, 1, 'length'), factors[1:],
                                      '%s\'s length' % name)
    return scaled


def rescale(sim, name, scale):
    """Scale model name of sim by scale [sx, sy, sz] (positive factors); call under the
    simulator's lock. FlatsimError says why a model cannot be scaled, and then nothing changed.
    Returns the new shape's sizes."""
    model = sim.models.get(name)
    if model is None:
        raise FlatsimError('there is no model named %r' % name)
    if not all(math.isfinite(factor) and factor > 0 for factor in scale):
        raise FlatsimError('scale factors must be positive numbers, got %r' % (list(scale),))
    kind = simple_shape(getattr(model, 'source', None)) if getattr(model, 'spec', None) is None else None
    if kind is None:
        raise FlatsimError('%s is not a simple shape: only a model of one box, cylinder or sphere '
                           'is scaled, as in Gazebo' % name)
    origin = sim.origins.get(name)
    if origin is None or not origin.sdf:
        raise FlatsimError('%s has no SDF of its own to scale' % name)
    element = scaled_element(ET.fromstring(origin.sdf), kind, shape_factors(kind, scale), name)
    text = '<sdf version="1.6">%s</sdf>' % ET.tostring(element, encoding='unicode')
    loaded, _ = read_spawned_model(text, name)
    loaded.pose = Pose()
    loaded.element = element
    pose = sim.model_pose(name)
    start = model.initial_pose
    sim.delete_model(name)
    try:
        placed = sim.add_world_model(loaded, pose, model_origin(origin.kind, element))
    except Exception:
        # Put back as it was: a refused scale changes nothing.
        sim.add_world_model(model.source, pose, origin)
        sim.models[name].initial_pose = start
        raise
    # Reset Model Poses still puts it where the world started it.
    placed.initial_pose = start
    geoms = loaded.collisions or loaded.visuals
    return list(geoms[0].size)
