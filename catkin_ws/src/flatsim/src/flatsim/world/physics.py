"""Top-down 2D rigid body physics for flatsim, on pymunk.

Everything lives in the ground plane seen from above; there is no gravity.
Static colliders are walls and furniture cut at the robot's working height.
Dynamic bodies are robots, driven through their drive plugin, balls that
robots push and that roll to a stop, and other dynamic models (a box, a
chair) that slide when pushed, braked by their friction on the ground.

A robot is driven as pymunk's examples/tank.py drives its tank: a kinematic
control body moves at the drive's target twist each step, and a pivot joint
(linear) plus a gear joint (yaw) pull the robot after it. Both joints are pure
velocity constraints whose force and torque are capped by the wheel torque
limit, so the robot reaches the commanded twist exactly when the wheels are
strong enough, accelerates at the torque limit when they are not, and stops
at obstacles through ordinary contact response.
"""
import math
from dataclasses import dataclass, field
from typing import List, Optional

import pymunk

from flatsim.errors import FlatsimError
from flatsim.names import logged_name

# Shape filter categories, for sensors that raycast only some kinds of shape.
STATIC_CATEGORY = 0b001
ROBOT_CATEGORY = 0b010
BALL_CATEGORY = 0b100
BODY_CATEGORY = 0b1000
# pymunk collision type of bodies' shapes, whose contacts with each other are checked in height.
BODY_COLLISION_TYPE = 1

# Overlap (m) that contacts leave uncorrected; pymunk's default of 0.1 suits
# pixel-sized worlds, not one measured in metres.
COLLISION_SLOP = 0.001

# pymunk multiplies the two shapes' values: ball on wall 0.36 (a small bounce),
# robot on wall or ball 0.12, robot on robot 0.04.
STATIC_ELASTICITY = 0.6
BALL_ELASTICITY = 0.6
ROBOT_ELASTICITY = 0.2
STATIC_FRICTION = 0.6
BALL_FRICTION = 0.6
ROBOT_FRICTION = 0.5
BODY_ELASTICITY = 0.2
BODY_FRICTION = 0.6

# What presses a sliding model onto the ground (m/s^2): Gazebo's default gravity.
GRAVITY = 9.8

# A ball rolling on the floor slows at this rate (m/s^2): from 1 m/s it coasts 2.5 m.
BALL_ROLLING_DECELERATION = 0.2

# A robot without a drive plugin rests on its wheels like a braked cart.
UNDRIVEN_DECELERATION = 5.0

# A drive that sets the body's velocity outright (planar move) holds it against this much
# acceleration (m/s^2, and rad/s^2 for the spin): far beyond any wheel's, yet contacts still win.
SET_VELOCITY_ACCELERATION = 100.0

# A body's spin about the vertical axis dies down at this rate (rad/s^2) when nothing drives it.
SPIN_DECELERATION = 2.0

# Bounds far beyond any course world that keep pymunk's arithmetic finite:
# requests past them are refused, and bodies that a step pushes past them slowed.
MAX_COORDINATE = 1e5       # m from the origin
MAX_SPEED = 100.0          # m/s
MAX_SPIN = 1000.0          # rad/s
MIN_BODY_SIZE = 1e-4       # m
# pymunk squares masses and moments on the way to an impulse: a mass near 1e154 kg
# overflows to inf at the first contact-free step.
MIN_MASS = 1e-9            # kg
MAX_MASS = 1e9             # kg


class PhysicsDiverged(FlatsimError):
    """A body's state stopped being finite numbers; model names it."""

    def __init__(self, model):
        self.model = model
        super().__init__('physics diverged for model %r' % logged_name(model))


@dataclass(eq=False)
class BodyHandle:
    """A dynamic body: its model name, its pymunk parts and, for a robot, its drive."""
    name: str
    kind: str                                 # 'robot' | 'ball' | 'body'
    body: pymunk.Body
    shapes: List[pymunk.Shape]
    # Robots: kinematic body that carries the drive target; balls: none.
    control: Optional[pymunk.Body] = None
    constraints: List[pymunk.Constraint] = field(default_factory=list)
    drive: object = None
    group: int = 0                            # pymunk ShapeFilter group of this body's shapes

    @property
    def shape_filter(self):
        """A query filter that leaves out this body's own shapes (for its sensors)."""
        return pymunk.ShapeFilter(group=self.group)


def _finite(*values):
    return all(math.isfinite(v) for v in values)


def _check_finite(what, *values):
    if not _finite(*values):
        raise FlatsimError('%s: %r is not all finite numbers' % (what, values))


def check_twist(what, vx, vy, wz):
    _check_finite('twist of %r' % what, vx, vy, wz)
    if math.hypot(vx, vy) > MAX_SPEED or abs(wz) > MAX_SPIN:
        raise FlatsimError('twist of %r: (%g m/s, %g m/s, %g rad/s) is beyond the %g m/s and '
                           '%g rad/s flatsim simulates' % (what, vx, vy, wz, MAX_SPEED, MAX_SPIN))


def check_position(what, x, y):
    _check_finite('position of %s' % what, x, y)
    if abs(x) > MAX_COORDINATE or abs(y) > MAX_COORDINATE:
        raise FlatsimError('position of %s: (%g, %g) is beyond the %g m from the origin that '
                           'flatsim simulates' % (what, x, y, MAX_COORDINATE))


def _check_mass(what, mass):
    if not MIN_MASS <= mass <= MAX_MASS:
        raise FlatsimError('%s: mass %g kg is outside the %g to %g kg flatsim simulates'
                           % (what, mass, MIN_MASS, MAX_MASS))


def _check_positive(what, *values):
    _check_finite(what, *values)
    if not all(v > 0.0 for v in values):
        raise FlatsimError('%s: %r must be positive' % (what, values))


def _friction_joints(body, anchor_body, force, torque, at=(0, 0)):
    """Joints that brake the body against the ground with a fixed force and torque, the
    force acting at the point at of the body (in its frame)."""
    slide = pymunk.PivotJoint(anchor_body, body, (0, 0), tuple(at))
    spin = pymunk.GearJoint(anchor_body, body, 0.0, 1.0)
    for joint, limit in ((slide, force), (spin, torque)):
        joint.max_bias = 0.0  # velocity only: never pull the body back to the anchor
        joint.max_force = limit
    return [slide, spin]


class Physics:
    """A pymunk space stepped at a fixed step; the caller owns simulation time."""

    def __init__(self, step=0.002):
        _check_positive('physics step', step)
        self.step_size = float(step)
        self.space = pymunk.Space()
        self.space.gravity = (0.0, 0.0)
        self.space.collision_slop = COLLISION_SLOP
        self._handles = {}
        self._next_group = 1
        # id of a body's shape -> (z_min, z_max): bodies meet only where their heights overlap
        # (a crate stacked on another passes over what the lower one meets).
        self._heights = {}
        self.space.on_collision(BODY_COLLISION_TYPE, BODY_COLLISION_TYPE,
                                pre_solve=self._bodies_meet_in_height)
        # Names of bodies a step slowed to MAX_SPEED or MAX_SPIN; the caller reports and clears it.
        self.slowed = set()

    def add_static_box(self, x, y, yaw, half_x, half_y):
        """A box collider centred at (x, y) and turned by yaw; returns its pymunk shape."""
        _check_finite('static box pose', x, y, yaw)
        _check_positive('static box half size', half_x, half_y)
        transform = pymunk.Transform.translation(x, y).rotated(yaw)
        corners = [(-half_x, -half_y), (half_x, -half_y), (half_x, half_y), (-half_x, half_y)]
        return self._add_static(pymunk.Poly(self.space.static_body, corners, transform))

    def add_static_circle(self, x, y, radius):
        """A round collider (a cylinder cut in the plane); returns its pymunk shape."""
        _check_finite('static circle centre', x, y)
        _check_positive('static circle radius', radius)
        return self._add_static(pymunk.Circle(self.space.static_body, radius, (x, y)))

    def _add_static(self, shape):
        shape.elasticity = STATIC_ELASTICITY
        shape.friction = STATIC_FRICTION
        shape.filter = pymunk.ShapeFilter(categories=STATIC_CATEGORY)
        self.space.add(shape)
        return shape

    def remove_static(self, shape):
        self.space.remove(shape)

    def restore_static(self, shape):
        """Puts back a collider that remove_static took out."""
        self.space.add(shape)

    def static_count(self):
        """How many static colliders the world has."""
        # A removed shape stays attached to the static body; count those in the space.
        return sum(1 for shape in self.space.static_body.shapes if shape.space is self.space)

    def add_ball(self, name, x, y, radius, mass):
        """A ball that robots push; it rolls, bounces a little off walls and comes to rest."""
        check_position('ball %r' % name, x, y)
        _check_positive('ball size and mass', radius, mass)
        _check_mass('ball %r' % name, mass)
        if radius < MIN_BODY_SIZE:
            raise FlatsimError('ball %r: radius %g m is below the %g m flatsim simulates'
                               % (name, radius, MIN_BODY_SIZE))
        body = pymunk.Body(mass, pymunk.moment_for_circle(mass, 0.0, radius))
        shape = pymunk.Circle(body, radius)
        shape.elasticity = BALL_ELASTICITY
        shape.friction = BALL_FRICTION
        handle = self._register(name, 'ball', body, [shape], BALL_CATEGORY)
        handle.constraints = _friction_joints(
            body, self.space.static_body, mass * BALL_ROLLING_DECELERATION,
            body.moment * SPIN_DECELERATION)
        body.position = (x, y)
        self.space.add(body, shape, *handle.constraints)
        return handle

    def add_body(self, name, prims, mass, moment, centre, x, y, yaw, friction):
        """A dynamic model that robots and balls push: one body made of boxes and circles
        (scene Prims in the body frame, cut in the plane), its centre of mass at centre (in
        the body frame) with that moment of inertia about it. The ground brakes it as
        Coulomb friction does: a force of friction * mass * GRAVITY against its sliding, and
        against its spin the torque that force gives spread over a disc of its footprint's
        area (2/3 of the force times the disc's radius)."""
        check_position('model %r' % name, x, y)
        _check_finite('pose of model %r' % name, yaw)
        _check_positive('model %r mass and moment of inertia' % name, mass, moment)
        _check_mass('model %r' % name, mass)
        _check_finite('friction of model %r' % name, friction, *centre)
        if friction < 0.0:
            raise FlatsimError('model %r: friction %g is negative' % (name, friction))
        body = pymunk.Body(mass, moment)
        body.center_of_gravity = tuple(centre)
        shapes = []
        for prim in prims:
            if prim.kind == 'box':
                _check_positive('box %r half size' % prim.name, prim.half_x, prim.half_y)
                transform = pymunk.Transform.translation(prim.x, prim.y).rotated(prim.yaw)
                corners = [(-prim.half_x, -prim.half_y), (prim.half_x, -prim.half_y),
                           (prim.half_x, prim.half_y), (-prim.half_x, prim.half_y)]
                shape = pymunk.Poly(body, corners, transform)
            else:
                _check_positive('%s %r radius' % (prim.kind, prim.name), prim.radius)
                shape = pymunk.Circle(body, prim.radius, (prim.x, prim.y))
            shape.elasticity = BODY_ELASTICITY
            shape.friction = BODY_FRICTION
            shape.collision_type = BODY_COLLISION_TYPE
            self._heights[id(shape)] = (prim.z_min, prim.z_max)
            shapes.append(shape)
        handle = self._register(name, 'body', body, shapes, BODY_CATEGORY)
        force = friction * mass * GRAVITY
        reach = math.sqrt(sum(shape.area for shape in shapes) / math.pi)
        handle.constraints = _friction_joints(body, self.space.static_body, force,
                                              2.0 / 3.0 * force * reach, at=centre)
        body.position = (x, y)
        body.angle = yaw
        self.space.add(body, *shapes, *handle.constraints)
        return handle

    def _bodies_meet_in_height(self, arbiter, _space, _data):
        first, second = (self._heights.get(id(shape)) for shape in arbiter.shapes)
        # Within a micrometre counts as one resting on the other.
        if first and second and (first[1] <= second[0] + 1e-6 or second[1] <= first[0] + 1e-6):
            arbiter.process_collision = False

    def add_robot(self, name, footprint_points, mass, x, y, yaw, drive=None, fixed=False):
        """A robot body shaped as the convex hull of its footprint (x, y points in its base frame).

        The base frame origin is where the drive acts and is the body's centre
        of gravity. With drive None the robot only brakes, like a parked cart.
        fixed: the robot is bolted to the world (a URDF whose root link is
        `world`, as for an arm): nothing moves it.
        """
        _check_finite('robot pose', x, y, yaw)
        # Checked before the robot takes its name: a refused placement leaves nothing behind.
        check_position('robot %r' % name, x, y)
        _check_positive('robot mass', mass)
        _check_mass('robot %r' % name, mass)
        points = [(float(px), float(py)) for px, py in footprint_points]
        if len(points) < 3 or not all(_finite(*p) for p in points):
            raise FlatsimError('robot %r: footprint needs at least three finite points, got %r' % (name, points))
        shape = pymunk.Poly(None, points)
        if shape.area <= 1e-12:
            raise FlatsimError('robot %r: footprint %r has no area' % (name, points))
        moment = pymunk.moment_for_poly(mass, shape.get_vertices())
        body = pymunk.Body(body_type=pymunk.Body.STATIC) if fixed else pymunk.Body(mass, moment)
        shape.body = body
        shape.elasticity = ROBOT_ELASTICITY
        shape.friction = ROBOT_FRICTION
        handle = self._register(name, 'robot', body, [shape], ROBOT_CATEGORY)
        if fixed:
            self.space.add(body, shape)
            self.set_pose(handle, x, y, yaw)
            return handle
        handle.drive = drive
        handle.control = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        if drive is None:
            force, torque = mass * UNDRIVEN_DECELERATION, moment * SPIN_DECELERATION
        elif drive.max_force is None:
            force, torque = mass * SET_VELOCITY_ACCELERATION, moment * SET_VELOCITY_ACCELERATION
        else:
            force, torque = drive.max_force, drive.max_torque
        handle.constraints = _friction_joints(body, handle.control, force, torque)
        self.space.add(body, shape, handle.control, *handle.constraints)
        self.set_pose(handle, x, y, yaw)
        return handle

    def _register(self, name, kind, body, shapes, category):
        if name in self._handles:
            raise FlatsimError('a model named %r already exists' % name)
        group = self._next_group
        self._next_group += 1
        for shape in shapes:
            shape.filter = pymunk.ShapeFilter(group=group, categories=category)
        handle = BodyHandle(name, kind, body, shapes, group=group)
        self._handles[name] = handle
        return handle

    def handle(self, name):
        try:
            return self._handles[name]
        except KeyError:
            raise FlatsimError('no model named %r' % name) from None

    def bodies(self):
        """Every dynamic body (robots, balls and other models), in the order they were added."""
        return list(self._handles.values())

    @staticmethod
    def _parts(handle):
        parts = [handle.body, *handle.shapes, *handle.constraints]
        if handle.control is not None:
            parts.append(handle.control)
        return parts

    def remove(self, handle):
        self.space.remove(*self._parts(handle))
        del self._handles[handle.name]

    def restore(self, handle):
        """Puts back a body that remove took out, with the pose and velocity it had."""
        if handle.name in self._handles:
            raise FlatsimError('a model named %r already exists' % handle.name)
        self.space.add(*self._parts(handle))
        self._handles[handle.name] = handle

    def set_pose(self, handle, x, y, yaw):
        _check_finite('pose of %r' % handle.name, x, y, yaw)
        check_position(handle.name, x, y)
        for body in (handle.body, handle.control):
            if body is not None:
                body.position = (x, y)
                body.angle = yaw
        self.space.reindex_shapes_for_body(handle.body)

    def set_twist(self, handle, vx, vy, wz):
        """Set the world-frame velocity; a robot's drive then pulls it back to its command."""
        check_twist(handle.name, vx, vy, wz)
        handle.body.velocity = (vx, vy)
        handle.body.angular_velocity = wz

    def apply_force(self, handle, force, offset, torque):
        """Push the body for the next step: a world-frame force (fx, fy) at a point
        (x, y) of the body frame, and a torque about the vertical axis."""
        _check_finite('wrench on %r' % handle.name, *force, *offset, torque)
        body = handle.body
        body.apply_force_at_world_point(tuple(force), body.local_to_world(tuple(offset)))
        body.torque += torque

    def restart(self, handle, x, y, yaw):
        """Put a body at a pose, at rest and with no contact remembered: after a divergence
        pymunk's cached contacts would carry the non-finite impulses into the next step."""
        if handle.body.body_type == pymunk.Body.STATIC:
            # Bolted to the world: no mass to carry over, no joints, no velocity of its own.
            self.set_pose(handle, x, y, yaw)
            return
        old = handle.body
        self.space.remove(old, *handle.shapes, *handle.constraints)
        # A new body and new joints: pymunk keeps a body's bias velocity and a joint's last
        # impulse from step to step, and after a divergence both are non-finite.
        handle.body = pymunk.Body(old.mass, old.moment)
        handle.body.center_of_gravity = old.center_of_gravity
        for shape in handle.shapes:
            shape.body = handle.body
        slide, spin = handle.constraints
        handle.constraints = _friction_joints(handle.body, slide.a, slide.max_force, spin.max_force,
                                              at=slide.anchor_b)
        # A non-finite impulse times a static body's zero inverse mass is not zero either.
        for anchor in (handle.control, self.space.static_body):
            if anchor is not None:
                anchor.velocity, anchor.angular_velocity = (0.0, 0.0), 0.0
        self.space.add(handle.body, *handle.shapes, *handle.constraints)
        self.set_pose(handle, x, y, yaw)

    def pose(self, handle):
        """(x, y, yaw) of the body origin in the world, yaw in [-pi, pi] as a quaternion gives it."""
        body = handle.body
        return body.position.x, body.position.y, math.atan2(math.sin(body.angle), math.cos(body.angle))

    def twist(self, handle):
        """(vx, vy, wz) of the body origin in the world frame."""
        body = handle.body
        return body.velocity.x, body.velocity.y, body.angular_velocity

    def body_twist(self, handle):
        """(forward, leftward, yaw rate) in the body's own frame."""
        body = handle.body
        local = body.velocity.rotated(-body.angle)
        return local.x, local.y, body.angular_velocity

    def step(self):
        """Advance exactly one fixed step: each drive sets its target, then pymunk integrates."""
        dt = self.step_size
        for handle in self._handles.values():
            if handle.kind == 'robot' and handle.control is not None:
                self._steer(handle, dt)
        self.space.step(dt)
        for handle in self._handles.values():
            body = handle.body
            if not _finite(body.position.x, body.position.y, body.angle,
                           body.velocity.x, body.velocity.y, body.angular_velocity):
                raise PhysicsDiverged(handle.name)
            self._bound_speed(handle)

    def _bound_speed(self, handle):
        body = handle.body
        speed = math.hypot(body.velocity.x, body.velocity.y)   # length would overflow squaring
        if speed > MAX_SPEED:
            body.velocity = body.velocity * (MAX_SPEED / speed)
            self.slowed.add(handle.name)
        if abs(body.angular_velocity) > MAX_SPIN:
            body.angular_velocity = math.copysign(MAX_SPIN, body.angular_velocity)
            self.slowed.add(handle.name)

    def _steer(self, handle, dt):
        body, control = handle.body, handle.control
        if handle.drive is None:
            forward, leftward, angular = 0.0, 0.0, 0.0
        else:
            forward, leftward, angular = handle.drive.update(dt, *self.body_twist(handle))
        # Heading at mid-step: pymunk moves the body along a straight chord, and
        # the chord of a circular arc points along the mid-step heading.
        heading = body.angle + angular * dt / 2.0
        cos_heading, sin_heading = math.cos(heading), math.sin(heading)
        control.position = body.position
        control.angle = body.angle
        control.velocity = (forward * cos_heading - leftward * sin_heading,
                            forward * sin_heading + leftward * cos_heading)
        control.angular_velocity = angular
