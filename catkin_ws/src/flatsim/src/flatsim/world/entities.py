"""Gazebo's entities in a flatsim world: models and their links, by Gazebo's names.

gazebo_ros finds what a request names with World::EntityByName: a model by
its name, a link by its scoped name `model::link`, or by its bare name (the
first such link in world order). Gazebo's URDF import lumps every link that
hangs on a fixed joint into its parent, so the course robot has the links
robot_footprint, left_wheel and right_wheel, and `chassis` is no entity.

Poses and twists here follow ignition::math as gazebo_ros uses it:
`pose - frame` is the pose seen from frame, `pose + frame` puts a pose given
in frame into the world. Twists are ((vx, vy, vz), (wx, wy, wz)) in the world.
No ROS here.
"""
from dataclasses import dataclass

import numpy as np

from flatsim.errors import FlatsimError
from flatsim.loading.urdf_robot import link_pose
from flatsim.pose import Pose

WORLD_FRAMES = ('', 'world', 'map', '/map')


@dataclass(frozen=True)
class Entity:
    model: str
    link: str = ''        # '' for the model itself
    offset: Pose = Pose()  # the link's pose in the model frame

    @property
    def scoped_name(self):
        return '%s::%s' % (self.model, self.link) if self.link else self.model


def model_links(sim, name):
    """(link name, pose in the model frame) of each link of a model, in file order."""
    model = sim.models[name]
    spec = getattr(model, 'spec', None)
    if spec is not None:
        return robot_bodies(spec)
    source = getattr(model, 'source', None)
    return list(getattr(source, 'links', None) or [('link', Pose())])


def robot_bodies(spec):
    """The links Gazebo makes of a URDF: the root and every link on a movable joint."""
    moving = [spec.root_link] + [joint.child for joint in spec.joints.values() if joint.kind != 'fixed']
    order = {name: index for index, name in enumerate(spec.links)}
    moving.sort(key=lambda name: (name != spec.root_link, order.get(name, 0)))
    return [(name, link_pose(spec, name)) for name in moving]


def find_entity(sim, name):
    """The model or link a request names, or None."""
    if not name:
        return None
    if name in sim.models:
        return Entity(name)
    model_name, sep, link = name.partition('::')
    if sep and model_name in sim.models:
        for link_name, offset in model_links(sim, model_name):
            if link_name == link:
                return Entity(model_name, link_name, offset)
        return None
    for model_name in sim.models:
        for link_name, offset in model_links(sim, model_name):
            if link_name == name:
                return Entity(model_name, link_name, offset)
    return None


def entity_pose(sim, entity):
    offset = entity.offset
    if entity.link:
        # The links of a robot whose joints ros_control moves are where the joints put them.
        control = getattr(sim.models[entity.model], 'control', None)
        if control is not None:
            offset = control.link_pose(entity.link)
    return sim.model_pose(entity.model) * offset


def entity_twist(sim, entity):
    """World-frame linear and angular velocity of the entity's origin."""
    vx, vy, wz = sim.model_twist(entity.model)
    linear = np.array([vx, vy, 0.0])
    angular = np.array([0.0, 0.0, wz])
    if entity.link:
        model_pose = sim.model_pose(entity.model)
        lever = entity_pose(sim, entity).matrix()[:3, 3] - model_pose.matrix()[:3, 3]
        linear = linear + np.cross(angular, lever)
    return tuple(linear), tuple(angular)


def relative_pose(pose, frame):
    """ignition's `pose - frame`: pose as seen from frame."""
    return Pose.from_matrix(np.linalg.inv(frame.matrix()) @ pose.matrix())


def without_offset(pose, offset):
    """The model pose that puts a link with this offset at pose."""
    return Pose.from_matrix(pose.matrix() @ np.linalg.inv(offset.matrix()))


def rotate(frame, vector):
    return tuple(frame.matrix()[:3, :3] @ np.asarray(vector, dtype=float))


def rotate_reverse(frame, vector):
    return tuple(frame.matrix()[:3, :3].T @ np.asarray(vector, dtype=float))


def set_joint_positions(sim, name, positions):
    """Put the named joints of a ros_control robot at these positions, at rest, as
    Model::SetJointPositions does; returns the names it has no movable joint for
    (Gazebo passes over those). Controllers go on from the new positions."""
    robot = sim.models[name]
    control = getattr(robot, 'control', None)
    if control is None:
        raise FlatsimError('flatsim moves the joints of ros_control robots only; the joints '
                           'of %s stay where its description puts them' % name)
    bad = [joint for joint, value in positions.items() if not np.isfinite(value)]
    if bad:
        raise FlatsimError('joint position of %s is not a finite number' % ', '.join(bad))
    articulation = control.articulation
    unknown = []
    for joint, value in positions.items():
        if joint not in articulation.joints:
            unknown.append(joint)
            continue
        index = articulation.index(joint)
        articulation.position[index] = value
        articulation.velocity[index] = 0.0
    return unknown


def ball_names(sim):
    """The world's balls: its pushable spheres (dynamic models of one sphere), by name."""
    return sorted(name for name, model in sim.models.items() if model.kind == 'ball')


def the_ball(names):
    """The one ball among names (ball_names' answer), for tools that move 'the ball' of
    whatever world is loaded; FlatsimError when there is none or several."""
    if len(names) == 1:
        return names[0]
    if not names:
        raise FlatsimError('the world has no ball (a dynamic model made of one sphere)')
    raise FlatsimError('the world has %d balls (%s); name the one to move'
                       % (len(names), ', '.join(names)))
