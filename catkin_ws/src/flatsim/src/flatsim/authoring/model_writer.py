"""The Model Editor's output: model.config and model.sdf for a design of simple shapes.

A design is a model name, a static flag and links; each link has one or more
shapes (box, sphere or cylinder), each used for both the visual and the
collision, with a pose in the link and Blinn-Phong colours. A link's mass is
shared among its shapes by volume, and its inertia is worked out from them
about the link origin. The files are shaped as Gazebo 11's Model Editor
writes them (SDF 1.7, model.config naming model.sdf), which is the course's
`my_ball`: a sphere of radius 0.1 with ambient, diffuse, specular and
emissive all 1 1 1 1. No ROS here.
"""
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from typing import List, Optional, Tuple

import numpy as np

from flatsim.authoring.saving import check_folder_name, replace_folder
from flatsim.authoring.sdf_text import child, is_finite, numbers, pose_text, to_text
from flatsim.errors import AuthoringError
from flatsim.pose import Pose

SDF_VERSION = '1.7'
RGBA = Tuple[float, float, float, float]
# Gazebo/Grey, the material the Model Editor gives a new shape.
GREY = dict(ambient=(0.3, 0.3, 0.3, 1.0), diffuse=(0.7, 0.7, 0.7, 1.0),
            specular=(0.01, 0.01, 0.01, 1.0), emissive=(0.0, 0.0, 0.0, 1.0))
SHAPE_SIZES = {'box': 3, 'sphere': 1, 'cylinder': 2}
# The largest shape or wall an editor makes (m): bigger is a slip of the keyboard, and would
# cover the whole world.
MAX_SIZE = 1000.0


@dataclass
class Material:
    ambient: RGBA = GREY['ambient']
    diffuse: RGBA = GREY['diffuse']
    specular: RGBA = GREY['specular']
    emissive: RGBA = GREY['emissive']


@dataclass
class Shape:
    kind: str                                  # 'box' | 'sphere' | 'cylinder'
    size: Tuple[float, ...]                    # box (x, y, z), sphere (radius,), cylinder (radius, length)
    pose: Pose = field(default_factory=Pose)   # in the link frame
    material: Material = field(default_factory=Material)


@dataclass
class LinkDesign:
    shapes: List[Shape]
    name: str = 'link'
    # In the model frame; None stands the link's shapes on the floor, as the editor inserts them.
    pose: Optional[Pose] = None
    mass: float = 1.0                          # kg


@dataclass
class ModelDesign:
    name: str
    links: List[LinkDesign]
    static: bool = False
    description: str = ''
    author_name: str = ''
    author_email: str = ''
    version: str = '1.0'


def check_name(name, what='model'):
    """A model or link name Gazebo and a folder can both hold."""
    if not isinstance(name, str) or not name.strip():
        raise AuthoringError('the %s needs a name' % what)
    if '/' in name or '\\' in name or '\0' in name or name in ('.', '..') or '::' in name:
        raise AuthoringError("the %s name %r may not hold '/', '\\\\', '::' or be '.' or '..'" % (what, name))
    return name


def _check_rgba(values, what):
    if not (isinstance(values, (tuple, list)) and len(values) == 4 and is_finite(*values)
            and all(0.0 <= v <= 1.0 for v in values)):
        raise AuthoringError('%s must be four numbers from 0 to 1, got %r' % (what, values))


def _check_pose(pose, what):
    if not is_finite(pose.x, pose.y, pose.z, pose.roll, pose.pitch, pose.yaw):
        raise AuthoringError('%s pose must be finite numbers, got %r' % (what, pose))


def check_design(design):
    """AuthoringError naming the first thing wrong with the design."""
    check_name(design.name)
    if not design.links:
        raise AuthoringError('model %s has no link' % design.name)
    seen = set()
    for link in design.links:
        check_name(link.name, 'link')
        if link.name in seen:
            raise AuthoringError('model %s has two links named %s' % (design.name, link.name))
        seen.add(link.name)
        if not (is_finite(link.mass) and link.mass > 0):
            raise AuthoringError('link %s: the mass must be a positive number, got %r' % (link.name, link.mass))
        if link.pose is not None:
            _check_pose(link.pose, 'link %s' % link.name)
        if not link.shapes:
            raise AuthoringError('link %s has no shape' % link.name)
        for shape in link.shapes:
            what = 'link %s: %s' % (link.name, shape.kind)
            if shape.kind not in SHAPE_SIZES:
                raise AuthoringError('link %s: a shape is a box, sphere or cylinder, not %r'
                                     % (link.name, shape.kind))
            size = tuple(shape.size)
            if len(size) != SHAPE_SIZES[shape.kind] or not is_finite(*size) or not all(v > 0 for v in size):
                raise AuthoringError('%s size must be %d positive numbers, got %r'
                                     % (what, SHAPE_SIZES[shape.kind], shape.size))
            if max(size) > MAX_SIZE:
                raise AuthoringError('%s size %g m is more than the %g m a shape may be'
                                     % (what, max(size), MAX_SIZE))
            _check_pose(shape.pose, what)
            for tag in ('ambient', 'diffuse', 'specular', 'emissive'):
                _check_rgba(getattr(shape.material, tag), '%s %s' % (what, tag))
    return design


def _volume(shape):
    if shape.kind == 'box':
        return float(np.prod(shape.size))
    if shape.kind == 'sphere':
        return 4.0 / 3.0 * math.pi * shape.size[0] ** 3
    radius, length = shape.size
    return math.pi * radius ** 2 * length


def _own_inertia(shape, mass):
    """The inertia tensor of a solid shape about its centre, in its own frame."""
    if shape.kind == 'box':
        x, y, z = shape.size
        return mass / 12.0 * np.diag([y * y + z * z, x * x + z * z, x * x + y * y])
    if shape.kind == 'sphere':
        return np.eye(3) * 0.4 * mass * shape.size[0] ** 2
    radius, length = shape.size
    across = mass * (3 * radius ** 2 + length ** 2) / 12.0
    return np.diag([across, across, 0.5 * mass * radius ** 2])


def link_inertia(link):
    """The link's inertia about its origin: its mass shared by volume, shapes moved by parallel axes."""
    volumes = [_volume(shape) for shape in link.shapes]
    total = np.zeros((3, 3))
    for shape, volume in zip(link.shapes, volumes):
        mass = link.mass * volume / sum(volumes)
        rot = shape.pose.matrix()[:3, :3]
        offset = np.array([shape.pose.x, shape.pose.y, shape.pose.z])
        total += rot @ _own_inertia(shape, mass) @ rot.T
        total += mass * (offset @ offset * np.eye(3) - np.outer(offset, offset))
    return total


def _lowest(shape):
    """The lowest height of the shape in the link frame."""
    rot = shape.pose.matrix()[:3, :3]
    if shape.kind == 'box':
        reach = sum(abs(rot[2, axis]) * shape.size[axis] / 2 for axis in range(3))
    elif shape.kind == 'sphere':
        reach = shape.size[0]
    else:
        radius, length = shape.size
        upright = abs(rot[2, 2])
        reach = upright * length / 2 + radius * math.sqrt(max(0.0, 1.0 - upright ** 2))
    return shape.pose.z - reach


def link_pose(link):
    """The link's pose in the model; by default raised so that its lowest shape rests on the floor."""
    if link.pose is not None:
        return link.pose
    return Pose(z=max(0.0, -min(_lowest(shape) for shape in link.shapes)))


def _geometry(parent, shape):
    geometry = child(parent, 'geometry')
    if shape.kind == 'box':
        child(child(geometry, 'box'), 'size', numbers(shape.size))
    elif shape.kind == 'sphere':
        child(child(geometry, 'sphere'), 'radius', numbers(shape.size))
    else:
        cylinder = child(geometry, 'cylinder')
        child(cylinder, 'radius', numbers(shape.size[:1]))
        child(cylinder, 'length', numbers(shape.size[1:]))


def _surface(collision):
    surface = child(collision, 'surface')
    friction = child(surface, 'friction')
    ode = child(friction, 'ode')
    for tag, text in (('mu', '1'), ('mu2', '1'), ('fdir1', '0 0 0'), ('slip1', '0'), ('slip2', '0')):
        child(ode, tag, text)
    torsional = child(friction, 'torsional')
    for tag, text in (('coefficient', '1'), ('patch_radius', '0'), ('surface_radius', '0'),
                      ('use_patch_radius', '1')):
        child(torsional, tag, text)
    child(child(torsional, 'ode'), 'slip', '0')
    bounce = child(surface, 'bounce')
    child(bounce, 'restitution_coefficient', '0')
    child(bounce, 'threshold', '1e+06')
    contact = child(surface, 'contact')
    for tag, text in (('collide_without_contact', '0'), ('collide_without_contact_bitmask', '1'),
                      ('collide_bitmask', '1')):
        child(contact, tag, text)
    contact_ode = child(contact, 'ode')
    for tag, text in (('soft_cfm', '0'), ('soft_erp', '0.2'), ('kp', '1e+13'), ('kd', '1'),
                      ('max_vel', '0.01'), ('min_depth', '0')):
        child(contact_ode, tag, text)
    bullet = child(contact, 'bullet')
    for tag, text in (('split_impulse', '1'), ('split_impulse_penetration_threshold', '-0.01'),
                      ('soft_cfm', '0'), ('soft_erp', '0.2'), ('kp', '1e+13'), ('kd', '1')):
        child(bullet, tag, text)


def _link(model, link):
    elem = child(model, 'link', name=link.name)
    inertial = child(elem, 'inertial')
    child(inertial, 'mass', numbers([link.mass]))
    tensor = link_inertia(link)
    inertia = child(inertial, 'inertia')
    for tag, (row, col) in (('ixx', (0, 0)), ('ixy', (0, 1)), ('ixz', (0, 2)),
                            ('iyy', (1, 1)), ('iyz', (1, 2)), ('izz', (2, 2))):
        # Six significant digits, as Gazebo writes them: the tensor is an estimate anyway.
        child(inertia, tag, numbers([float('%.6g' % tensor[row, col])]))
    child(inertial, 'pose', '0 0 0 0 -0 0')
    for tag, text in (('self_collide', '0'), ('enable_wind', '0'), ('kinematic', '0')):
        child(elem, tag, text)
    child(elem, 'pose', pose_text(link_pose(link)))
    child(elem, 'gravity', '1')
    for index, shape in enumerate(link.shapes):
        # The editor's names: visual and collision, then visual_1, collision_1, ...
        suffix = '_%d' % index if index else ''
        visual = child(elem, 'visual', name='visual' + suffix)
        _geometry(visual, shape)
        material = child(visual, 'material')
        script = child(material, 'script')
        child(script, 'name', 'Gazebo/Grey')
        child(script, 'uri', 'file://media/materials/scripts/gazebo.material')
        child(child(material, 'shader', type='pixel'), 'normal_map', '__default__')
        for tag in ('ambient', 'diffuse', 'specular', 'emissive'):
            child(material, tag, numbers(getattr(shape.material, tag)))
        child(visual, 'pose', pose_text(shape.pose))
        child(visual, 'transparency', '0')
        child(visual, 'cast_shadows', '1')
        collision = child(elem, 'collision', name='collision' + suffix)
        child(collision, 'laser_retro', '0')
        child(collision, 'max_contacts', '10')
        child(collision, 'pose', pose_text(shape.pose))
        _geometry(collision, shape)
        _surface(collision)


def model_sdf(design):
    """The model.sdf text for a design (checked first)."""
    check_design(design)
    root = ET.Element('sdf', version=SDF_VERSION)
    model = child(root, 'model', name=design.name)
    for link in design.links:
        _link(model, link)
    child(model, 'static', '1' if design.static else '0')
    child(model, 'allow_auto_disable', '1')
    return to_text(root)


def model_config(design):
    """The model.config text, as Gazebo's save dialog writes it."""
    check_name(design.name)
    root = ET.Element('model')
    child(root, 'name', design.name)
    child(root, 'version', design.version)
    child(root, 'sdf', 'model.sdf', version=SDF_VERSION)
    author = child(root, 'author')
    child(author, 'name', design.author_name)
    child(author, 'email', design.author_email)
    child(root, 'description', design.description)
    ET.indent(root, '    ')
    return '<?xml version="1.0" ?>\n' + ET.tostring(root, encoding='unicode', short_empty_elements=False) + '\n'


def folder_name(model_name, what='model'):
    """The folder Gazebo's save dialog makes for a model: its name with spaces as underscores,
    one plain folder name (flatsim.authoring.saving.check_folder_name)."""
    return check_folder_name(check_name(model_name, what).replace(' ', '_'), '%s name' % what)


def save_model_files(model_name, config_text, sdf_text, allowed_folders, folder):
    """Write folder/<model folder>/model.config and model.sdf.

    Returns the model folder. Nothing is written when a name is refused, and a failure part way
    leaves the old model folder as it was (flatsim.authoring.saving.replace_folder).
    """
    texts = {'model.config': config_text, 'model.sdf': sdf_text}
    return replace_folder(allowed_folders, folder, folder_name(model_name), texts)

