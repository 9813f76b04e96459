"""Rigid-body dynamics of a robot's movable joints on a base that stays put.

Links joined by fixed joints are lumped into one body (their masses, centres
of mass and inertias combined), as Gazebo's URDF conversion does. Each
revolute, continuous or prismatic joint then moves one body relative to its
parent. The equations of motion M(q) qdd + b(q, qd) = tau come from the
recursive Newton-Euler algorithm: b with the joint accelerations at zero
(gravity, Coriolis and centrifugal terms), and each column of M with one unit
acceleration and neither gravity nor velocity. A step is semi-implicit Euler.

On the joint forces, as Gazebo applies them (gazebo::physics::Joint):
- beyond the joint's velocity limit, effort that would speed it up is dropped;
- effort is clamped to the effort limit;
- viscous damping is integrated implicitly, so large damping stays stable;
- Coulomb friction stops a slow joint outright, like ODE's friction motor;
- position limits (revolute, prismatic) are hard stops.
A joint on a position interface is placed where it is told (Gazebo's
SetPosition); one on a velocity interface is driven by a motor with the
effort limit as its strength (Gazebo's "vel"/"fmax" joint parameters).
"""
import math

import numpy as np

from flatsim.errors import FlatsimError
from flatsim.pose import Pose
from flatsim.sensors.raycast import jit

GRAVITY = 9.80665
# A body lighter than this gets this much mass and inertia, so M stays invertible.
MIN_MASS = 1e-6
MIN_INERTIA = 1e-9


@jit
def _rotation(axis, angle):
    """Rotation matrix about a unit axis (Rodrigues)."""
    x, y, z = axis[0], axis[1], axis[2]
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    return np.array([[t * x * x + c, t * x * y - s * z, t * x * z + s * y],
                     [t * x * y + s * z, t * y * y + c, t * y * z - s * x],
                     [t * x * z - s * y, t * y * z + s * x, t * z * z + c]])


@jit
def _mul(a, b):
    """Matrix product without BLAS (numba's @ needs scipy), for the small matrices here."""
    out = np.zeros((a.shape[0], b.shape[1]))
    for i in range(a.shape[0]):
        for j in range(b.shape[1]):
            for k in range(a.shape[1]):
                out[i, j] += a[i, k] * b[k, j]
    return out


@jit
def _apply(matrix, vector):
    out = np.zeros(3)
    for i in range(3):
        out[i] = matrix[i, 0] * vector[0] + matrix[i, 1] * vector[1] + matrix[i, 2] * vector[2]
    return out


@jit
def _frames(position, parent, origin, axis, prismatic):
    """Each body's 4x4 pose in the base frame (parents come before children)."""
    n = position.size
    frames = np.empty((n, 4, 4))
    for k in range(n):
        motion = np.eye(4)
        if prismatic[k]:
            motion[:3, 3] = axis[k] * position[k]
        else:
            motion[:3, :3] = _rotation(axis[k], position[k])
        base = np.eye(4) if parent[k] == 0 else frames[parent[k] - 1]
        frames[k] = _mul(_mul(base, origin[k]), motion)
    return frames


@jit
def _rnea(frames, velocity, acceleration, gravity, parent, axis, prismatic, mass, com, inertia):
    """Joint forces for these accelerations (recursive Newton-Euler in the base frame)."""
    n = velocity.size
    omega = np.zeros((n + 1, 3))
    alpha = np.zeros((n + 1, 3))
    accel = np.zeros((n + 1, 3))          # linear acceleration of each body-frame origin
    origin = np.zeros((n + 1, 3))
    accel[0, 2] = gravity                 # the base accelerates up: gravity on every body
    axes_w = np.zeros((n, 3))
    force = np.zeros((n + 1, 3))
    moment = np.zeros((n + 1, 3))
    for k in range(n):
        b, p = k + 1, parent[k]
        rot = frames[k, :3, :3].copy()
        origin[b] = frames[k, :3, 3]
        joint_axis = _apply(rot, axis[k])
        axes_w[k] = joint_axis
        arm = origin[b] - origin[p]
        base_accel = accel[p] + np.cross(alpha[p], arm) + np.cross(omega[p], np.cross(omega[p], arm))
        if prismatic[k]:
            omega[b] = omega[p]
            alpha[b] = alpha[p]
            accel[b] = (base_accel + 2.0 * np.cross(omega[p], joint_axis * velocity[k])
                        + joint_axis * acceleration[k])
        else:
            omega[b] = omega[p] + joint_axis * velocity[k]
            alpha[b] = alpha[p] + joint_axis * acceleration[k] + np.cross(omega[p], joint_axis * velocity[k])
            accel[b] = base_accel
        to_com = _apply(rot, com[k])
        accel_com = accel[b] + np.cross(alpha[b], to_com) + np.cross(omega[b], np.cross(omega[b], to_com))
        inertia_w = _mul(_mul(rot, inertia[k]), rot.T.copy())
        force[b] = mass[k] * accel_com
        moment[b] = _apply(inertia_w, alpha[b]) + np.cross(omega[b], _apply(inertia_w, omega[b])) \
            + np.cross(to_com, force[b])
    tau = np.zeros(n)
    for k in range(n - 1, -1, -1):
        b, p = k + 1, parent[k]
        along = force[b] if prismatic[k] else moment[b]
        tau[k] = axes_w[k, 0] * along[0] + axes_w[k, 1] * along[1] + axes_w[k, 2] * along[2]
        if p > 0:
            force[p] += force[b]
            moment[p] += moment[b] + np.cross(origin[b] - origin[p], force[b])
    return tau


@jit
def _mass_matrix_and_bias(position, velocity, gravity, parent, origin, axis, prismatic, mass,
                          com, inertia):
    frames = _frames(position, parent, origin, axis, prismatic)
    n = position.size
    zero = np.zeros(n)
    bias = _rnea(frames, velocity, zero, gravity, parent, axis, prismatic, mass, com, inertia)
    matrix = np.empty((n, n))
    for j in range(n):
        unit = np.zeros(n)
        unit[j] = 1.0
        matrix[:, j] = _rnea(frames, zero, unit, 0.0, parent, axis, prismatic, mass, com, inertia)
    return matrix, bias


def _lump(parts):
    """(mass, centre of mass, inertia about it) of parts given as (mass, com, inertia at com)."""
    mass = sum(m for m, _, _ in parts)
    if mass <= 0.0:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    com = sum(m * c for m, c, _ in parts) / mass
    inertia = np.zeros((3, 3))
    for m, c, i in parts:
        d = c - com
        inertia += i + m * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return mass, com, inertia


class Articulation:
    """The movable joints of one robot, their state, and one step of their motion.

    joints: the movable joint names, in the order of every array here (parents
    before children). position, velocity and effort are per joint.
    """

    def __init__(self, spec):
        model = spec.articulation
        children = {}
        for joint in spec.joints.values():
            children.setdefault(joint.parent, []).append(joint)
        self.joints, self.kinds, self.models = [], [], []
        parent_body, origins, axes = [], [], []
        # body -> list of (mass, com, inertia) parts in the body frame
        parts = [[]]
        link_body = {spec.root_link: (0, Pose())}
        pending = [spec.root_link]
        while pending:
            link = pending.pop(0)
            body, to_body = link_body[link]
            inertial = model.inertials.get(link)
            if inertial is not None and inertial.mass > 0.0:
                pose = to_body * inertial.origin
                rot = pose.matrix()[:3, :3]
                parts[body].append((inertial.mass, np.array([pose.x, pose.y, pose.z]),
                                    rot @ inertial.inertia @ rot.T))
            for joint in sorted(children.get(link, []), key=lambda j: j.name):
                if joint.name in model.joints:
                    self.joints.append(joint.name)
                    self.kinds.append(joint.kind)
                    self.models.append(model.joints[joint.name])
                    parent_body.append(body)
                    origins.append((to_body * joint.origin).matrix())
                    axis = np.asarray(joint.axis, dtype=float)
                    norm = np.linalg.norm(axis)
                    if not norm > 0.0:
                        raise FlatsimError('joint %s has a zero axis' % joint.name)
                    axes.append(axis / norm)
                    parts.append([])
                    link_body[joint.child] = (len(self.joints), Pose())
                else:
                    link_body[joint.child] = (body, to_body * joint.origin)
                pending.append(joint.child)
        self.parent = np.array(parent_body, dtype=np.int64)   # parent body of each joint's body
        self.origin = np.array(origins).reshape(-1, 4, 4)
        self.axis = np.array(axes).reshape(-1, 3)
        self.prismatic = np.array([kind == 'prismatic' for kind in self.kinds], dtype=bool)
        bodies = [_lump(p) for p in parts]
        self.mass = np.array([max(m, MIN_MASS) for m, _, _ in bodies[1:]])
        self.com = np.array([c for _, c, _ in bodies[1:]]).reshape(-1, 3)
        self.inertia = np.array([i + MIN_INERTIA * np.eye(3) for _, _, i in bodies[1:]]).reshape(-1, 3, 3)
        n = len(self.joints)
        self.position = np.zeros(n)
        self.velocity = np.zeros(n)
        self.effort = np.zeros(n)
        self.lower = np.array([m.limits.lower if m.limits.lower is not None else -np.inf
                               for m in self.models])
        self.upper = np.array([m.limits.upper if m.limits.upper is not None else np.inf
                               for m in self.models])
        self.effort_limit = np.array([m.limits.effort if m.limits.effort else np.inf
                                      for m in self.models])
        self.velocity_limit = np.array([m.limits.velocity if m.limits.velocity else np.inf
                                        for m in self.models])
        self.damping = np.array([m.damping for m in self.models])
        self.friction = np.array([m.friction for m in self.models])
        # Joints placed by a position interface (value: target) or driven at a velocity.
        self.position_target = np.full(n, np.nan)
        self.velocity_target = np.full(n, np.nan)

    def index(self, joint):
        return self.joints.index(joint)

    # -- kinematics ---------------------------------------------------------
    def body_frames(self, position=None):
        """Each body's 4x4 pose in the base frame."""
        position = self.position if position is None else np.asarray(position, dtype=float)
        return _frames(position, self.parent, self.origin, self.axis, self.prismatic)

    def link_offset(self, spec, link):
        """(movable joint index or -1 for the base, pose of link in that body's frame)."""
        parent_joint = {joint.child: joint for joint in spec.joints.values()}
        pose = Pose()
        while link != spec.root_link:
            joint = parent_joint[link]
            if joint.name in self.joints:
                return self.joints.index(joint.name), pose
            pose = joint.origin * pose
            link = joint.parent
        return -1, pose

    # -- dynamics -----------------------------------------------------------
    def mass_matrix_and_bias(self):
        """M(q) and b(q, qd) (gravity, Coriolis, centrifugal) at the present state."""
        return _mass_matrix_and_bias(self.position, self.velocity, GRAVITY, self.parent,
                                     self.origin, self.axis, self.prismatic, self.mass, self.com,
                                     self.inertia)

    def step(self, dt, effort):
        """Advance by dt with these commanded joint efforts (N*m or N); returns the efforts applied."""
        if not len(self.joints):
            return effort
        mass, bias = self.mass_matrix_and_bias()
        applied = np.where(np.isfinite(effort), effort, 0.0)
        motor = np.isfinite(self.velocity_target)
        if motor.any():
            # A velocity motor pushes with what reaching the target in one step takes.
            need = np.diag(mass) * (self.velocity_target - self.velocity) / dt + bias
            applied = np.where(motor, need, applied)
        # Gazebo drops effort that would push a joint further past its velocity limit.
        over = np.abs(self.velocity) > self.velocity_limit
        applied = np.where(over & (np.sign(applied) == np.sign(self.velocity)), 0.0, applied)
        applied = np.clip(applied, -self.effort_limit, self.effort_limit)
        placed = np.isfinite(self.position_target)
        acceleration = np.zeros(len(self.joints))
        free = ~placed
        if free.any():
            # A placed joint moves as it is told: only the others answer to the forces.
            acceleration[free] = np.linalg.solve(mass[np.ix_(free, free)], (applied - bias)[free])
        velocity = self.velocity + acceleration * dt
        diagonal = np.diag(mass)
        velocity /= 1.0 + self.damping * dt / diagonal
        stop = self.friction * dt / diagonal
        velocity = np.where(np.abs(velocity) <= stop, 0.0, velocity - np.sign(velocity) * stop)
        position = self.position + velocity * dt
        if placed.any():
            position = np.where(placed, self.position_target, position)
            velocity = np.where(placed, (position - self.position) / dt, velocity)
        hit = (position < self.lower) | (position > self.upper)
        position = np.clip(position, self.lower, self.upper)
        velocity = np.where(hit, 0.0, velocity)
        if not (np.isfinite(position).all() and np.isfinite(velocity).all()):
            raise FlatsimError('joint motion diverged (%s)' % ', '.join(self.joints))
        self.position, self.velocity, self.effort = position, velocity, applied
        return applied
