"""Read a URDF robot description and its <gazebo> plugin tags into a RobotSpec.

Names, defaults and namespacing follow gazebo_ros (noetic) so that a course
robot written for Gazebo publishes on the same topics and frames here.
"""
import math
import os
import xml.dom.minidom
from xml.etree import ElementTree
from xml.parsers import expat

import cv2
import numpy as np

from flatsim.errors import Adjusted, FlatsimError, ModelFileError, Skipped
from flatsim.loading.config import (CameraConfig, DriveConfig, Joint, LaserConfig, Link, RobotSpec,
                                    Steering, Wheel)
from flatsim.loading.meshes import MeshError, MeshNotFound, describe, find_mesh, mesh_boxes
from flatsim.loading.ros_control import ROS_CONTROL_PLUGIN, read_articulation, read_ros_control_plugin
from flatsim.pose import Pose
from flatsim.world.drive import MIN_UPDATE_RATE

DIFF_DRIVE_PLUGIN = 'libgazebo_ros_diff_drive.so'
SKID_STEER_PLUGIN = 'libgazebo_ros_skid_steer_drive.so'
PLANAR_MOVE_PLUGIN = 'libgazebo_ros_planar_move.so'
TRICYCLE_PLUGIN = 'libgazebo_ros_tricycle_drive.so'
DRIVE_PLUGINS = (DIFF_DRIVE_PLUGIN, SKID_STEER_PLUGIN, PLANAR_MOVE_PLUGIN, TRICYCLE_PLUGIN)
# A model plugin flatsim does not provide counts as a drive when its file name or one of
# its tags says so; the tags that name its command topic, most specific first.
DRIVE_WORDS = ('drive', 'steer', 'move', 'wheel', 'mecanum', 'omni', 'ackermann', 'tricycle',
               'locomotion', 'cmd_vel')
# Plugins whose names hold such a word without being drives (gazebo_plugins' wheel slip).
NOT_DRIVES = ('wheel_slip',)
COMMAND_TAGS = ('commandTopic', 'command_topic', 'cmdVelTopic', 'cmd_vel_topic', 'cmdTopic',
                'cmd_topic', 'twistTopic', 'velocityTopic', 'topicName', 'topic')
# A joint axis whose horizontal part is shorter than this does not roll a wheel on the ground.
MIN_ROLLING_AXIS = 0.1
# A steering axis needs at least this vertical part to turn a wheel in the ground plane.
MIN_STEERING_AXIS = 0.9
CAMERA_PLUGINS = {'libgazebo_ros_camera.so': 'camera',
                  'libgazebo_ros_openni_kinect.so': 'openni_kinect'}
LASER_PLUGINS = ('libgazebo_ros_laser.so', 'libgazebo_ros_gpu_laser.so')
CAMERA_SENSOR_TYPES = ('camera', 'depth')
LASER_SENSOR_TYPES = ('ray', 'gpu_ray')

# Joints that keep a link attached to the body at a known pose (position 0).
ATTACHED_JOINT_TYPES = ('fixed', 'continuous', 'revolute', 'prismatic')
CIRCLE_POINTS = 32
# Larger sensors would need gigabytes per frame or scan: refused as the bad input they are.
# 16384 is the largest texture side common GPUs render, so Gazebo cannot go beyond it either.
MAX_IMAGE_SIDE = 16384
MAX_LASER_SAMPLES = 100000
# Hz: one update per step of flatsim's finest physics step (10 us).
MAX_SENSOR_RATE = 1e5
# Beyond this (m) the footprint loses precision in OpenCV's float32 hull and physics diverges.
MAX_FOOTPRINT_REACH = 1e6
# A footprint thinner than this (m^2) cannot make a physics body.
MIN_FOOTPRINT_AREA = 1e-6
# Half the side of the square that stands in for a point when the hull is degenerate (m).
POINT_PAD = 0.05
# A hull vertex closer than this to the line through its neighbours is dropped (m).
FLAT_VERTEX_TOLERANCE = 1e-4


def expand_xacro(path, mappings=None):
    """Expand a xacro file (with `name:=value` mappings) into URDF text.

    `$(find pkg)` is resolved through ROS_PACKAGE_PATH, as roslaunch does.
    """
    import xacro
    from roslaunch import substitution_args
    # roslaunch caches one package crawl per process; a later ROS_PACKAGE_PATH must count.
    substitution_args._rospack = None
    try:
        doc = xacro.process_file(str(path), mappings=dict(mappings or {}))
        return doc.toprettyxml(indent='  ')
    except Exception as err:  # noqa: BLE001 - xacro raises many types (its own, rospkg, expat, OSError)
        raise ModelFileError('xacro failed: %s' % (str(err) or type(err).__name__),
                             path=str(path)) from None


def load_robot(urdf_xml, name=None, source=None, robot_namespace=''):
    """Build a RobotSpec from URDF text that xacro has already expanded.

    name: the spawned model name (defaults to <robot name>); gazebo_ros uses it
      only when a plugin has an empty <robotNamespace>.
    source: file name or parameter name for error messages.
    robot_namespace: what spawn_model's -robot_namespace gives plugins that have
      no <robotNamespace> ('' is the root namespace, where names stay relative).
    """
    return _RobotReader(urdf_xml, name, source, robot_namespace).read()


def link_pose(spec, link):
    """Pose of `link` in the root link frame, with every movable joint at position 0."""
    if link not in spec.links:
        raise FlatsimError('robot %s has no link %r' % (spec.name, link))
    return link_poses(spec)[link]


def link_poses(spec):
    """Every link's pose in the root link frame, found in one walk down the tree.

    Kept on the spec until its links or joints change: a chain of N links
    would otherwise cost N^2 pose products.
    """
    key = (len(spec.links), len(spec.joints), spec.root_link)
    cached = getattr(spec, '_link_poses', None)
    if cached is not None and cached[0] == key:
        return cached[1]
    children = {}
    for joint in spec.joints.values():
        children.setdefault(joint.parent, []).append(joint)
    poses = {spec.root_link: Pose()}
    pending = [spec.root_link]
    while pending:
        parent = pending.pop()
        for joint in children.get(parent, ()):
            if joint.child not in poses:
                poses[joint.child] = poses[parent] * joint.origin
                pending.append(joint.child)
    spec._link_poses = (key, poses)
    return poses


def tf_resolve(prefix, frame):
    """tf::resolve from ROS 1 tf: a leading '/' makes a frame global, else the prefix applies."""
    if frame.startswith('/'):
        return frame[1:]
    if prefix:
        return '%s/%s' % (prefix.lstrip('/'), frame)
    return frame


def ros_resolve(namespace, name):
    """A name as a ros::NodeHandle in `namespace` resolves it ('' keeps it relative)."""
    if name.startswith('/') or not namespace:
        return ros_clean(name)
    return ros_clean('%s/%s' % (namespace, name))


def ros_clean(name):
    """ros::names::clean: no repeated or trailing slashes; a leading one stays."""
    cleaned = '/'.join(part for part in name.split('/') if part)
    return '/' + cleaned if name.startswith('/') else cleaned


def _parse_xml(text, source):
    """ElementTree from text, remembering each element's line for error messages."""
    builder = ElementTree.TreeBuilder()
    parser = expat.ParserCreate()
    lines = {}

    def start(tag, attrs):
        lines[builder.start(tag, attrs)] = parser.CurrentLineNumber

    parser.StartElementHandler = start
    parser.EndElementHandler = builder.end
    parser.CharacterDataHandler = builder.data
    try:
        parser.Parse(text, True)
    except expat.ExpatError as err:
        raise ModelFileError('malformed XML: %s' % expat.ErrorString(err.code),
                             path=source, line=err.lineno) from None
    return builder.close(), lines


class _RobotReader:

    def __init__(self, urdf_xml, name, source, robot_namespace):
        if isinstance(urdf_xml, xml.dom.minidom.Document):
            urdf_xml = urdf_xml.toxml()
        if not isinstance(urdf_xml, (str, bytes)) or not urdf_xml.strip():
            raise ModelFileError('the robot description is empty', path=source)
        self.source = source
        self.root, self.lines = _parse_xml(urdf_xml, source)
        if self.root.tag != 'robot':
            raise ModelFileError('expected a <robot> URDF, found <%s>' % self.root.tag,
                                 path=source, line=self.lines.get(self.root))
        self.name = name or self.root.get('name') or 'robot'
        self.robot_namespace = robot_namespace or ''
        self.skipped = []
        self.mesh_origins = {}  # link name -> origins of collision meshes it cannot read
        # Relative mesh file names are read beside the description's file, when it is one.
        self.base_dir = os.path.dirname(os.path.abspath(source)) if source and os.path.isfile(str(source)) \
            else None
        self.drawn_by_collisions = []  # (link, uri) of links whose visual mesh is not found

    def error(self, message, element=None):
        return ModelFileError(message, path=self.source, line=self.lines.get(element))

    def skip(self, subject, reason):
        self.skipped.append(Skipped(subject, reason))

    def adjust(self, subject, reason):
        self.skipped.append(Adjusted(subject, reason))

    # Values -----------------------------------------------------------------

    def number(self, text, what, element=None):
        try:
            value = float((text or '').strip())
        except ValueError:
            raise self.error('%s is %r, not a number' % (what, text), element) from None
        if not math.isfinite(value):
            raise self.error('%s is %r, not a finite number' % (what, text), element)
        return value

    def numbers(self, text, count, what, element=None):
        parts = (text or '').split()
        if len(parts) != count:
            raise self.error('%s is %r, not %d numbers' % (what, text, count), element)
        return tuple(self.number(part, what, element) for part in parts)

    def child_number(self, parent, path, default, what):
        element = parent.find(path)
        if element is None or not (element.text or '').strip():
            return default
        return self.number(element.text, '%s <%s>' % (what, path), element)

    def sensor_rate(self, sensor, label):
        """<update_rate> in Hz; one beyond any physics rate means every step, as in Gazebo."""
        rate = self.child_number(sensor, 'update_rate', 0.0, label)
        if rate > MAX_SENSOR_RATE:
            self.adjust('%s <update_rate>' % label, '%g Hz is beyond any physics rate; the sensor '
                        'is kept and updates at every step (%g Hz at most)' % (rate, MAX_SENSOR_RATE))
            return MAX_SENSOR_RATE
        return rate

    def child_text(self, parent, path, default):
        element = parent.find(path)
        if element is None:
            return default
        return (element.text or '').strip()

    def child_bool(self, parent, tag, default, what, strict=False):
        """sdformat's Get<bool> takes true/false/1/0; gazebo_ros's getParameterBoolean (strict) only true/false."""
        element = parent.find(tag)
        if element is None:
            return default
        text = (element.text or '').strip().lower()
        if text in ('true', 'false'):
            return text == 'true'
        if text in ('1', '0') and not strict:
            return text == '1'
        if text in ('1', '0'):
            self.skip('%s <%s>' % (what, tag),
                      '%r is not true or false; gazebo_ros keeps the default %s'
                      % (element.text.strip(), str(default).lower()))
            return default
        raise self.error('%s <%s> is %r, not true, false, 1 or 0' % (what, tag, element.text),
                         element)

    def origin(self, element, what):
        origin = element.find('origin')
        if origin is None:
            return Pose()
        xyz = self.numbers(origin.get('xyz', '0 0 0'), 3, '%s origin xyz' % what, origin)
        rpy = self.numbers(origin.get('rpy', '0 0 0'), 3, '%s origin rpy' % what, origin)
        return Pose(*xyz, *rpy)

    def sdf_pose(self, parent, what):
        element = parent.find('pose')
        if element is None or not (element.text or '').strip():
            return Pose()
        return Pose(*self.numbers(element.text, 6, '%s <pose>' % what, element))

    # Links and joints -------------------------------------------------------

    def read(self):
        links = {}
        for element in self.root.findall('link'):
            link = self.read_link(element)
            if link.name in links:
                raise self.error('link %r is defined twice' % link.name, element)
            links[link.name] = link
        if not links:
            raise self.error('robot %r has no <link>' % self.name, self.root)
        joints = {}
        for element in self.root.findall('joint'):
            joint = self.read_joint(element, links)
            if joint.name in joints:
                raise self.error('joint %r is defined twice' % joint.name, element)
            joints[joint.name] = joint
        spec = RobotSpec(name=self.name, root_link=self.find_root(links, joints),
                         links=links, joints=joints)
        spec.mass = sum(link.mass for link in links.values())
        spec.articulation = read_articulation(self, spec)
        self.read_gazebo_tags(spec)
        if spec.ros_control is not None:
            spec.ros_control.wheels = self.ros_control_wheels(spec)
        spec.footprint = self.footprint(spec)
        if self.drawn_by_collisions:
            self.skip('visual meshes not found', 'drawn by their collisions instead: %s'
                      % ', '.join('%s (%s)' % item for item in self.drawn_by_collisions))
        spec.skipped = self.skipped
        return spec

    def read_link(self, element):
        name = element.get('name')
        if not name:
            raise self.error('a <link> has no name', element)
        link = Link(name=name)
        mass = element.find('inertial/mass')
        if mass is not None:
            link.mass = self.number(mass.get('value'), 'link %s mass value' % name, mass)
            link.centre_of_mass = self.origin(element.find('inertial'), 'link %s inertial' % name)
        mesh_visuals, missing = [], []
        for role in ('collision', 'visual'):
            shapes = link.collisions if role == 'collision' else link.visuals
            for index, part in enumerate(element.findall(role)):
                what = 'link %s %s %s' % (name, role, part.get('name') or index)
                kind, size = self.read_geometry(part, what)
                if kind != 'mesh':
                    shapes.append((kind, self.origin(part, what), size))
                    continue
                origin = self.origin(part, what)
                boxes = self.read_mesh(part.find('geometry/mesh'), origin, what, role, missing)
                if boxes is None:
                    if role == 'collision':
                        self.mesh_origins.setdefault(name, []).append(origin)
                    continue
                shapes.extend(('box', box.pose, box.size) for box in boxes)
                if role == 'visual':
                    mesh_visuals.extend(('box', box.pose, box.size) for box in boxes)
        if not link.collisions and not self.mesh_origins.get(name) and mesh_visuals:
            # A mesh drawn with no collision of its own collides by its shape, or another
            # robot's lidar and the ball would pass through what the camera sees.
            link.collisions.extend(mesh_visuals)
        if missing and link.collisions:
            link.visuals.extend(link.collisions)
            self.drawn_by_collisions.extend((name, uri) for uri in missing)
        elif missing:
            for uri in missing:
                self.skip('link %s visual' % name, '%s; it is not drawn' % describe(uri, 'file not found'))
        return link

    def read_mesh(self, mesh, origin, what, role, missing):
        """The boxes covering a <mesh> in the link frame, or None (said why, or noted in missing
        for a visual whose file is not found)."""
        uri = (mesh.get('filename') or '').strip()
        try:
            scale = self.numbers(mesh.get('scale', '1 1 1'), 3, '%s mesh scale' % what, mesh)
            if not all(value > 0 for value in scale):
                raise MeshError('has a scale that is not positive (%s)' % mesh.get('scale'))
            return mesh_boxes(find_mesh(uri, self.base_dir), scale, origin.matrix())
        except MeshNotFound as error:
            if role == 'visual':
                missing.append(uri or '(no uri)')
                return None
            reason = describe(uri, error)
        except MeshError as error:
            reason = describe(uri, error)
        self.skip(what, '%s; %s' % (reason, 'its origin counts as a point of the footprint'
                                    if role == 'collision' else 'it is not drawn'))
        return None

    def read_geometry(self, part, what):
        geometry = part.find('geometry')
        if geometry is None:
            raise self.error('%s has no <geometry>' % what, part)
        box = geometry.find('box')
        if box is not None:
            return 'box', self.numbers(box.get('size'), 3, '%s box size' % what, box)
        cylinder = geometry.find('cylinder')
        if cylinder is not None:
            return 'cylinder', (self.number(cylinder.get('radius'), '%s cylinder radius' % what, cylinder),
                                self.number(cylinder.get('length'), '%s cylinder length' % what, cylinder))
        sphere = geometry.find('sphere')
        if sphere is not None:
            return 'sphere', (self.number(sphere.get('radius'), '%s sphere radius' % what, sphere),)
        if geometry.find('mesh') is not None:
            return 'mesh', ()
        raise self.error('%s has no box, cylinder, sphere or mesh' % what, geometry)

    def read_joint(self, element, links):
        name = element.get('name')
        if not name:
            raise self.error('a <joint> has no name', element)
        parent, child = element.find('parent'), element.find('child')
        parent_link = parent.get('link') if parent is not None else None
        child_link = child.get('link') if child is not None else None
        for role, link in (('parent', parent_link), ('child', child_link)):
            if not link:
                raise self.error('joint %s has no <%s link=...>' % (name, role), element)
            if link not in links:
                raise self.error('joint %s names %s link %r, which the robot does not define'
                                 % (name, role, link), element)
        axis = element.find('axis')
        axis_xyz = (1.0, 0.0, 0.0)
        if axis is not None:
            axis_xyz = self.numbers(axis.get('xyz', '1 0 0'), 3, 'joint %s axis xyz' % name, axis)
        return Joint(name=name, kind=element.get('type', ''), parent=parent_link, child=child_link,
                     origin=self.origin(element, 'joint %s' % name), axis=axis_xyz)

    def find_root(self, links, joints):
        parents = {}
        for joint in joints.values():
            if joint.child in parents:
                raise self.error('link %s is the child of two joints (%s and %s)'
                                 % (joint.child, parents[joint.child].name, joint.name))
            parents[joint.child] = joint
        roots = [name for name in links if name not in parents]
        if len(roots) != 1:
            raise self.error('a URDF is a tree with one root link; links without a parent: %s'
                             % (', '.join(sorted(roots)) or 'none (the joints form a loop)'))
        # Each link is walked up only until a link already known to reach the root, so a
        # chain of N links costs N steps, not N^2.
        reaches_root = {roots[0]}
        for name in links:
            path, on_path = [], set()
            while name not in reaches_root:
                if name in on_path:
                    raise self.error('the joints form a loop through link %s' % name)
                if name not in parents:
                    raise self.error('link %s is not connected to the root link %s'
                                     % (path[0] if path else name, roots[0]))
                path.append(name)
                on_path.add(name)
                name = parents[name].parent
            reaches_root.update(path)
        return roots[0]

    # Footprint ----------------------------------------------------------------

    def attached_links(self, spec):
        # The loose (not attached) joint nearest above each link, or None; found parents
        # first, so that every link looks one joint up.
        loose_above = {spec.root_link: None}
        pending = [spec.root_link]
        children = {}
        for joint in spec.joints.values():
            children.setdefault(joint.parent, []).append(joint)
        while pending:
            parent = pending.pop()
            for joint in children.get(parent, ()):
                loose_above[joint.child] = (joint if joint.kind not in ATTACHED_JOINT_TYPES
                                            else loose_above[parent])
                pending.append(joint.child)
        attached = []
        for name in spec.links:
            loose = loose_above[name]
            if loose is None:
                attached.append(name)
            elif loose.child == name:
                self.skip('link %s' % name, '%s joint %s does not hold it at a known place, '
                          'so it is not part of the footprint' % (loose.kind or 'untyped', loose.name))
        return attached

    def footprint(self, spec):
        points = []
        for name in self.attached_links(spec):
            to_root = link_pose(spec, name)
            for kind, origin, size in spec.links[name].collisions:
                points.append(_shape_outline(kind, to_root * origin, size))
            for origin in self.mesh_origins.get(name, []):
                points.append(_shape_outline('point', to_root * origin, ()))
        if not points:
            self.skip('robot %s' % spec.name, 'no collision geometry: the footprint is a %.2f m square '
                      'around the root link' % (2 * POINT_PAD))
            points = [np.zeros((1, 2))]
        points = np.vstack(points)
        reach = float(np.max(np.abs(points)))
        if not reach <= MAX_FOOTPRINT_REACH:
            raise self.error('robot %s: its collision geometry reaches %g m from the root link; flatsim '
                             'simulates robots within %g m' % (spec.name, reach, MAX_FOOTPRINT_REACH))
        hull = _convex_hull(points)
        if _polygon_area(hull) < MIN_FOOTPRINT_AREA:
            pad = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * POINT_PAD
            hull = _convex_hull((points[:, None, :] + pad[None, :, :]).reshape(-1, 2))
        return [(float(x), float(y)) for x, y in hull]

    # <gazebo> tags -------------------------------------------------------------

    def read_gazebo_tags(self, spec):
        for gazebo in self.root.findall('gazebo'):
            reference = gazebo.get('reference')
            if reference is None:
                for plugin in gazebo.findall('plugin'):
                    self.read_model_plugin(spec, plugin)
                continue
            if reference not in spec.links:
                what = 'joint' if reference in spec.joints else None
                sensors = gazebo.findall('sensor')
                if what and not sensors:
                    continue
                self.skip('<gazebo reference="%s">' % reference,
                          'the robot has no link named %s, so its tags are ignored' % reference
                          + (' (sensors need a link)' if what else ''))
                continue
            material = self.child_text(gazebo, 'material', '')
            if material:
                spec.links[reference].material = material
            for sensor in gazebo.findall('sensor'):
                self.read_sensor(spec, reference, sensor)
            for plugin in gazebo.findall('plugin'):
                self.skip('plugin %s (%s)' % (plugin.get('name', ''), plugin.get('filename', '')),
                          'a plugin directly under <gazebo reference="%s"> is not one flatsim runs'
                          % reference)

    def plugin_namespace(self, plugin):
        """The namespace gazebo_ros gives a plugin: its <robotNamespace> (an empty one means the
        model name, for model and sensor plugins alike), else the one spawn_model adds."""
        element = plugin.find('robotNamespace')
        if element is None:
            return self.robot_namespace
        return (element.text or '').strip() or self.name

    def read_model_plugin(self, spec, plugin):
        filename = (plugin.get('filename') or '').strip()
        label = 'plugin %s (%s)' % (plugin.get('name', ''), filename)
        if filename == ROS_CONTROL_PLUGIN and spec.ros_control is None:
            spec.ros_control = read_ros_control_plugin(self, spec, plugin)
            for warning in spec.ros_control.warnings:
                self.skip(label, warning)
            return
        if filename not in DRIVE_PLUGINS:
            drive_topic = self.unknown_drive(plugin)
            if drive_topic is not None:
                self.skip(label, 'a drive plugin flatsim cannot run%s; flatsim does not provide %s, '
                          'so nothing moves the robot on %s'
                          % (' (its commands come on %s)' % drive_topic if drive_topic else '',
                             filename or 'a plugin with no filename',
                             drive_topic or 'its commands'))
                return
            self.skip(label, 'flatsim does not provide %s; the robot runs without it'
                      % (filename or 'a plugin with no filename'))
            return
        if spec.drive is not None:
            self.skip(label, 'the robot already has a drive plugin (%s); only the first is used'
                      % spec.drive.plugin)
            return
        if filename == DIFF_DRIVE_PLUGIN:
            drive = self.read_diff_drive(plugin, label)
        elif filename == SKID_STEER_PLUGIN:
            drive = self.read_skid_steer(plugin, label)
        elif filename == PLANAR_MOVE_PLUGIN:
            spec.drive = self.read_planar_move(plugin, label)
            return
        else:
            drive = self.read_tricycle(plugin, label)
        joint_names = drive.left_joints + drive.right_joints
        if drive.steering is not None:
            joint_names = [drive.steering.joint] + joint_names
        problems = []
        for joint_name in joint_names:
            joint = spec.joints.get(joint_name)
            if joint is None:
                problems.append('there is no joint %s' % joint_name)
            elif joint.kind not in ('continuous', 'revolute'):
                # URDF to SDF conversion merges fixed joints away, so Gazebo cannot find them.
                problems.append('joint %s is %s, not a wheel hinge' % (joint_name, joint.kind))
        if not problems:
            problems = self.place_wheels(spec, drive, label)
        if problems:
            self.skip(label, '%s: the robot stays where it is' % '; '.join(problems))
            return
        spec.drive = drive

    def unknown_drive(self, plugin):
        """For a model plugin flatsim does not run: its command topic ('' when its tags give
        none) if it looks like a drive, else None."""
        topic = None
        for tag in COMMAND_TAGS:
            text = self.child_text(plugin, tag, '')
            if text:
                topic = text
                break
        if topic is None:
            for child in plugin.iter():
                text = (child.text or '').strip()
                if child is not plugin and text.rstrip('/').endswith('cmd_vel'):
                    topic = text
                    break
        filename = (plugin.get('filename') or '').lower()
        names = filename + ' ' + (plugin.get('name') or '').lower()
        if any(word in names for word in NOT_DRIVES):
            return None
        if topic is None and not any(word in names for word in DRIVE_WORDS):
            return None
        if topic is None:
            return ''
        return ros_resolve(self.plugin_namespace(plugin), topic)

    def wheel(self, spec, joint_name, radius_tag, fallback_radius, label):
        """The Wheel a joint drives: its place and rolling direction in the base frame; or
        the reason it cannot roll the robot."""
        joint = spec.joints[joint_name]
        frame = (link_poses(spec)[joint.parent] * joint.origin).matrix()
        axis = np.asarray(joint.axis, dtype=float)
        length = float(np.linalg.norm(axis))
        if not length > 0.0:
            return 'joint %s has no axis' % joint_name
        axis = frame[:3, :3] @ (axis / length)
        if math.hypot(axis[0], axis[1]) < MIN_ROLLING_AXIS:
            return 'joint %s turns about an upright axis, so its wheel cannot roll the robot' % joint_name
        radius = self.wheel_radius(spec, joint.child)
        if radius is None:
            radius = fallback_radius
            self.adjust('%s joint %s' % (label, joint_name),
                        'its link %s has no cylinder or sphere collision to roll on; flatsim takes '
                        'the radius <%s> gives, %g m' % (joint.child, radius_tag, radius))
        return Wheel(joint_name, float(frame[0, 3]), float(frame[1, 3]),
                     radius * float(axis[1]), -radius * float(axis[0]), radius, float(frame[2, 3]))

    @staticmethod
    def wheel_radius(spec, link):
        radii = [size[0] for kind, _, size in spec.links[link].collisions if kind in ('cylinder', 'sphere')]
        return max(radii) if radii and max(radii) > 0.0 else None

    def ros_control_wheels(self, spec):
        """Joints on ros_control's velocity interface that could roll the robot: a horizontal
        axis and a round collision (whether they reach the floor is the simulation's to say)."""
        wheels = []
        for transmission in spec.ros_control.transmissions:
            joint = spec.joints.get(transmission.joint)
            if (transmission.interface != 'velocity' or joint is None
                    or joint.kind not in ('continuous', 'revolute')
                    or self.wheel_radius(spec, joint.child) is None):
                continue
            wheel = self.wheel(spec, joint.name, 'wheel_radius', 0.0, 'gazebo_ros_control')
            if isinstance(wheel, Wheel):
                wheels.append(wheel)
        return wheels

    def place_wheels(self, spec, drive, label):
        """Fill drive.wheels (and the tricycle's steering and encoder wheels) from the URDF;
        returns what keeps the drive from running."""
        problems = []
        if drive.plugin == 'tricycle':
            driven = [drive.left_joints[0]]
            drive.encoder_wheels = []
            for name in (drive.left_joints[1], drive.right_joints[0]):
                wheel = self.wheel(spec, name, 'encoderWheelDiameter',
                                   drive.encoder_wheel_diameter / 2.0, label)
                if isinstance(wheel, str):
                    problems.append(wheel)
                else:
                    drive.encoder_wheels.append(wheel)
            steering = spec.joints[drive.steering.joint]
            frame = (link_poses(spec)[steering.parent] * steering.origin).matrix()
            axis = np.asarray(steering.axis, dtype=float)
            length = float(np.linalg.norm(axis))
            upright = float((frame[:3, :3] @ (axis / length))[2]) if length > 0.0 else 0.0
            if abs(upright) < MIN_STEERING_AXIS:
                problems.append('steering joint %s does not turn about an upright axis'
                                % steering.name)
            drive.steering = Steering(steering.name, float(frame[0, 3]), float(frame[1, 3]),
                                      1.0 if upright >= 0.0 else -1.0)
            radius_tag = 'actuatedWheelDiameter'
        else:
            driven = drive.left_joints + drive.right_joints
            radius_tag = 'wheelDiameter'
        drive.wheels = []
        for name in driven:
            wheel = self.wheel(spec, name, radius_tag, drive.wheel_diameter / 2.0, label)
            if isinstance(wheel, str):
                problems.append(wheel)
            else:
                drive.wheels.append(wheel)
        return problems

    def read_diff_drive(self, plugin, label):
        namespace = self.plugin_namespace(plugin)
        node_namespace = namespace + '/' if namespace else ''
        tf_prefix = node_namespace.rstrip('/')
        drive = DriveConfig(plugin='diff_drive', tf_prefix=tf_prefix)
        self.read_drive_common(plugin, label, drive, node_namespace, tf_prefix)
        drive.left_joints = [self.child_text(plugin, 'leftJoint', 'left_joint')]
        drive.right_joints = [self.child_text(plugin, 'rightJoint', 'right_joint')]
        drive.wheel_separation = self.child_number(plugin, 'wheelSeparation', 0.34, label)
        drive.wheel_diameter = self.child_number(plugin, 'wheelDiameter', 0.15, label)
        drive.wheel_acceleration = self.child_number(plugin, 'wheelAcceleration', 0.0, label)
        drive.wheel_torque = self.child_number(plugin, 'wheelTorque', 5.0, label)
        source = self.child_text(plugin, 'odometrySource', 'world')
        if source not in ('world', 'encoder'):
            self.skip('%s <odometrySource>' % label,
                      '%r is not world or encoder; gazebo_ros uses world' % source)
            source = 'world'
        drive.odometry_source = source
        drive.publish_odometry = self.child_bool(plugin, 'publishTf', True, label)
        publish_odom_tf = self.child_bool(plugin, 'publishOdomTF', True, label, strict=True)
        drive.publish_tf = drive.publish_odometry and publish_odom_tf
        drive.publish_wheel_tf = self.child_bool(plugin, 'publishWheelTF', False, label, strict=True)
        drive.publish_wheel_joint_state = self.child_bool(plugin, 'publishWheelJointState', False,
                                                          label, strict=True)
        drive.covariance = (0.00001, 0.00001, 0.001)
        if self.child_text(plugin, 'legacyMode', 'false').lower() in ('true', '1'):
            # gazebo_plugins 2.8.3 (melodic) removed legacy mode; noetic's plugin never reads it.
            self.skip('%s <legacyMode>' % label,
                      "noetic's gazebo_ros_diff_drive does not read it, so the wheels are not "
                      'swapped: leftJoint gets the left wheel speed and rightJoint the right one')
        return drive

    def read_skid_steer(self, plugin, label):
        element = plugin.find('robotNamespace')
        if element is None:
            namespace = self.robot_namespace
        else:
            namespace = (element.text or '').strip()
        node_namespace = namespace + '/' if element is not None or namespace else ''
        # The skid steer plugin takes its tf prefix only from the tf_prefix parameter.
        drive = DriveConfig(plugin='skid_steer', tf_prefix='')
        self.read_drive_common(plugin, label, drive, node_namespace, '')
        drive.left_joints = [self.child_text(plugin, 'leftFrontJoint', 'left_front_joint'),
                             self.child_text(plugin, 'leftRearJoint', 'left_rear_joint')]
        drive.right_joints = [self.child_text(plugin, 'rightFrontJoint', 'right_front_joint'),
                              self.child_text(plugin, 'rightRearJoint', 'right_rear_joint')]
        drive.wheel_separation = self.child_number(plugin, 'wheelSeparation', 0.4, label)
        drive.wheel_diameter = self.child_number(plugin, 'wheelDiameter', 0.15, label)
        drive.wheel_acceleration = 0.0
        drive.wheel_torque = self.child_number(plugin, 'torque', 5.0, label)
        drive.odometry_source = 'world'
        drive.publish_odometry = True
        drive.publish_tf = self.child_bool(plugin, 'broadcastTF', False, label)
        drive.publish_wheel_tf = False
        drive.publish_wheel_joint_state = False
        drive.covariance = (self.child_number(plugin, 'covariance_x', 0.0001, label),
                            self.child_number(plugin, 'covariance_y', 0.0001, label),
                            self.child_number(plugin, 'covariance_yaw', 0.01, label))
        return drive

    def read_planar_move(self, plugin, label):
        """libgazebo_ros_planar_move: a NodeHandle in <robotNamespace>, tf_prefix from its parameter."""
        element = plugin.find('robotNamespace')
        namespace = self.robot_namespace if element is None else (element.text or '').strip()
        node_namespace = namespace + '/' if element is not None or namespace else ''
        drive = DriveConfig(plugin='planar_move', tf_prefix='', left_joints=[], right_joints=[])
        self.read_drive_common(plugin, label, drive, node_namespace, '', rate_tag='odometryRate',
                               default_rate=20.0)
        drive.publish_odometry = True
        drive.publish_tf = self.child_bool(plugin, 'publishOdometryTf', True, label)
        drive.covariance = (0.0, 0.0, 0.0)
        return drive

    def read_tricycle(self, plugin, label):
        namespace = self.plugin_namespace(plugin)
        node_namespace = namespace + '/' if namespace else ''
        tf_prefix = node_namespace.rstrip('/')
        drive = DriveConfig(plugin='tricycle', tf_prefix=tf_prefix)
        self.read_drive_common(plugin, label, drive, node_namespace, tf_prefix,
                               base_frame='base_link')
        drive.wheel_diameter = self.child_number(plugin, 'actuatedWheelDiameter', 0.15, label)
        drive.encoder_wheel_diameter = self.child_number(plugin, 'encoderWheelDiameter', 0.15, label)
        drive.wheel_torque = self.child_number(plugin, 'wheelTorque', 5.0, label)
        drive.wheel_acceleration = self.child_number(plugin, 'wheelAcceleration', 0.0, label)
        drive.wheel_deceleration = self.child_number(plugin, 'wheelDeceleration',
                                                     drive.wheel_acceleration, label)
        drive.wheel_speed_tolerance = self.child_number(plugin, 'wheelSpeedTolerance', 0.01, label)
        drive.steering_speed = self.child_number(plugin, 'steeringSpeed', 0.0, label)
        drive.steering_angle_tolerance = self.child_number(plugin, 'steeringAngleTolerance', 0.01, label)
        drive.encoder_wheel_separation = self.child_number(plugin, 'encoderWheelSeparation', 0.5, label)
        drive.wheel_separation = drive.encoder_wheel_separation
        drive.publish_wheel_tf = self.child_bool(plugin, 'publishWheelTF', False, label, strict=True)
        drive.publish_wheel_joint_state = self.child_bool(plugin, 'publishWheelJointState', False,
                                                          label, strict=True)
        source = self.child_text(plugin, 'odometrySource', 'world')
        if source != 'world':
            self.adjust('%s <odometrySource>' % label,
                        '%r: flatsim publishes the tricycle drive\'s odometry from the world' % source)
        drive.odometry_source = 'world'
        drive.publish_odometry = drive.publish_tf = True
        drive.covariance = (0.0, 0.0, 0.0)
        steering = self.child_text(plugin, 'steeringJoint', 'front_steering_joint')
        drive.steering = Steering(steering)
        drive.left_joints = [self.child_text(plugin, 'actuatedWheelJoint', 'front_wheel_joint'),
                             self.child_text(plugin, 'encoderWheelLeftJoint', 'left_wheel_joint')]
        drive.right_joints = [self.child_text(plugin, 'encoderWheelRightJoint', 'right_wheel_joint')]
        return drive

    def read_drive_common(self, plugin, label, drive, node_namespace, tf_prefix,
                          base_frame='base_footprint', rate_tag='updateRate', default_rate=100.0):
        drive.command_topic = ros_resolve(node_namespace, self.child_text(plugin, 'commandTopic', 'cmd_vel'))
        drive.odometry_topic = ros_resolve(node_namespace, self.child_text(plugin, 'odometryTopic', 'odom'))
        drive.odometry_frame = tf_resolve(tf_prefix, self.child_text(plugin, 'odometryFrame', 'odom'))
        drive.robot_base_frame = tf_resolve(tf_prefix, self.child_text(plugin, 'robotBaseFrame',
                                                                       base_frame))
        drive.update_rate = self.child_number(plugin, rate_tag, default_rate, label)
        if 0.0 < drive.update_rate < MIN_UPDATE_RATE:
            self.adjust('%s <%s>' % (label, rate_tag), '%g Hz would never update the drive; %g Hz is used'
                        % (drive.update_rate, MIN_UPDATE_RATE))
            drive.update_rate = MIN_UPDATE_RATE

    # Sensors ----------------------------------------------------------------

    def read_sensor(self, spec, link, sensor):
        sensor_type = (sensor.get('type') or '').strip()
        sensor_name = sensor.get('name') or sensor_type
        label = 'sensor %s on link %s' % (sensor_name, link)
        plugins = sensor.findall('plugin')
        known = [plugin for plugin in plugins
                 if (plugin.get('filename') or '').strip() in tuple(CAMERA_PLUGINS) + LASER_PLUGINS]
        for plugin in plugins:
            if plugin not in known:
                self.skip('%s plugin %s' % (label, plugin.get('filename', '')),
                          'flatsim does not provide this plugin; it is ignored')
        if not known:
            self.skip(label, 'no gazebo_ros camera or laser plugin publishes it, so flatsim leaves it out')
            return
        plugin = known[0]
        filename = plugin.get('filename').strip()
        if sensor_type in CAMERA_SENSOR_TYPES and filename in CAMERA_PLUGINS:
            spec.cameras.append(self.read_camera(sensor, plugin, sensor_name, link, label,
                                                 CAMERA_PLUGINS[filename]))
        elif sensor_type in LASER_SENSOR_TYPES and filename in LASER_PLUGINS:
            spec.lasers.append(self.read_laser(sensor, plugin, sensor_name, link, label))
        else:
            self.skip(label, '%s needs a different sensor type than %r' % (filename, sensor_type))
        for extra in known[1:]:
            self.skip('%s plugin %s' % (label, extra.get('filename')),
                      'only the first camera or laser plugin of a sensor is used')

    def read_camera(self, sensor, plugin, sensor_name, link, label, kind):
        camera = sensor.find('camera')
        if camera is None:
            raise self.error('%s has no <camera> block' % label, sensor)
        namespace = self.plugin_namespace(plugin)
        camera_name = self.child_text(plugin, 'cameraName', '')
        node_namespace = ros_clean('%s/%s' % (namespace, camera_name)) if namespace else camera_name
        config = CameraConfig(sensor_name=sensor_name, link=link, plugin=kind)
        config.pose = self.sdf_pose(sensor, label)
        config.update_rate = self.sensor_rate(sensor, label)
        config.plugin_update_rate = self.child_number(plugin, 'updateRate', 0.0, label)
        config.width = self.positive_int(camera, 'image/width', 320, label, MAX_IMAGE_SIDE)
        config.height = self.positive_int(camera, 'image/height', 240, label, MAX_IMAGE_SIDE)
        config.hfov = self.child_number(camera, 'horizontal_fov', 1.047, label)
        if not 0.0 < config.hfov < math.pi:
            raise self.error('%s <horizontal_fov> %g is not between 0 and pi' % (label, config.hfov),
                             camera.find('horizontal_fov'))
        config.image_format = self.child_text(camera, 'image/format', 'R8G8B8') or 'R8G8B8'
        config.near = self.child_number(camera, 'clip/near', 0.1, label)
        config.far = self.child_number(camera, 'clip/far', 100.0, label)
        config.image_topic = ros_resolve(node_namespace, self.child_text(plugin, 'imageTopicName', 'image_raw'))
        config.info_topic = ros_resolve(node_namespace,
                                        self.child_text(plugin, 'cameraInfoTopicName', 'camera_info'))
        config.frame_name = tf_resolve(namespace.rstrip('/'), self.child_text(plugin, 'frameName', ''))
        config.hack_baseline = self.child_number(plugin, 'hackBaseline', 0.0, label)
        config.distortion = tuple(self.child_number(plugin, tag, 0.0, label) for tag in
                                  ('distortionK1', 'distortionK2', 'distortionT1', 'distortionT2',
                                   'distortionK3'))
        return config

    def positive_int(self, parent, path, default, label, maximum):
        value = self.child_number(parent, path, default, label)
        if value < 1 or value != int(value):
            raise self.error('%s <%s> is %g, not a positive whole number' % (label, path, value),
                             parent.find(path))
        if value > maximum:
            raise self.error('%s <%s> is %g, more than flatsim simulates (%d)' % (label, path, value, maximum),
                             parent.find(path))
        return int(value)

    def read_laser(self, sensor, plugin, sensor_name, link, label):
        ray = sensor.find('ray')
        if ray is None:
            raise self.error('%s has no <ray> block' % label, sensor)
        namespace = self.plugin_namespace(plugin)
        config = LaserConfig(sensor_name=sensor_name, link=link)
        config.pose = self.sdf_pose(sensor, label)
        config.update_rate = self.sensor_rate(sensor, label)
        samples = self.positive_int(ray, 'scan/horizontal/samples', 640, label, MAX_LASER_SAMPLES)
        resolution = self.child_number(ray, 'scan/horizontal/resolution', 1.0, label)
        # Gazebo returns samples * resolution ranges (interpolated when resolution < 1).
        ranges = samples * resolution
        if not ranges <= MAX_LASER_SAMPLES:
            raise self.error('%s gives %g ranges (samples %d x resolution %g), more than flatsim '
                             'simulates (%d)' % (label, ranges, samples, resolution, MAX_LASER_SAMPLES), ray)
        config.samples = max(1, int(round(ranges)))
        config.min_angle = self.child_number(ray, 'scan/horizontal/min_angle', 0.0, label)
        config.max_angle = self.child_number(ray, 'scan/horizontal/max_angle', 0.0, label)
        if config.max_angle < config.min_angle:
            raise self.error('%s <max_angle> %g is below <min_angle> %g'
                             % (label, config.max_angle, config.min_angle), ray)
        config.range_min = self.child_number(ray, 'range/min', 0.0, label)
        config.range_max = self.child_number(ray, 'range/max', 0.0, label)
        config.range_resolution = self.child_number(ray, 'range/resolution', 0.0, label)
        noise = ray.find('noise')
        if noise is not None:
            noise_type = self.child_text(noise, 'type', 'none').lower()
            if noise_type == 'gaussian':
                config.noise_mean = self.child_number(noise, 'mean', 0.0, label)
                config.noise_stddev = self.child_number(noise, 'stddev', 0.0, label)
            elif noise_type != 'none':
                self.skip('%s noise' % label, 'noise type %r is not gaussian; the scan has no noise'
                          % noise_type)
        config.topic = ros_resolve(namespace, self.child_text(plugin, 'topicName', '/world'))
        config.frame_name = tf_resolve(namespace.rstrip('/'), self.child_text(plugin, 'frameName', '/world'))
        return config


def _shape_outline(kind, pose, size):
    """(x, y) points whose convex hull is the shape's shadow on the ground plane."""
    if kind == 'box':
        corners = np.array(np.meshgrid([-0.5, 0.5], [-0.5, 0.5], [-0.5, 0.5])).reshape(3, -1).T
        local = corners * np.asarray(size)
    elif kind == 'cylinder':
        radius, length = size
        angles = np.linspace(0.0, 2.0 * math.pi, CIRCLE_POINTS, endpoint=False)
        ring = np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])
        local = np.vstack([np.column_stack([ring, np.full(len(ring), z)])
                           for z in (-length / 2.0, length / 2.0)])
    elif kind == 'sphere':
        angles = np.linspace(0.0, 2.0 * math.pi, CIRCLE_POINTS, endpoint=False)
        centre = np.array([pose.x, pose.y])
        return centre + size[0] * np.column_stack([np.cos(angles), np.sin(angles)])
    else:
        local = np.zeros((1, 3))
    matrix = pose.matrix()
    world = local @ matrix[:3, :3].T + matrix[:3, 3]
    return world[:, :2]


def _convex_hull(points):
    """Counter-clockwise convex hull of (N, 2) points."""
    # OpenCV works in float32, so take its indices and keep the exact float64 points.
    indices = cv2.convexHull(np.ascontiguousarray(points, dtype=np.float32), returnPoints=False)
    if indices is None:
        # OpenCV returns nothing when the points coincide in float32: the hull is that one point.
        return np.asarray(points, dtype=float)[:1]
    indices = indices.reshape(-1)
    hull = np.asarray(points, dtype=float)[indices]
    if _polygon_area(hull) < 0:
        hull = hull[::-1]
    # Cylinders seen from the side (often turned by 1.5707 rather than pi/2) leave runs of
    # nearly collinear vertices: drop the flattest until every vertex is a real corner.
    while len(hull) > 3:
        before, after = np.roll(hull, 1, axis=0), np.roll(hull, -1, axis=0)
        chord = after - before
        offset = (np.abs(chord[:, 0] * (hull[:, 1] - before[:, 1]) - chord[:, 1] * (hull[:, 0] - before[:, 0]))
                  / np.maximum(np.linalg.norm(chord, axis=1), 1e-12))
        flattest = int(np.argmin(offset))
        if offset[flattest] > FLAT_VERTEX_TOLERANCE:
            break
        hull = np.delete(hull, flattest, axis=0)
    return hull


def _polygon_area(polygon):
    """Signed area: positive when the vertices run counter-clockwise."""
    if len(polygon) < 3:
        return 0.0
    x, y = polygon[:, 0], polygon[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
