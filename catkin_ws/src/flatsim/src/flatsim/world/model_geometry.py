"""Models' geometry as the simulation sees it: the 2.5D primitives of their geoms in the world,
a robot's collision shapes and resting height, a body's inertia in the plane, and which
primitives are ground and which stop a robot. No ROS here."""
import math
from dataclasses import dataclass, replace

from flatsim.loading.urdf_robot import link_pose
from flatsim.pose import Pose
from flatsim.world.scene import Prim

# Heights between which geometry blocks a ground robot: above the floor's
# contact patch and below the top of any course robot.
WORKING_HEIGHT = (0.02, 0.5)
# A slab lying on the floor whose top is no higher than this is ground that robots drive onto,
# not an obstacle: the Building Editor's floor (0.1 m thick) and a thin mat or platform. 0.1 m
# is the wheel radius of most course robots, which a wheel meets at or below its axle.
MAX_STEP_HEIGHT = 0.1


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
