"""A robot saved inside a world file, read as the URDF it was spawned from.

Gazebo's "Save World" writes a spawned robot into the .world as an SDF
<model>: its links (fixed joints already lumped), its wheel joints, its
<sensor>s with their gazebo_ros plugins and its model plugins (the diff
drive). Gazebo runs that model as it ran the spawned robot. To do the same,
flatsim writes the model back as URDF, with the sensors and plugins in
<gazebo> tags, and reads that with the URDF reader, so a saved robot gets the
same drive, camera and lidar as a spawned one.

Only top-level models that are not static and carry a sensor or a model
plugin count as robots. No ROS here.
"""
import xml.etree.ElementTree as ET

import numpy as np

from flatsim.errors import FlatsimError
from flatsim.pose import Pose

# SDF writes an unlimited revolute joint with limits of +-1e16.
UNLIMITED = 1e15
URDF_JOINT_TYPES = {'revolute': 'revolute', 'continuous': 'continuous', 'prismatic': 'prismatic',
                    'fixed': 'fixed'}


def is_saved_robot(model_elem):
    """True for a dynamic model with a sensor on a link or a plugin of its own."""
    if (model_elem.findtext('static') or '').strip().lower() in ('1', 'true'):
        return False
    return (model_elem.find('plugin') is not None
            or model_elem.find('link/sensor') is not None)


def _origin(pose):
    return ET.Element('origin', xyz='%r %r %r' % (pose.x, pose.y, pose.z),
                      rpy='%r %r %r' % (pose.roll, pose.pitch, pose.yaw))


def _pose(elem):
    """elem's own <pose> (relative to its parent link), as Gazebo 9 reads it."""
    try:
        return Pose.parse(elem.findtext('pose') or '')
    except FlatsimError as error:
        raise FlatsimError('%s %s: %s' % (elem.tag, elem.get('name', ''), error)) from None


def _geometry(geometry):
    """URDF <geometry> for an SDF one; None for shapes URDF has no word for."""
    out = ET.Element('geometry')
    shape = next(iter(geometry), None) if geometry is not None else None
    if shape is None:
        return None
    if shape.tag == 'box':
        ET.SubElement(out, 'box', size=(shape.findtext('size') or '1 1 1').strip())
    elif shape.tag == 'cylinder':
        ET.SubElement(out, 'cylinder', radius=(shape.findtext('radius') or '1').strip(),
                      length=(shape.findtext('length') or '1').strip())
    elif shape.tag == 'sphere':
        ET.SubElement(out, 'sphere', radius=(shape.findtext('radius') or '1').strip())
    elif shape.tag == 'mesh':
        mesh = ET.SubElement(out, 'mesh', filename=(shape.findtext('uri') or '').strip())
        if (shape.findtext('scale') or '').strip():
            mesh.set('scale', shape.findtext('scale').strip())
    else:
        return None
    return out


def _link(link_elem, skipped):
    name = link_elem.get('name')
    link = ET.Element('link', name=name)
    inertial = link_elem.find('inertial')
    if inertial is not None and inertial.findtext('mass'):
        out = ET.SubElement(link, 'inertial')
        out.append(_origin(_pose(inertial)))
        ET.SubElement(out, 'mass', value=inertial.findtext('mass').strip())
        inertia = inertial.find('inertia')
        if inertia is not None:
            ET.SubElement(out, 'inertia', {key: (inertia.findtext(key) or '0').strip() for key in
                                           ('ixx', 'ixy', 'ixz', 'iyy', 'iyz', 'izz')})
    for role in ('collision', 'visual'):
        for part in link_elem.findall(role):
            geometry = _geometry(part.find('geometry'))
            if geometry is None:
                skipped.append('%s %s of link %s: no box, cylinder, sphere or mesh'
                               % (role, part.get('name', ''), name))
                continue
            out = ET.SubElement(link, role, name=part.get('name', ''))
            out.append(_origin(_pose(part)))
            out.append(geometry)
    return link


def _joint(joint_elem, link_poses):
    name = joint_elem.get('name')
    parent = (joint_elem.findtext('parent') or '').strip()
    child = (joint_elem.findtext('child') or '').strip()
    for role, link in (('parent', parent), ('child', child)):
        if link not in link_poses:
            raise FlatsimError('joint %s: its %s %r is not a link of the model' % (name, role, link))
    kind = joint_elem.get('type', '')
    axis = joint_elem.find('axis')
    xyz = np.array([1.0, 0.0, 0.0])
    lower = upper = None
    if axis is not None:
        try:
            xyz = np.array([float(v) for v in (axis.findtext('xyz') or '1 0 0').split()])
            lower = float(axis.findtext('limit/lower')) if axis.findtext('limit/lower') else None
            upper = float(axis.findtext('limit/upper')) if axis.findtext('limit/upper') else None
        except ValueError:
            raise FlatsimError('joint %s: axis or limit is not numbers' % name) from None
        if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
            raise FlatsimError('joint %s: axis xyz is not three finite numbers' % name)
        in_model_frame = ((axis.findtext('use_parent_model_frame') or '').strip().lower()
                          in ('1', 'true')
                          or (axis.find('xyz') is not None
                              and axis.find('xyz').get('expressed_in') == '__model__'))
        if in_model_frame:
            xyz = link_poses[child].matrix()[:3, :3].T @ xyz
    if kind == 'revolute' and (lower is None or upper is None
                               or not (abs(lower) < UNLIMITED and abs(upper) < UNLIMITED)):
        kind = 'continuous'
    joint = ET.Element('joint', name=name, type=URDF_JOINT_TYPES.get(kind, 'floating'))
    offset = Pose.from_matrix(np.linalg.inv(link_poses[parent].matrix())
                              @ link_poses[child].matrix())
    joint.append(_origin(offset))
    ET.SubElement(joint, 'parent', link=parent)
    ET.SubElement(joint, 'child', link=child)
    ET.SubElement(joint, 'axis', xyz='%r %r %r' % tuple(float(v) for v in xyz))
    if kind in ('revolute', 'prismatic'):
        ET.SubElement(joint, 'limit', lower=repr(lower if lower is not None else 0.0),
                      upper=repr(upper if upper is not None else 0.0),
                      effort=(axis.findtext('limit/effort') or '0').strip(),
                      velocity=(axis.findtext('limit/velocity') or '0').strip())
    return joint


def saved_robot_urdf(model_elem, name):
    """(URDF text, notes) for a saved robot's <model>; FlatsimError when it is not a tree of
    links flatsim can read that way (nested models, links without a joint)."""
    if model_elem.find('model') is not None or model_elem.find('include') is not None:
        raise FlatsimError('it holds nested models or includes')
    links = model_elem.findall('link')
    if not links:
        raise FlatsimError('it has no <link>')
    skipped = []
    robot = ET.Element('robot', name=name)
    link_poses = {}
    for link_elem in links:
        if not link_elem.get('name'):
            raise FlatsimError('a <link> has no name')
        link_poses[link_elem.get('name')] = _pose(link_elem)
        robot.append(_link(link_elem, skipped))
    for joint_elem in model_elem.findall('joint'):
        robot.append(_joint(joint_elem, link_poses))
    for link_elem in links:
        sensors = link_elem.findall('sensor')
        if sensors:
            gazebo = ET.SubElement(robot, 'gazebo', reference=link_elem.get('name'))
            gazebo.extend(sensors)
    plugins = model_elem.findall('plugin')
    if plugins:
        ET.SubElement(robot, 'gazebo').extend(plugins)
    return ET.tostring(robot, encoding='unicode'), skipped
