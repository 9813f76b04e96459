"""Gazebo's ROS API, as gazebo_ros_api_plugin (noetic) offers it, served by flatsim.

Everything lives under `gazebo/` in flatsim's namespace, so `/gazebo/...` by
default, with gazebo_msgs types and gazebo_ros's success flags, status
messages and reference-frame rules:

Topics: gazebo/model_states, gazebo/link_states (gazebo_msgs/ModelStates,
LinkStates; world frame, at ~model_states_rate while subscribed);
subscribes to gazebo/set_model_state and gazebo/set_link_state.
Flatsim's own: ~model_moves (std_msgs/String), one JSON object per model moved
by set_model_state or set_link_state (service or topic) or pushed by
apply_body_wrench: {"time": sim seconds, "by": the caller's node name as its
connection header gives it, "through": the service or topic, "target": the
model, link or body}. A grader tells its own placements from a node's.
Services: gazebo/get_model_state, set_model_state, get_link_state,
set_link_state, get_world_properties, get_model_properties, spawn_urdf_model,
spawn_sdf_model, delete_model, pause_physics, unpause_physics,
reset_simulation, reset_world, get_physics_properties, set_physics_properties,
apply_body_wrench, clear_body_wrenches, set_model_configuration.

What the plane cannot hold is said plainly rather than faked: heights, roll
and pitch of a requested pose are not applied to a moving model (robots stand
on the ground, balls and other bodies keep their height above it), nor are z
forces or x/y torques; a static or jointed model, which nothing pushes, takes
the whole requested pose, as in Gazebo; joint positions are not set.
"""
import copy
import json
import math
import xml.etree.ElementTree as ET

import rospy
from gazebo_msgs.msg import LinkState, LinkStates, ModelState, ModelStates, ODEPhysics
from gazebo_msgs.srv import (
    ApplyBodyWrench, ApplyBodyWrenchResponse, BodyRequest, BodyRequestResponse,
    DeleteModel, DeleteModelResponse, GetLinkState, GetLinkStateResponse,
    GetModelProperties, GetModelPropertiesResponse, GetModelState, GetModelStateResponse,
    GetPhysicsProperties, GetPhysicsPropertiesResponse, GetWorldProperties,
    GetWorldPropertiesResponse, SetLinkState, SetLinkStateResponse, SetModelConfiguration,
    SetModelConfigurationResponse, SetModelState, SetModelStateResponse,
    SetPhysicsProperties, SetPhysicsPropertiesResponse, SpawnModel, SpawnModelResponse)
from geometry_msgs.msg import Twist, Vector3
from std_msgs.msg import String
from std_srvs.srv import Empty, EmptyResponse

from flatsim import settings
from flatsim.errors import FlatsimError
from flatsim.loading.model_path import find_model, model_name_from_uri, model_path
from flatsim.loading.sdf_world import read_spawned_model
from flatsim.loading.urdf_robot import load_robot
from flatsim.names import logged_name
from flatsim.pose import Pose
from flatsim.ros import messages as rosmsg
from flatsim.world import entities
from flatsim.world.entities import WORLD_FRAMES
from flatsim.world.model_geometry import root_height
from flatsim.world.sim import check_step_size
from flatsim.world.wrench import WrenchJob

NAMESPACE = 'gazebo/'
MOVES_TOPIC = '~model_moves'
# SDF's defaults for <physics type="ode">, which Gazebo reports for a world that sets none.
ODE_DEFAULTS = dict(auto_disable_bodies=False, sor_pgs_precon_iters=0, sor_pgs_iters=50,
                    sor_pgs_w=1.3, sor_pgs_rms_error_tol=0.0, contact_surface_layer=0.001,
                    contact_max_correcting_vel=100.0, cfm=0.0, erp=0.2, max_contacts=20)
_WRENCH_OVERFLOWS = ('ApplyBodyWrench: the wrench overflows: the torque of that force about the '
                     'body is beyond what a float holds; use a smaller force or a nearer '
                     'reference_point')
SPAWN_NOT_XML = ('GazeboRosApiPlugin SpawnModel Failure: input model_xml not SDF or URDF, '
                 'or cannot be converted to Gazebo compatible format.')


def model_xml_kind(xml):
    """'urdf', 'sdf' or None, from the root element as gazebo_ros's isURDF/isSDF judge it."""
    try:
        root = ET.fromstring(xml.strip())
    except (ET.ParseError, ValueError):
        return None
    if root.tag == 'robot':
        return 'urdf'
    if root.tag in ('sdf', 'gazebo'):
        return 'sdf'
    return None


def sdf_spawn_obstacle(xml):
    """Why flatsim cannot spawn an SDF, or None when it holds a <model> or includes one on the model path."""
    root = ET.fromstring(xml.strip())
    if root.find('model') is not None:
        return None
    uris = [uri.text.strip() for uri in root.iterfind('world/include/uri') if uri.text]
    missing = [uri for uri in uris if find_model(model_name_from_uri(uri)) is None]
    if missing:
        return ('flatsim has no model database to resolve %s, and no folder of that name is on the '
                'model path (%s); pass the model\'s own SDF (spawn_model -sdf -file model.sdf)'
                % (', '.join(missing), ':'.join(model_path())))
    if uris:
        return None
    if root.find('light') is not None:
        return 'flatsim simulates no lights'
    return 'the SDF holds no <model>'


def vector3(values):
    return Vector3(*[float(v) for v in values])


def twist3_msg(linear, angular):
    return Twist(linear=vector3(linear), angular=vector3(angular))


class GazeboApi:
    """The services and topics of gazebo_ros_api_plugin, on flatsim's node."""

    def __init__(self, node, world=None):
        self.node = node
        self.sim = node.sim
        self.lock = node.lock
        self.gravity = tuple(world.gravity) if world is not None else (0.0, 0.0, -9.8)
        self.ode = dict(ODE_DEFAULTS)
        self.get_model_state_counts = {}
        rate = float(rospy.get_param('~model_states_rate', 50.0))
        self.states_period = 1.0 / rate if rate > 0 else 0.0
        self.next_states = 0.0
        def name(relative):
            return NAMESPACE + relative
        self.model_states_pub = rospy.Publisher(name('model_states'), ModelStates, queue_size=10)
        self.link_states_pub = rospy.Publisher(name('link_states'), LinkStates, queue_size=10)
        self.moves_pub = rospy.Publisher(MOVES_TOPIC, String, queue_size=100)
        self.subscribers = [
            rospy.Subscriber(name('set_model_state'), ModelState, self.on_model_state_topic,
                             queue_size=10),
            rospy.Subscriber(name('set_link_state'), LinkState, self.on_link_state_topic,
                             queue_size=10),
        ]
        handlers = [
            ('get_model_state', GetModelState, self.get_model_state),
            ('set_model_state', SetModelState,
             self.recording('set_model_state', self.set_model_state,
                            lambda req: req.model_state.model_name)),
            ('get_link_state', GetLinkState, self.get_link_state),
            ('set_link_state', SetLinkState,
             self.recording('set_link_state', self.set_link_state,
                            lambda req: req.link_state.link_name)),
            ('get_world_properties', GetWorldProperties, self.get_world_properties),
            ('get_model_properties', GetModelProperties, self.get_model_properties),
            ('spawn_urdf_model', SpawnModel, self.spawn_urdf_model),
            ('spawn_sdf_model', SpawnModel, self.spawn_sdf_model),
            ('delete_model', DeleteModel, self.delete_model),
            ('pause_physics', Empty, self.pause_physics),
            ('unpause_physics', Empty, self.unpause_physics),
            ('reset_simulation', Empty, self.reset_simulation),
            ('reset_world', Empty, self.reset_world),
            ('get_physics_properties', GetPhysicsProperties, self.get_physics_properties),
            ('set_physics_properties', SetPhysicsProperties, self.set_physics_properties),
            ('apply_body_wrench', ApplyBodyWrench,
             self.recording('apply_body_wrench', self.apply_body_wrench, lambda req: req.body_name)),
            ('clear_body_wrenches', BodyRequest, self.clear_body_wrenches),
            ('set_model_configuration', SetModelConfiguration, self.set_model_configuration),
        ]
        self.services = [rospy.Service(name(service), kind, handler)
                         for service, kind, handler in handlers]

    # -- who moves models ----------------------------------------------------
    def recording(self, service, handler, target):
        """handler, each successful call of it said on ~model_moves."""
        def handle(req):
            response = handler(req)
            if response.success:
                self.moved(rospy.resolve_name(NAMESPACE + service), target(req), req)
            return response
        return handle

    def moved(self, through, target, message):
        """Say on ~model_moves that the caller whose message this is moved target through."""
        header = getattr(message, '_connection_header', None) or {}
        self.moves_pub.publish(String(json.dumps({
            'time': self.sim.time, 'by': header.get('callerid', ''), 'through': through,
            'target': target})))

    # -- topics ------------------------------------------------------------
    def publish_states(self, now):
        """Called after each step under the node's lock."""
        if not self.states_period or now + 1e-9 < self.next_states:
            return
        self.next_states = now + self.states_period
        if self.model_states_pub.get_num_connections():
            self.model_states_pub.publish(self.model_states())
        if self.link_states_pub.get_num_connections():
            self.link_states_pub.publish(self.link_states())

    def model_states(self):
        msg = ModelStates()
        for name in self.sim.models:
            entity = entities.Entity(name)
            msg.name.append(name)
            msg.pose.append(rosmsg.pose_msg(entities.entity_pose(self.sim, entity)))
            msg.twist.append(twist3_msg(*entities.entity_twist(self.sim, entity)))
        return msg

    def link_states(self):
        msg = LinkStates()
        for name in self.sim.models:
            for link, offset in entities.model_links(self.sim, name):
                entity = entities.Entity(name, link, offset)
                msg.name.append(entity.scoped_name)
                msg.pose.append(rosmsg.pose_msg(entities.entity_pose(self.sim, entity)))
                msg.twist.append(twist3_msg(*entities.entity_twist(self.sim, entity)))
        return msg

    def on_model_state_topic(self, msg):
        response = self.set_model_state(SetModelState._request_class(model_state=msg))
        if response.success:
            self.moved(rospy.resolve_name(NAMESPACE + 'set_model_state'), msg.model_name, msg)
        else:
            rospy.logerr_throttle(5.0, 'flatsim: gazebo/set_model_state topic: %s'
                                  % response.status_message)

    def on_link_state_topic(self, msg):
        response = self.set_link_state(SetLinkState._request_class(link_state=msg))
        if response.success:
            self.moved(rospy.resolve_name(NAMESPACE + 'set_link_state'), msg.link_name, msg)
        else:
            rospy.logerr_throttle(5.0, 'flatsim: gazebo/set_link_state topic: %s'
                                  % response.status_message)

    # -- model and link state -----------------------------------------------
    def _frame(self, name):
        """(entity, its world pose and twist) for a reference frame; None for the world frame.

        Raises KeyError for a name that is neither an entity nor a world frame.
        """
        entity = entities.find_entity(self.sim, name)
        if entity is None:
            if name in WORLD_FRAMES:
                return None
            raise KeyError(name)
        return (entity, entities.entity_pose(self.sim, entity),
                entities.entity_twist(self.sim, entity))

    def get_model_state(self, req):
        with self.lock:
            if req.model_name not in self.sim.models:
                rospy.logerr('GetModelState: model [%s] does not exist', logged_name(req.model_name))
                return GetModelStateResponse(success=False,
                                             status_message='GetModelState: model does not exist')
            count = self.get_model_state_counts.get(req.model_name, 0) + 1
            self.get_model_state_counts[req.model_name] = count
            response = GetModelStateResponse()
            response.header.seq = count
            response.header.stamp = rospy.Time.now()
            response.header.frame_id = req.relative_entity_name
            try:
                pose, linear, angular = self._state_in(entities.Entity(req.model_name),
                                                       req.relative_entity_name)
            except KeyError:
                return GetModelStateResponse(
                    success=False,
                    status_message='GetModelState: reference relative_entity_name not found, '
                                   'did you forget to scope the body by model name?')
        response.pose = rosmsg.pose_msg(pose)
        response.twist = twist3_msg(linear, angular)
        response.success = True
        response.status_message = 'GetModelState: got properties'
        return response

    def _state_in(self, entity, frame_name):
        pose = entities.entity_pose(self.sim, entity)
        linear, angular = entities.entity_twist(self.sim, entity)
        frame = self._frame(frame_name)
        if frame is None:
            return pose, linear, angular
        _, frame_pose, (frame_linear, frame_angular) = frame
        return (entities.relative_pose(pose, frame_pose),
                entities.rotate_reverse(frame_pose, [a - b for a, b in zip(linear, frame_linear)]),
                entities.rotate_reverse(frame_pose, [a - b for a, b in zip(angular, frame_angular)]))

    def set_model_state(self, req):
        state = req.model_state
        try:
            target = rosmsg.requested_pose(state.pose)
        except FlatsimError as error:
            return SetModelStateResponse(False, 'SetModelState: %s' % error)
        linear = (state.twist.linear.x, state.twist.linear.y, state.twist.linear.z)
        angular = (state.twist.angular.x, state.twist.angular.y, state.twist.angular.z)
        with self.lock:
            if state.model_name not in self.sim.models:
                rospy.logerr('Updating ModelState: model [%s] does not exist', logged_name(state.model_name))
                return SetModelStateResponse(False, 'SetModelState: model does not exist')
            try:
                frame = self._frame(state.reference_frame)
            except KeyError:
                rospy.logerr('Updating ModelState: for model[%s], specified reference frame '
                             'entity [%s] does not exist', logged_name(state.model_name),
                             logged_name(state.reference_frame))
                return SetModelStateResponse(
                    False, 'SetModelState: specified reference frame entity does not exist')
            if frame is not None:
                frame_pose = frame[1]
                target = frame_pose * target
                linear = entities.rotate(frame_pose, linear)
                angular = entities.rotate(frame_pose, angular)
            try:
                self.sim.set_model_state(state.model_name, target, (linear[0], linear[1], angular[2]))
            except FlatsimError as error:
                return SetModelStateResponse(False, 'SetModelState: %s' % error)
        return SetModelStateResponse(True, 'SetModelState: set model state done')

    def get_link_state(self, req):
        with self.lock:
            body = entities.find_entity(self.sim, req.link_name)
            if body is None or not body.link:
                return GetLinkStateResponse(
                    success=False, status_message='GetLinkState: link not found, did you forget '
                                                  'to scope the link by model name?')
            try:
                pose, linear, angular = self._state_in(body, req.reference_frame)
            except KeyError:
                return GetLinkStateResponse(
                    success=False, status_message='GetLinkState: reference reference_frame not '
                                                  'found, did you forget to scope the link by '
                                                  'model name?')
        state = LinkState(link_name=req.link_name, pose=rosmsg.pose_msg(pose),
                          twist=twist3_msg(linear, angular), reference_frame=req.reference_frame)
        return GetLinkStateResponse(link_state=state, success=True,
                                    status_message='GetLinkState: got state')

    def set_link_state(self, req):
        state = req.link_state
        try:
            target = rosmsg.requested_pose(state.pose)
        except FlatsimError as error:
            return SetLinkStateResponse(False, 'SetLinkState: %s' % error)
        linear = [state.twist.linear.x, state.twist.linear.y, state.twist.linear.z]
        angular = [state.twist.angular.x, state.twist.angular.y, state.twist.angular.z]
        with self.lock:
            body = entities.find_entity(self.sim, state.link_name)
            if body is None or not body.link:
                rospy.logerr('Updating LinkState: link [%s] does not exist', logged_name(state.link_name))
                return SetLinkStateResponse(False, 'SetLinkState: link does not exist')
            frame = entities.find_entity(self.sim, state.reference_frame)
            if frame is not None and frame.link:
                # As gazebo_ros: the pose is put in the frame, the frame's velocity subtracted.
                target = entities.entity_pose(self.sim, frame) * target
                frame_linear, frame_angular = entities.entity_twist(self.sim, frame)
                linear = [a - b for a, b in zip(linear, frame_linear)]
                angular = [a - b for a, b in zip(angular, frame_angular)]
            elif state.reference_frame not in WORLD_FRAMES:
                rospy.logerr('Updating LinkState: reference_frame is not a valid entity name')
                return SetLinkStateResponse(False, 'SetLinkState: failed')
            # One rigid body per model: the model moves so that the link lands on the target.
            model_pose = entities.without_offset(target, body.offset)
            try:
                self.sim.set_model_state(body.model, model_pose, (linear[0], linear[1], angular[2]))
            except FlatsimError as error:
                return SetLinkStateResponse(False, 'SetLinkState: %s' % error)
        return SetLinkStateResponse(True, 'SetLinkState: success')

    # -- world and model properties -----------------------------------------
    def get_world_properties(self, _req):
        with self.lock:
            return GetWorldPropertiesResponse(
                sim_time=self.sim.time, model_names=list(self.sim.models), rendering_enabled=True,
                success=True, status_message='GetWorldProperties: got properties')

    def get_model_properties(self, req):
        with self.lock:
            model = self.sim.models.get(req.model_name)
            if model is None:
                rospy.logerr('GetModelProperties: model [%s] does not exist', logged_name(req.model_name))
                return GetModelPropertiesResponse(
                    success=False, status_message='GetModelProperties: model does not exist')
            response = GetModelPropertiesResponse(success=True,
                                                  status_message='GetModelProperties: got properties')
            response.body_names = [link for link, _ in entities.model_links(self.sim, req.model_name)]
            spec = getattr(model, 'spec', None)
            if spec is not None:
                response.geom_names = _robot_collision_names(spec, response.body_names)
                response.joint_names = [joint.name for joint in spec.joints.values()
                                        if joint.kind != 'fixed']
            elif model.source is not None:
                response.geom_names = [geom.name for geom in model.source.collisions]
                response.is_static = bool(model.source.static)
            return response

    # -- spawning and deleting ------------------------------------------------
    def spawn_urdf_model(self, req):
        if model_xml_kind(req.model_xml) != 'urdf':
            rospy.logerr('SpawnModel: Failure - entity format is invalid.')
            # gazebo_ros answers this one with a failed call, not a response.
            raise rospy.ServiceException('SpawnModel: Failure - entity format is invalid.')
        return self.spawn_sdf_model(req)

    def spawn_sdf_model(self, req):
        """Both spawn services end here: gazebo_ros's SDF service takes URDF too."""
        kind = model_xml_kind(req.model_xml)
        if kind is None:
            rospy.logerr('GazeboRosApiPlugin SpawnModel Failure: input xml format not recognized')
            return SpawnModelResponse(False, SPAWN_NOT_XML)
        with self.lock:
            try:
                frame = self._frame(req.reference_frame)
            except KeyError:
                return SpawnModelResponse(False, 'SpawnModel: reference reference_frame not found, '
                                                 'did you forget to scope the link by model name?')
            try:
                pose = rosmsg.requested_pose(req.initial_pose)
            except FlatsimError as error:
                return SpawnModelResponse(False, 'SpawnModel: Failure - initial_pose %s' % error)
            if frame is not None:
                pose = frame[1] * pose
            if self._name_taken(req.model_name, kind):
                rospy.logerr('SpawnModel: Failure - model name %s already exist.', logged_name(req.model_name))
                return SpawnModelResponse(False, 'SpawnModel: Failure - entity already exists.')
        try:
            # Reading the model takes long for big files: the world keeps stepping meanwhile.
            loaded, offset = self._load(kind, req)
        except FlatsimError as error:
            rospy.logerr('flatsim: cannot spawn %s: %s', logged_name(req.model_name), error)
            return SpawnModelResponse(False, 'SpawnModel: Failure - %s' % error)
        return self._place(req.model_name, kind, loaded, pose if offset is None else pose * offset)

    def _place(self, name, kind, loaded, pose, origin=None):
        """The last part of every spawn: put a loaded model into the world under its name.

        origin (a ModelOrigin) says where it came from; by default a spawned model.
        """
        try:
            with self.lock:
                if self._name_taken(name, kind):
                    return SpawnModelResponse(False, 'SpawnModel: Failure - entity already exists.')
                self.node.add_model(name, loaded, pose, origin)
        except FlatsimError as error:
            rospy.logerr('flatsim: cannot spawn %s: %s', logged_name(name), error)
            return SpawnModelResponse(False, 'SpawnModel: Failure - %s' % error)
        self.node.publish_ball_names()
        return SpawnModelResponse(True, 'SpawnModel: Successfully spawned entity')

    def spawn_copy(self, source, name, pose):
        """A copy of a model in the world under a new name at pose (world frame), placed as
        spawn_sdf_model places a model it has read: Gazebo's window pastes models this way."""
        with self.lock:
            model = self.sim.models.get(source)
            if model is None:
                return SpawnModelResponse(False, 'SpawnModel: Failure - there is no model %s '
                                                 'to copy' % source)
            spec = getattr(model, 'spec', None)
            original = spec if spec is not None else model.source
        if original is None:
            return SpawnModelResponse(False, 'SpawnModel: Failure - %s cannot be copied' % source)
        loaded = copy.deepcopy(original)
        if spec is None:
            loaded.name = name
            # The copy's own pose is where it is pasted.
            loaded.pose = Pose()
        return self._place(name, 'urdf' if spec is not None else 'sdf', loaded, pose)

    def insert_model(self, name, loaded, pose, origin):
        """A model read for the Insert tab (flatsim.studio.world.model_to_insert) placed at pose
        (world frame), as spawn_sdf_model places one: Gazebo's window inserts models this way."""
        kind = 'urdf' if loaded.robot is not None else 'sdf'
        return self._place(name, kind, loaded.robot if loaded.robot is not None else loaded, pose, origin)

    def restore_model(self, name, robot, loaded, pose, origin):
        """A model the studio's Undo or Redo puts back (robot: a RobotSpec, else a world model
        whose own pose is cleared), placed at pose (world frame) as spawn places one, with the
        origin it had, so that Save World As writes it as before."""
        return self._place(name, 'urdf' if robot else 'sdf', loaded, pose, origin)

    def _name_taken(self, name, kind):
        model = self.sim.models.get(name)
        # A robot spawned under the name of a saved copy in the world takes its place.
        return model is not None and not (kind == 'urdf' and self.sim.robot_may_replace(name))

    def _load(self, kind, req):
        """(robot spec or world model, pose of the model in the requested frame or None)."""
        if not req.model_name:
            raise FlatsimError('the model needs a name')
        if kind == 'urdf':
            spec = load_robot(req.model_xml, name=req.model_name,
                              robot_namespace=req.robot_namespace)
            for skipped in spec.skipped:
                rospy.logwarn('flatsim: robot %s: %s %s', logged_name(req.model_name), skipped.verb,
                              skipped)
            root_height(spec)    # worked out now, outside the lock
            return spec, None
        obstacle = sdf_spawn_obstacle(req.model_xml)
        if obstacle:
            raise FlatsimError(obstacle)
        model, skipped = read_spawned_model(req.model_xml, req.model_name,
                                            robot_namespace=req.robot_namespace)
        for item in skipped:
            rospy.logwarn('flatsim: model %s: %s %s', logged_name(req.model_name), item.verb, item)
        if model.robot is not None:
            # A robot in SDF (sensors, plugins) runs as one spawned from URDF; gazebo_ros puts
            # the model's own <pose> in the frame of the requested one.
            return model.robot, model.pose
        return model, None

    def delete_model(self, req):
        with self.lock:
            if req.model_name not in self.sim.models:
                rospy.logerr('DeleteModel: model [%s] does not exist', logged_name(req.model_name))
                return DeleteModelResponse(False, 'DeleteModel: model does not exist')
            self.node.remove_model(req.model_name)
        self.node.publish_ball_names()
        return DeleteModelResponse(True, 'DeleteModel: successfully deleted model')

    # -- time and physics -----------------------------------------------------
    def pause_physics(self, _req):
        self.node.pause()
        return EmptyResponse()

    def unpause_physics(self, _req):
        with self.lock:
            self.sim.paused = False
        return EmptyResponse()

    def reset_world(self, _req):
        self.node.reset_world()
        return EmptyResponse()

    def reset_simulation(self, _req):
        self.node.reset_time()
        return EmptyResponse()

    def get_physics_properties(self, _req):
        with self.lock:
            step = self.sim.step_size
            factor = self.node.real_time_factor
            return GetPhysicsPropertiesResponse(
                time_step=step, pause=self.sim.paused,
                max_update_rate=factor / step if factor > 0 else 0.0,
                gravity=vector3(self.gravity), ode_config=ODEPhysics(**self.ode),
                success=True, status_message='GetPhysicsProperties: got properties')

    def set_physics_properties(self, req):
        """The step and the real-time factor (max_update_rate x time_step) take effect;
        gravity and the ODE settings are kept and reported back."""
        values = (req.time_step, req.max_update_rate, req.gravity.x, req.gravity.y, req.gravity.z)
        if not all(math.isfinite(v) for v in values) or req.max_update_rate < 0:
            return SetPhysicsPropertiesResponse(
                False, 'SetPhysicsProperties: time_step, max_update_rate and gravity must be '
                       'finite, max_update_rate not negative')
        try:
            check_step_size(req.time_step)
            factor = settings.real_time_factor(req.max_update_rate * req.time_step,
                                               name='the real-time factor (max_update_rate x time_step)')
        except FlatsimError as error:
            return SetPhysicsPropertiesResponse(False, 'SetPhysicsProperties: %s' % error)
        with self.lock:
            self.sim.set_step_size(req.time_step)
            self.node.set_real_time_factor(factor)
            self.gravity = (req.gravity.x, req.gravity.y, req.gravity.z)
            self.ode = {key: getattr(req.ode_config, key) for key in ODE_DEFAULTS}
        rospy.loginfo('flatsim: physics step %g s, real-time factor %s', req.time_step,
                      req.max_update_rate * req.time_step or 'as fast as possible')
        return SetPhysicsPropertiesResponse(True, 'physics engine updated')

    # -- wrenches and joints ------------------------------------------------------
    def apply_body_wrench(self, req):
        force = (req.wrench.force.x, req.wrench.force.y, req.wrench.force.z)
        torque = [req.wrench.torque.x, req.wrench.torque.y, req.wrench.torque.z]
        point = (req.reference_point.x, req.reference_point.y, req.reference_point.z)
        if not all(math.isfinite(v) for v in force + tuple(torque) + point):
            return ApplyBodyWrenchResponse(False, 'ApplyBodyWrench: wrench and reference_point '
                                                  'must be finite numbers')
        # A wrench given at a point is the same wrench at the origin plus a torque.
        torque = [t + c for t, c in zip(torque, _cross(point, force))]
        if not all(math.isfinite(v) for v in torque):
            return ApplyBodyWrenchResponse(False, _WRENCH_OVERFLOWS)
        with self.lock:
            body = entities.find_entity(self.sim, req.body_name)
            if body is None or not body.link:
                rospy.logerr('ApplyBodyWrench: body [%s] does not exist', logged_name(req.body_name))
                return ApplyBodyWrenchResponse(False, 'ApplyBodyWrench: body does not exist')
            held = self.sim.models[body.model].held
            if held:
                # Gazebo would push it; flatsim cannot, and says so rather than take the wrench.
                return ApplyBodyWrenchResponse(False, 'ApplyBodyWrench: flatsim holds model %s '
                                                      'still: %s' % (logged_name(body.model), held))
            frame = entities.find_entity(self.sim, req.reference_frame)
            if frame is not None:
                # gazebo_ros turns the wrench by the frame's pose seen from the body.
                to_frame = entities.relative_pose(entities.entity_pose(self.sim, frame),
                                                  entities.entity_pose(self.sim, body))
                force = entities.rotate(to_frame, force)
                torque = [t + c for t, c in zip(entities.rotate(to_frame, torque),
                                                _cross((to_frame.x, to_frame.y, to_frame.z), force))]
            elif req.reference_frame not in WORLD_FRAMES:
                rospy.logerr('ApplyBodyWrench: reference_frame is not a valid entity name')
                return ApplyBodyWrenchResponse(False, 'ApplyBodyWrench: reference_frame not found')
            now = self.sim.time
            try:
                self.sim.wrenches.add(WrenchJob(
                    body=body.scoped_name, model=body.model, offset=(body.offset.x, body.offset.y),
                    force=tuple(force), torque=tuple(torque),
                    start=max(req.start_time.to_sec(), now), duration=req.duration.to_sec()))
            except FlatsimError:
                # Turned into the reference frame, the wrench overflowed.
                return ApplyBodyWrenchResponse(False, _WRENCH_OVERFLOWS)
        return ApplyBodyWrenchResponse(True, '')

    def clear_body_wrenches(self, req):
        with self.lock:
            self.sim.wrenches.clear(req.body_name)
        return BodyRequestResponse()

    def set_model_configuration(self, req):
        with self.lock:
            if req.model_name not in self.sim.models:
                rospy.logerr('SetModelConfiguration: model [%s] does not exist', logged_name(req.model_name))
                return SetModelConfigurationResponse(
                    False, 'SetModelConfiguration: model does not exist')
            if len(req.joint_names) != len(req.joint_positions):
                return SetModelConfigurationResponse(
                    False, 'SetModelConfiguration: joint name and position list have different '
                           'lengths')
            try:
                unknown = entities.set_joint_positions(
                    self.sim, req.model_name, dict(zip(req.joint_names, req.joint_positions)))
            except FlatsimError as error:
                return SetModelConfigurationResponse(False, 'SetModelConfiguration: %s' % error)
        if unknown:
            rospy.logwarn('SetModelConfiguration: %s has no movable joint named %s; left alone',
                          logged_name(req.model_name), logged_name(', '.join(unknown)))
        return SetModelConfigurationResponse(True, 'SetModelConfiguration: success')


def _cross(a, b):
    # In Python floats, which overflow to inf quietly, where numpy's would warn on stderr.
    (ax, ay, az), (bx, by, bz) = [float(v) for v in a], [float(v) for v in b]
    return (ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx)


def _robot_collision_names(spec, bodies):
    """Collision names as Gazebo's URDF import makes them, lumped ones under their body."""
    names = []
    parent = {joint.child: joint for joint in spec.joints.values()}
    for link_name, link in spec.links.items():
        body = link_name
        while body not in bodies and body in parent:
            body = parent[body].parent
        stem = link_name if body == link_name else '%s_fixed_joint_lump__%s' % (body, link_name)
        for index in range(len(link.collisions)):
            names.append('%s_collision' % stem + ('_%d' % index if index else ''))
    return names
