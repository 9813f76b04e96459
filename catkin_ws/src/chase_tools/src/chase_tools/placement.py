"""Where a chase starts, and when it has reached the ball. Pure geometry: no ROS.

A placement puts the robot and the ball in a world's free space so that the
robot's own camera sees the whole ball from the start:

- the camera's pose is the robot's: its link's pose through the URDF's joints
  and its <sensor><pose>, as flatsim mounts it, and its field of view is the
  sensor's <horizontal_fov> (the vertical one follows from the image size);
- both edges of the ball lie inside that field of view, and rays from the
  camera to the ball's near side, from edge to edge and no more than
  SIGHT_GAP_M apart where they meet it, meet no collider;
- the robot's outline (its footprint polygon, as flatsim's physics simulates
  it) stays clear of every collider flatsim simulates: static models, the
  models it holds still, the dynamic ones robots push (a box, a building saved
  as a non-static model) and the world's other balls where they start, but not
  the ground robots drive on (a building's floor slab); the ball stands away from them too,
  inside a room when the world has rooms, and a corridor as wide as the robot
  leads from the robot to the ball with no collider in it, however thin.

Whether a chase has reached the ball is decided by chase_tools.reach's surface rule.
"""
import collections
import math
from dataclasses import dataclass
from typing import Tuple

import numpy as np
import pymunk

from chase_tools.reach import polygon_distance
from flatsim.errors import FlatsimError
from flatsim.loading.urdf_robot import link_pose, load_robot
from flatsim.sensors import raycast
from flatsim.world.scene import BOX, Scene
from flatsim.world.model_geometry import geom_prims, is_obstacle, root_height
from flatsim.world.sim import Simulation

# The ball stands at least this far from every collider; indoors, the robot's origin must be
# enclosed as well.
WALL_MARGIN_M = 0.5
# The robot's outline stays at least this far from every collider.
ROBOT_MARGIN_M = 0.25
# Distance from the camera to the ball's centre.
BALL_RANGE_M = (1.0, 4.0)
# The ball's surface starts at least this far from the robot's outline.
START_GAP_M = 0.5
# The ball's edges stay this far inside the edges of the image.
VIEW_MARGIN_RAD = 0.05
# The corridor from the robot to the ball is at least this wide on each side of its middle.
CORRIDOR_HALF_WIDTH_M = 0.2
# Neighbouring rays of the camera's sight of the ball are at most this far apart where they meet
# it: no collider wider than this fits between them (a table's leg, a chair's).
SIGHT_GAP_M = 0.01
# A world with no colliders: placements within this distance of the robot's spawn point.
OPEN_WORLD_RADIUS_M = 5.0
# A point counts as indoors when rays in all these directions meet a collider.
ENCLOSURE_RAYS = 16
MAX_DRAWS = 10000
# A robot without a camera: the course camera's field of view, straight ahead of its origin.
COURSE_HFOV = 1.3962634
COURSE_CAMERA_HEIGHT_M = 0.1


@dataclass(frozen=True)
class Placement:
    """Robot pose (x, y in m, yaw in rad) and ball position in the world frame."""
    robot_x: float
    robot_y: float
    robot_yaw: float
    ball_x: float
    ball_y: float

    @property
    def ball_distance(self):
        return math.hypot(self.ball_x - self.robot_x, self.ball_y - self.robot_y)


@dataclass(frozen=True)
class CameraView:
    """A camera's pose relative to the robot's root link on the floor, and its field of view.

    x, y, yaw: in the root link frame; z: height above the floor; pitch: positive looks down
    (REP 103). hfov, vfov: full angles in rad.
    """
    x: float
    y: float
    z: float
    yaw: float
    pitch: float
    hfov: float
    vfov: float

    def world(self, robot_x, robot_y, robot_yaw):
        """(x, y, yaw) of the camera for a robot at that pose."""
        cos_yaw, sin_yaw = math.cos(robot_yaw), math.sin(robot_yaw)
        return (robot_x + cos_yaw * self.x - sin_yaw * self.y,
                robot_y + sin_yaw * self.x + cos_yaw * self.y, robot_yaw + self.yaw)


@dataclass(frozen=True)
class RobotGeometry:
    """What the placements and the reach need of a robot: its outline and its camera."""
    footprint: Tuple[Tuple[float, float], ...]   # counter-clockwise, in the root link frame
    camera: CameraView
    note: str = ''                               # how the camera was chosen, when it was a guess

    @classmethod
    def from_spec(cls, spec, camera_topic):
        """From a flatsim RobotSpec: the camera that publishes camera_topic (else the first)."""
        wanted = camera_topic.strip('/')
        chosen = next((c for c in spec.cameras if c.image_topic.strip('/') == wanted), None)
        note = ''
        if chosen is None and spec.cameras:
            chosen = spec.cameras[0]
            note = ('no camera of the robot publishes %s; placements use camera %s on link %s (%s)'
                    % (camera_topic, chosen.sensor_name, chosen.link, chosen.image_topic))
        if chosen is None:
            camera = CameraView(0.0, 0.0, COURSE_CAMERA_HEIGHT_M, 0.0, 0.0, COURSE_HFOV,
                                COURSE_HFOV)
            note = ('the robot has no camera; placements put the ball within the course camera\'s '
                    'field of view (%.2f rad) ahead of its origin' % COURSE_HFOV)
        else:
            mount = link_pose(spec, chosen.link) * chosen.pose
            vfov = 2.0 * math.atan(math.tan(chosen.hfov / 2.0) * chosen.height / chosen.width)
            camera = CameraView(mount.x, mount.y, root_height(spec) + mount.z, mount.yaw, mount.pitch,
                                chosen.hfov, vfov)
        return cls(tuple((float(x), float(y)) for x, y in spec.footprint), camera, note)

    @classmethod
    def from_urdf(cls, urdf_xml, camera_topic, source=None):
        """From URDF text (xacro already run), read with flatsim's own loader."""
        return cls.from_spec(load_robot(urdf_xml, source=source), camera_topic)

    @property
    def half_width(self):
        return max(abs(y) for _x, y in self.footprint)

    def outline(self, x, y, yaw):
        """The footprint polygon, (N, 2), for a robot at that pose."""
        points = np.asarray(self.footprint, dtype=float)
        cos_yaw, sin_yaw = math.cos(yaw), math.sin(yaw)
        return np.column_stack([x + cos_yaw * points[:, 0] - sin_yaw * points[:, 1],
                                y + sin_yaw * points[:, 0] + cos_yaw * points[:, 1]])


def world_colliders(world, keep_out=()):
    """The collision primitives that stop a robot (flatsim.world.model_geometry.is_obstacle: at working
    height, and not ground such as a building's floor slab) of every model but robots, where
    it starts.

    flatsim's own reading of the world decides: static models, the models it holds still,
    the dynamic models it lets robots push and balls, where they start. Robots saved in the
    world and the models named in keep_out (the chased ball, the spawned robot) are left out.
    """
    sim = Simulation(world)
    prims = []
    for model in sim.models.values():
        if model.kind == 'robot' or model.name in keep_out or model.source is None:
            continue
        prims.extend(prim for prim in geom_prims(model.name, model.initial_pose,
                                                 model.source.collisions, 'lidar')
                     if is_obstacle(prim))
    return prims


class FreeSpace:
    """Where a robot or ball can stand in a world, and what its camera can see there.

    With no collider at all (an open world), the free space is a square of
    OPEN_WORLD_RADIUS_M around `around`, the robot's spawn point.
    """

    def __init__(self, world, margin=WALL_MARGIN_M, indoors=True, keep_out=(), around=(0.0, 0.0)):
        prims = world_colliders(world, keep_out)
        self.open = not prims
        self.scene = Scene(prims)
        self.indices = np.arange(len(prims))
        self.margin = margin
        self.indoors = indoors and not self.open
        self.space = pymunk.Space()
        self._probe_body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        s = self.scene
        for index in self.indices:
            if s.kind[index] == BOX:
                corners = [(-s.half_x[index], -s.half_y[index]), (s.half_x[index], -s.half_y[index]),
                           (s.half_x[index], s.half_y[index]), (-s.half_x[index], s.half_y[index])]
                transform = pymunk.Transform.translation(s.x[index], s.y[index]).rotated(s.yaw[index])
                self.space.add(pymunk.Poly(self.space.static_body, corners, transform))
            else:
                self.space.add(pymunk.Circle(self.space.static_body, s.radius[index],
                                             (s.x[index], s.y[index])))
        if self.open:
            x, y = around
            self.bounds = (x - OPEN_WORLD_RADIUS_M, x + OPEN_WORLD_RADIUS_M,
                           y - OPEN_WORLD_RADIUS_M, y + OPEN_WORLD_RADIUS_M)
        else:
            corners_x, corners_y = [], []
            for sign_x, sign_y in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
                reach_x = sign_x * s.half_x + s.radius
                reach_y = sign_y * s.half_y + s.radius
                corners_x.append(s.x + reach_x * s.cos_yaw - reach_y * s.sin_yaw)
                corners_y.append(s.y + reach_x * s.sin_yaw + reach_y * s.cos_yaw)
            self.bounds = (float(np.min(corners_x)), float(np.max(corners_x)),
                           float(np.min(corners_y)), float(np.max(corners_y)))
        self.fan = raycast.directions(np.linspace(0.0, 2 * math.pi, ENCLOSURE_RAYS, endpoint=False))

    def clearance(self, x, y):
        """Distance from (x, y) to the nearest collider outline; 0 inside one."""
        s = self.scene
        if not len(self.indices):
            return math.inf
        rel_x, rel_y = x - s.x, y - s.y
        local_x = rel_x * s.cos_yaw + rel_y * s.sin_yaw
        local_y = rel_y * s.cos_yaw - rel_x * s.sin_yaw
        box_gap = np.hypot(np.maximum(np.abs(local_x) - s.half_x, 0.0),
                           np.maximum(np.abs(local_y) - s.half_y, 0.0))
        circle_gap = np.maximum(np.hypot(rel_x, rel_y) - s.radius, 0.0)
        return float(np.min(np.where(s.kind == BOX, box_gap, circle_gap)))

    def enclosed(self, x, y):
        distance, _ = raycast.nearest(self.scene, x, y, *self.fan, self.indices)
        return bool(np.all(np.isfinite(distance)))

    def free(self, x, y):
        return self.clearance(x, y) >= self.margin and (not self.indoors or self.enclosed(x, y))

    def outline_clear(self, outline, margin=ROBOT_MARGIN_M):
        """True when the polygon (N, 2) comes no closer than margin to any collider."""
        probe = pymunk.Poly(self._probe_body, [tuple(p) for p in outline], radius=margin)
        return not self.space.shape_query(probe)

    def clear_rays(self, origin, targets):
        """True when the straight line from origin to each target (x, y) meets no collider."""
        targets = np.atleast_2d(np.asarray(targets, dtype=float))
        dx, dy = targets[:, 0] - origin[0], targets[:, 1] - origin[1]
        length = np.hypot(dx, dy)
        distance, _ = raycast.nearest(self.scene, origin[0], origin[1], dx / length, dy / length,
                                      self.indices)
        return bool(np.all(distance >= length))

    def in_sight(self, from_xy, to_xy, half_width=CORRIDOR_HALF_WIDTH_M):
        """True when the straight corridor from one point to the other (a rectangle half_width
        to each side of the line between them) meets no collider, however thin: anything in it
        would stop the robot on its way."""
        dx, dy = to_xy[0] - from_xy[0], to_xy[1] - from_xy[1]
        length = math.hypot(dx, dy)
        across = np.array([-dy, dx]) / length * half_width
        ends = np.array([from_xy, to_xy], dtype=float)
        corridor = np.concatenate([ends - across, ends[::-1] + across])
        return self.outline_clear(corridor, margin=0.0)

    def ball_edges_visible(self, camera_xy, ball_xy, radius):
        """True when the camera sees the whole of the ball's near side: rays from the camera to
        its outline, from edge to edge, meet no collider before the ball.

        The rays are spread so that, where they meet the ball, neighbours are at most
        SIGHT_GAP_M apart, and closer everywhere nearer the camera: no collider wider than
        that fits between them.
        """
        dx, dy = ball_xy[0] - camera_xy[0], ball_xy[1] - camera_xy[1]
        distance = math.hypot(dx, dy)
        if distance <= radius:
            return False
        half = math.asin(radius / distance)
        offsets = np.linspace(-half, half, sight_ray_count(2.0 * half * distance))
        # Where each ray meets the ball's outline (the edge rays touch it).
        along = distance * np.cos(offsets)
        length = along - np.sqrt(np.maximum(radius * radius - (distance * np.sin(offsets)) ** 2, 0.0))
        bearing = math.atan2(dy, dx)
        hit, _ = raycast.nearest(self.scene, camera_xy[0], camera_xy[1],
                                 *raycast.directions(bearing + offsets), self.indices)
        return bool(np.all(hit >= length))


def sight_ray_count(span_m, gap=SIGHT_GAP_M):
    """How many rays, spread evenly over an arc span_m long, leave neighbours no more than gap
    apart along it (at least the two ends and the middle)."""
    return max(3, math.ceil(span_m / gap - 1e-9) + 1)


def ball_edges(camera_xy, ball_xy, radius):
    """The ball's centre and the two points where the camera's sight lines touch its outline."""
    dx, dy = ball_xy[0] - camera_xy[0], ball_xy[1] - camera_xy[1]
    distance = math.hypot(dx, dy)
    bearing = math.atan2(dy, dx)
    half = math.asin(min(1.0, radius / distance))
    tangent = math.sqrt(max(distance * distance - radius * radius, 0.0))
    return [tuple(ball_xy)] + [(camera_xy[0] + tangent * math.cos(bearing + side * half),
                                camera_xy[1] + tangent * math.sin(bearing + side * half))
                               for side in (-1.0, 1.0)]


def whole_ball_in_view(camera, camera_pose, ball_xy, ball_z, radius, margin=VIEW_MARGIN_RAD):
    """True when the whole ball lies inside the camera's field of view (walls aside).

    camera_pose: the camera's world (x, y, yaw).
    """
    x, y, yaw = camera_pose
    dx, dy = ball_xy[0] - x, ball_xy[1] - y
    distance = math.hypot(dx, dy)
    dz = ball_z - camera.z
    slant = math.hypot(distance, dz)
    if slant <= radius:
        return False
    off_axis = abs(math.remainder(math.atan2(dy, dx) - yaw, 2 * math.pi))
    if off_axis + math.asin(radius / distance if distance > radius else 1.0) > camera.hfov / 2 - margin:
        return False
    # The optical axis rises by -pitch; the ball's centre by atan2(dz, distance).
    vertical = abs(math.atan2(dz, distance) + camera.pitch) + math.asin(radius / slant)
    return vertical <= camera.vfov / 2 - margin


def ball_of(world, name):
    """(radius, centre height) of the named ball in a WorldSpec."""
    for model in world.models:
        if model.name == name:
            spheres = [geom for geom in model.collisions + model.visuals if geom.kind == 'sphere']
            if spheres:
                return max(geom.size[0] for geom in spheres), model.pose.z
    raise FlatsimError('the world has no ball named %r' % name)


def in_plain_sight(space, robot, place, ball_radius):
    """True when, from the placement, the robot's camera sees the whole of the ball's near side
    (FreeSpace.ball_edges_visible) and a corridor as wide as the robot, and at least
    CORRIDOR_HALF_WIDTH_M to each side, leads from the robot's origin to the ball with nothing
    in it (FreeSpace.in_sight). Fields of view aside: see whole_ball_in_view."""
    camera_x, camera_y, _yaw = robot.camera.world(place.robot_x, place.robot_y, place.robot_yaw)
    ball = (place.ball_x, place.ball_y)
    return (space.clearance(camera_x, camera_y) > 0.0
            and space.ball_edges_visible((camera_x, camera_y), ball, ball_radius)
            and space.in_sight((place.robot_x, place.robot_y), ball,
                               max(CORRIDOR_HALF_WIDTH_M, robot.half_width)))


def sample_placement(space, robot, rng, ball_radius, ball_z, ball_range=BALL_RANGE_M):
    """One placement drawn from rng by rejection; FlatsimError if none is found.

    The draw: the robot's position and heading, then the ball's distance from the
    camera and where across the camera's usable field of view it stands.
    """
    camera = robot.camera
    half_view = camera.hfov / 2 - VIEW_MARGIN_RAD
    # The whole ball fits in the view from this distance on.
    nearest = ball_radius / math.sin(half_view) if half_view > 0 else math.inf
    if nearest > ball_range[1]:
        raise FlatsimError('the camera\'s field of view (%.2f rad) is too narrow to hold the whole '
                           'ball (radius %.2f m) within %g m' % (camera.hfov, ball_radius, ball_range[1]))
    near = max(ball_range[0], nearest * (1 + 1e-9))
    x_min, x_max, y_min, y_max = space.bounds
    refused = collections.Counter()
    for _ in range(MAX_DRAWS):
        robot_x, robot_y = rng.uniform(x_min, x_max), rng.uniform(y_min, y_max)
        robot_yaw = rng.uniform(-math.pi, math.pi)
        distance = rng.uniform(near, ball_range[1])
        across = rng.uniform(-1.0, 1.0)
        camera_x, camera_y, camera_yaw = camera.world(robot_x, robot_y, robot_yaw)
        bearing = camera_yaw + across * (half_view - math.asin(ball_radius / distance))
        ball = camera_x + distance * math.cos(bearing), camera_y + distance * math.sin(bearing)
        outline = robot.outline(robot_x, robot_y, robot_yaw)
        why = refusal(space, camera, (camera_x, camera_y, camera_yaw), outline, (robot_x, robot_y),
                      ball, ball_z, ball_radius)
        if why:
            refused[why] += 1
            continue
        drawn = Placement(float(robot_x), float(robot_y), float(math.remainder(robot_yaw, 2 * math.pi)),
                          float(ball[0]), float(ball[1]))
        if in_plain_sight(space, robot, drawn, ball_radius):
            return drawn
        refused[NO_SIGHT] += 1
    raise FlatsimError('no free placement with the whole ball in the camera\'s view %g-%g m away '
                       'found in %d draws, refused for: %s'
                       % (ball_range[0], ball_range[1], MAX_DRAWS, refusals_text(refused)))


# Why a draw was refused, in the order the draw is checked.
BALL_NOT_FREE = 'the ball on a collider or outside the walls'
ROBOT_OUTSIDE = 'the robot outside the building\'s rooms'
BALL_OUT_OF_VIEW = 'the ball above or below the camera\'s view'
TOO_CLOSE = 'the ball within %.0f cm of the robot' % (100 * START_GAP_M)
ROBOT_ON_COLLIDER = 'the robot\'s outline on a collider'
NO_SIGHT = 'something between the camera and the ball'


def refusal(space, camera, camera_pose, outline, robot_xy, ball, ball_z, ball_radius):
    """Why a drawn placement cannot be used, or '' when it can (sight aside: in_plain_sight)."""
    if not space.free(*ball):
        return BALL_NOT_FREE
    if space.indoors and not space.enclosed(*robot_xy):
        return ROBOT_OUTSIDE
    if not whole_ball_in_view(camera, camera_pose, ball, ball_z, ball_radius):
        return BALL_OUT_OF_VIEW
    if polygon_distance(outline, [ball])[0] - ball_radius < START_GAP_M:
        return TOO_CLOSE
    if not space.outline_clear(outline):
        return ROBOT_ON_COLLIDER
    return ''


def refusals_text(refused):
    """'the ball on a collider or outside the walls (2,980), the robot outside ... (1,950), ...', most first."""
    return ', '.join('%s (%s)' % (why, '{:,}'.format(count)) for why, count in refused.most_common())


def sample_placements(space, robot, count, seed, ball_radius, ball_z, ball_range=BALL_RANGE_M):
    """count placements in a FreeSpace; placement i depends only on (seed, i)."""
    return [sample_placement(space, robot, np.random.default_rng([seed, index]), ball_radius, ball_z,
                             ball_range)
            for index in range(count)]


def plan_placements(world, robot, count, seed, ball, keep_out=(), spawn=(0.0, 0.0),
                    ball_range=BALL_RANGE_M):
    """(placements, notes) for a robot (RobotGeometry) chasing the named ball in a WorldSpec.

    Indoors when the world has a room large enough, else anywhere free (with a note); in a
    world with no colliders, around the spawn point (with a note).
    """
    radius, ball_z = ball_of(world, ball)
    keep_out = set(keep_out) | {ball}
    notes = [robot.note] if robot.note else []
    space = FreeSpace(world, keep_out=keep_out, around=spawn)
    if space.open:
        notes.append('the world has no colliders at working height: placements lie within %g m of '
                     'the robot\'s spawn point (%.2f, %.2f)' % (OPEN_WORLD_RADIUS_M, spawn[0], spawn[1]))
    try:
        return sample_placements(space, robot, count, seed, radius, ball_z, ball_range), notes
    except FlatsimError:
        if not space.indoors:
            raise
    space = FreeSpace(world, indoors=False, keep_out=keep_out)
    notes.append('the world has no enclosed room the size of a trial; placements may lie outdoors')
    return sample_placements(space, robot, count, seed, radius, ball_z, ball_range), notes


def robot_view(robot, space, robot_poses, ball_xy, ball_radius):
    """Per row: is some part of the ball inside the camera's horizontal view, with a clear line
    from the camera to its centre or one of its edges? (The vertical view is left aside: a
    ball on the floor stays in it while it is in the horizontal one.)"""
    seen = np.zeros(len(robot_poses), dtype=bool)
    for row, ((x, y, yaw), ball) in enumerate(zip(robot_poses, ball_xy)):
        camera_x, camera_y, camera_yaw = robot.camera.world(x, y, yaw)
        distance = math.hypot(ball[0] - camera_x, ball[1] - camera_y)
        if distance <= ball_radius:
            continue
        off_axis = abs(math.remainder(math.atan2(ball[1] - camera_y, ball[0] - camera_x) - camera_yaw,
                                      2 * math.pi))
        if off_axis - math.asin(ball_radius / distance) > robot.camera.hfov / 2:
            continue
        edges = ball_edges((camera_x, camera_y), ball, ball_radius)
        seen[row] = any(space.clear_rays((camera_x, camera_y), [edge]) for edge in edges)
    return seen
